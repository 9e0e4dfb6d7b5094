#include "terracut/core/math.hpp"

#include <algorithm>
#include <numbers>

namespace terracut {

Quat normalized(Quat q) {
  double n = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
  if (!(n > 0.0) || !std::isfinite(n)) return Quat{};
  return {q.w / n, q.x / n, q.y / n, q.z / n};
}

Vec3 rotate(Quat q, Vec3 v) {
  // v' = v + 2 w (u x v) + 2 u x (u x v), with u the vector part of q.
  Vec3 u{q.x, q.y, q.z};
  Vec3 t = cross(u, v) * 2.0;
  return v + t * q.w + cross(u, t);
}

Quat quat_from_axis_angle(Vec3 axis, double angle_rad) {
  double n = length(axis);
  if (!(n > 0.0)) return Quat{};
  double s = std::sin(angle_rad / 2.0) / n;
  return {std::cos(angle_rad / 2.0), axis.x * s, axis.y * s, axis.z * s};
}

Quat quat_from_euler_deg(Vec3 euler_deg) {
  constexpr double kDeg = std::numbers::pi / 180.0;
  Quat qx = quat_from_axis_angle({1, 0, 0}, euler_deg.x * kDeg);
  Quat qy = quat_from_axis_angle({0, 1, 0}, euler_deg.y * kDeg);
  Quat qz = quat_from_axis_angle({0, 0, 1}, euler_deg.z * kDeg);
  // Extrinsic X, then Y, then Z: R = Rz * Ry * Rx.
  return normalized(qz * qy * qx);
}

Vec3 euler_deg_from_quat(Quat q) {
  constexpr double kRad = 180.0 / std::numbers::pi;
  q = normalized(q);
  // Rotation matrix entries of R = Rz * Ry * Rx.
  double r20 = 2.0 * (q.x * q.z - q.w * q.y);
  double r21 = 2.0 * (q.y * q.z + q.w * q.x);
  double r22 = 1.0 - 2.0 * (q.x * q.x + q.y * q.y);
  double r10 = 2.0 * (q.x * q.y + q.w * q.z);
  double r00 = 1.0 - 2.0 * (q.y * q.y + q.z * q.z);
  double ry = std::asin(std::clamp(-r20, -1.0, 1.0));
  double rx = std::atan2(r21, r22);
  double rz = std::atan2(r10, r00);
  return {rx * kRad, ry * kRad, rz * kRad};
}

Quat slerp(Quat a, Quat b, double t) {
  double d = a.w * b.w + a.x * b.x + a.y * b.y + a.z * b.z;
  // Take the shorter arc.
  if (d < 0.0) {
    b = {-b.w, -b.x, -b.y, -b.z};
    d = -d;
  }
  double wa, wb;
  if (d > 0.9995) {
    // Nearly parallel: linear interpolation is accurate and avoids 0/0.
    wa = 1.0 - t;
    wb = t;
  } else {
    double theta = std::acos(std::clamp(d, -1.0, 1.0));
    double s = std::sin(theta);
    wa = std::sin((1.0 - t) * theta) / s;
    wb = std::sin(t * theta) / s;
  }
  return normalized({a.w * wa + b.w * wb, a.x * wa + b.x * wb, a.y * wa + b.y * wb,
                     a.z * wa + b.z * wb});
}

double angle_between(Quat a, Quat b) {
  double d = std::abs(a.w * b.w + a.x * b.x + a.y * b.y + a.z * b.z);
  return 2.0 * std::acos(std::clamp(d, 0.0, 1.0));
}

}  // namespace terracut
