#include "camera.hpp"

#include <algorithm>

namespace terracut::viewer {

Mat4 inverse(const Mat4& a) {
  const auto& m = a.m;
  std::array<float, 16> inv{};
  inv[0] = m[5] * m[10] * m[15] - m[5] * m[11] * m[14] - m[9] * m[6] * m[15] +
           m[9] * m[7] * m[14] + m[13] * m[6] * m[11] - m[13] * m[7] * m[10];
  inv[4] = -m[4] * m[10] * m[15] + m[4] * m[11] * m[14] + m[8] * m[6] * m[15] -
           m[8] * m[7] * m[14] - m[12] * m[6] * m[11] + m[12] * m[7] * m[10];
  inv[8] = m[4] * m[9] * m[15] - m[4] * m[11] * m[13] - m[8] * m[5] * m[15] +
           m[8] * m[7] * m[13] + m[12] * m[5] * m[11] - m[12] * m[7] * m[9];
  inv[12] = -m[4] * m[9] * m[14] + m[4] * m[10] * m[13] + m[8] * m[5] * m[14] -
            m[8] * m[6] * m[13] - m[12] * m[5] * m[10] + m[12] * m[6] * m[9];
  inv[1] = -m[1] * m[10] * m[15] + m[1] * m[11] * m[14] + m[9] * m[2] * m[15] -
           m[9] * m[3] * m[14] - m[13] * m[2] * m[11] + m[13] * m[3] * m[10];
  inv[5] = m[0] * m[10] * m[15] - m[0] * m[11] * m[14] - m[8] * m[2] * m[15] +
           m[8] * m[3] * m[14] + m[12] * m[2] * m[11] - m[12] * m[3] * m[10];
  inv[9] = -m[0] * m[9] * m[15] + m[0] * m[11] * m[13] + m[8] * m[1] * m[15] -
           m[8] * m[3] * m[13] - m[12] * m[1] * m[11] + m[12] * m[3] * m[9];
  inv[13] = m[0] * m[9] * m[14] - m[0] * m[10] * m[13] - m[8] * m[1] * m[14] +
            m[8] * m[2] * m[13] + m[12] * m[1] * m[10] - m[12] * m[2] * m[9];
  inv[2] = m[1] * m[6] * m[15] - m[1] * m[7] * m[14] - m[5] * m[2] * m[15] +
           m[5] * m[3] * m[14] + m[13] * m[2] * m[7] - m[13] * m[3] * m[6];
  inv[6] = -m[0] * m[6] * m[15] + m[0] * m[7] * m[14] + m[4] * m[2] * m[15] -
           m[4] * m[3] * m[14] - m[12] * m[2] * m[7] + m[12] * m[3] * m[6];
  inv[10] = m[0] * m[5] * m[15] - m[0] * m[7] * m[13] - m[4] * m[1] * m[15] +
            m[4] * m[3] * m[13] + m[12] * m[1] * m[7] - m[12] * m[3] * m[5];
  inv[14] = -m[0] * m[5] * m[14] + m[0] * m[6] * m[13] + m[4] * m[1] * m[14] -
            m[4] * m[2] * m[13] - m[12] * m[1] * m[6] + m[12] * m[2] * m[5];
  inv[3] = -m[1] * m[6] * m[11] + m[1] * m[7] * m[10] + m[5] * m[2] * m[11] -
           m[5] * m[3] * m[10] - m[9] * m[2] * m[7] + m[9] * m[3] * m[6];
  inv[7] = m[0] * m[6] * m[11] - m[0] * m[7] * m[10] - m[4] * m[2] * m[11] +
           m[4] * m[3] * m[10] + m[8] * m[2] * m[7] - m[8] * m[3] * m[6];
  inv[11] = -m[0] * m[5] * m[11] + m[0] * m[7] * m[9] + m[4] * m[1] * m[11] -
            m[4] * m[3] * m[9] - m[8] * m[1] * m[7] + m[8] * m[3] * m[5];
  inv[15] = m[0] * m[5] * m[10] - m[0] * m[6] * m[9] - m[4] * m[1] * m[10] +
            m[4] * m[2] * m[9] + m[8] * m[1] * m[6] - m[8] * m[2] * m[5];
  float det = m[0] * inv[0] + m[1] * inv[4] + m[2] * inv[8] + m[3] * inv[12];
  Mat4 r;
  if (det == 0.0f || !std::isfinite(det)) return r;
  for (int i = 0; i < 16; ++i) r.m[std::size_t(i)] = inv[std::size_t(i)] / det;
  return r;
}

void Camera::frame_terrain(const GridSpec& spec, double max_height_m) {
  float sx = float(spec.size_x_m), sz = float(spec.size_z_m);
  float h = float(std::max(max_height_m, 1e-3));
  target = {float(spec.origin_m.x) + 0.5f * sx, float(spec.origin_m.y) + 0.25f * h,
            float(spec.origin_m.z) + 0.5f * sz};
  scene_radius_m = 0.5f * std::sqrt(sx * sx + sz * sz + h * h);
  distance_m = 3.0f * scene_radius_m;
  top_x0 = float(spec.origin_m.x);
  top_z0 = float(spec.origin_m.z);
  top_x1 = top_x0 + sx;
  top_z1 = top_z0 + sz;
  top_y_max = float(spec.origin_m.y) + 4.0f * h + scene_radius_m;
}

Vec3f Camera::eye() const {
  if (mode == CameraMode::kTop) return {0.5f * (top_x0 + top_x1), top_y_max, 0.5f * (top_z0 + top_z1)};
  float cp = std::cos(pitch_rad);
  Vec3f offset{cp * std::sin(yaw_rad), std::sin(pitch_rad), cp * std::cos(yaw_rad)};
  return target + offset * distance_m;
}

Mat4 Camera::view() const {
  if (mode == CameraMode::kTop) {
    // Looking down -Y; screen right = +X, screen up = -Z.
    Vec3f e = eye();
    return look_at(e, e - Vec3f{0.0f, 1.0f, 0.0f}, {0.0f, 0.0f, -1.0f});
  }
  return look_at(eye(), target, {0.0f, 1.0f, 0.0f});
}

Mat4 Camera::projection(float aspect) const {
  if (mode == CameraMode::kTop) {
    // Fit the extent into the inner (1 - 2 margin) part of the viewport, aspect kept.
    float w = top_x1 - top_x0, d = top_z1 - top_z0;
    float inner = 1.0f - 2.0f * kTopMarginFraction;
    float half_w = 0.5f * w / inner, half_h = 0.5f * d / inner;
    if (half_w / half_h < aspect) {
      half_w = half_h * aspect;
    } else {
      half_h = half_w / aspect;
    }
    return orthographic(-half_w, half_w, -half_h, half_h, 0.0f, 2.0f * top_y_max + 100.0f);
  }
  float near_m = std::max(distance_m - 3.0f * scene_radius_m, 0.01f * scene_radius_m);
  float far_m = distance_m + 6.0f * scene_radius_m;
  return perspective(fov_y_rad, aspect, near_m, far_m);
}

Ray Camera::ray(float x01, float y01, float aspect) const {
  Mat4 inv = inverse(projection(aspect) * view());
  float nx = 2.0f * x01 - 1.0f, ny = 1.0f - 2.0f * y01;
  Vec3f a = transform_point(inv, {nx, ny, -1.0f});
  Vec3f b = transform_point(inv, {nx, ny, 1.0f});
  return {a, normalize(b - a)};
}

}  // namespace terracut::viewer
