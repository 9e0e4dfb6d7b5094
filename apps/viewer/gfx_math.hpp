// Small single-precision matrix helpers for the viewer's OpenGL drawing.
// Matrices are column-major 4x4 (OpenGL's layout): element (row i, column j)
// is m[j * 4 + i]. World frame: right-handed, Y up (as the core).
#pragma once

#include <array>
#include <cmath>

#include "terracut/core/math.hpp"

namespace terracut::viewer {

struct Vec3f {
  float x = 0.0f;
  float y = 0.0f;
  float z = 0.0f;
};

inline Vec3f to_f(Vec3 v) { return {float(v.x), float(v.y), float(v.z)}; }
inline Vec3f operator+(Vec3f a, Vec3f b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline Vec3f operator-(Vec3f a, Vec3f b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Vec3f operator*(Vec3f a, float s) { return {a.x * s, a.y * s, a.z * s}; }
inline float dot(Vec3f a, Vec3f b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3f cross(Vec3f a, Vec3f b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline float length(Vec3f a) { return std::sqrt(dot(a, a)); }
inline Vec3f normalize(Vec3f a) {
  float l = length(a);
  return l > 0.0f ? a * (1.0f / l) : Vec3f{0.0f, 1.0f, 0.0f};
}

/// A column-major 4x4 matrix.
struct Mat4 {
  std::array<float, 16> m{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  float& at(int row, int col) { return m[std::size_t(col * 4 + row)]; }
  float at(int row, int col) const { return m[std::size_t(col * 4 + row)]; }
  const float* data() const { return m.data(); }
};

inline Mat4 operator*(const Mat4& a, const Mat4& b) {
  Mat4 r;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      float s = 0.0f;
      for (int k = 0; k < 4; ++k) s += a.at(i, k) * b.at(k, j);
      r.at(i, j) = s;
    }
  return r;
}

/// Transforms a point (w = 1) and divides by w.
inline Vec3f transform_point(const Mat4& a, Vec3f p) {
  float x = a.at(0, 0) * p.x + a.at(0, 1) * p.y + a.at(0, 2) * p.z + a.at(0, 3);
  float y = a.at(1, 0) * p.x + a.at(1, 1) * p.y + a.at(1, 2) * p.z + a.at(1, 3);
  float z = a.at(2, 0) * p.x + a.at(2, 1) * p.y + a.at(2, 2) * p.z + a.at(2, 3);
  float w = a.at(3, 0) * p.x + a.at(3, 1) * p.y + a.at(3, 2) * p.z + a.at(3, 3);
  return {x / w, y / w, z / w};
}

inline Mat4 translation(Vec3f t) {
  Mat4 r;
  r.at(0, 3) = t.x;
  r.at(1, 3) = t.y;
  r.at(2, 3) = t.z;
  return r;
}

inline Mat4 scaling(Vec3f s) {
  Mat4 r;
  r.at(0, 0) = s.x;
  r.at(1, 1) = s.y;
  r.at(2, 2) = s.z;
  return r;
}

/// Rotation matrix of a unit quaternion.
inline Mat4 rotation(Quat q) {
  Mat4 r;
  double w = q.w, x = q.x, y = q.y, z = q.z;
  r.at(0, 0) = float(1 - 2 * (y * y + z * z));
  r.at(0, 1) = float(2 * (x * y - w * z));
  r.at(0, 2) = float(2 * (x * z + w * y));
  r.at(1, 0) = float(2 * (x * y + w * z));
  r.at(1, 1) = float(1 - 2 * (x * x + z * z));
  r.at(1, 2) = float(2 * (y * z - w * x));
  r.at(2, 0) = float(2 * (x * z - w * y));
  r.at(2, 1) = float(2 * (y * z + w * x));
  r.at(2, 2) = float(1 - 2 * (x * x + y * y));
  return r;
}

/// A matrix whose columns 0..2 are the given axes (a rotation when they are orthonormal).
inline Mat4 basis(Vec3f x_axis, Vec3f y_axis, Vec3f z_axis) {
  Mat4 r;
  r.at(0, 0) = x_axis.x;
  r.at(1, 0) = x_axis.y;
  r.at(2, 0) = x_axis.z;
  r.at(0, 1) = y_axis.x;
  r.at(1, 1) = y_axis.y;
  r.at(2, 1) = y_axis.z;
  r.at(0, 2) = z_axis.x;
  r.at(1, 2) = z_axis.y;
  r.at(2, 2) = z_axis.z;
  return r;
}

/// Right-handed view matrix looking from eye at target.
inline Mat4 look_at(Vec3f eye, Vec3f target, Vec3f up) {
  Vec3f f = normalize(target - eye);
  Vec3f s = normalize(cross(f, up));
  Vec3f u = cross(s, f);
  Mat4 r;
  r.at(0, 0) = s.x;
  r.at(0, 1) = s.y;
  r.at(0, 2) = s.z;
  r.at(1, 0) = u.x;
  r.at(1, 1) = u.y;
  r.at(1, 2) = u.z;
  r.at(2, 0) = -f.x;
  r.at(2, 1) = -f.y;
  r.at(2, 2) = -f.z;
  r.at(0, 3) = -dot(s, eye);
  r.at(1, 3) = -dot(u, eye);
  r.at(2, 3) = dot(f, eye);
  return r;
}

/// OpenGL perspective projection (depth to [-1, 1]); fov_y in radians.
inline Mat4 perspective(float fov_y_rad, float aspect, float near_m, float far_m) {
  float f = 1.0f / std::tan(fov_y_rad * 0.5f);
  Mat4 r;
  r.m.fill(0.0f);
  r.at(0, 0) = f / aspect;
  r.at(1, 1) = f;
  r.at(2, 2) = (far_m + near_m) / (near_m - far_m);
  r.at(2, 3) = 2.0f * far_m * near_m / (near_m - far_m);
  r.at(3, 2) = -1.0f;
  return r;
}

/// OpenGL orthographic projection of the view-space box [l, r] x [b, t] x [-n, -f].
inline Mat4 orthographic(float l, float r, float b, float t, float n, float f) {
  Mat4 m;
  m.at(0, 0) = 2.0f / (r - l);
  m.at(1, 1) = 2.0f / (t - b);
  m.at(2, 2) = -2.0f / (f - n);
  m.at(0, 3) = -(r + l) / (r - l);
  m.at(1, 3) = -(t + b) / (t - b);
  m.at(2, 3) = -(f + n) / (f - n);
  return m;
}

/// General 4x4 inverse (cofactors); returns the identity for a singular matrix.
Mat4 inverse(const Mat4& a);

}  // namespace terracut::viewer
