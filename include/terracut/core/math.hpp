// Small vector and quaternion types for the core. Double precision: poses and
// geometry are computed in double, heights are stored in float (see grid.hpp).
#pragma once

#include <cmath>

namespace terracut {

/// A point or direction in the world frame (right-handed, Y up), metres.
struct Vec3 {
  double x = 0.0;
  double y = 0.0;
  double z = 0.0;
};

inline constexpr Vec3 operator+(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline constexpr Vec3 operator-(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline constexpr Vec3 operator*(Vec3 a, double s) { return {a.x * s, a.y * s, a.z * s}; }
inline constexpr Vec3 operator*(double s, Vec3 a) { return {a.x * s, a.y * s, a.z * s}; }
inline constexpr double dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline constexpr Vec3 cross(Vec3 a, Vec3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double length(Vec3 a) { return std::sqrt(dot(a, a)); }
inline constexpr Vec3 lerp(Vec3 a, Vec3 b, double t) { return a + (b - a) * t; }
inline bool is_finite(Vec3 a) { return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z); }

/// A unit quaternion (w, x, y, z) rotating vectors from the blade frame to the world frame.
struct Quat {
  double w = 1.0;
  double x = 0.0;
  double y = 0.0;
  double z = 0.0;
};

inline constexpr Quat operator*(Quat a, Quat b) {
  return {a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z,
          a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
          a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
          a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w};
}
inline bool is_finite(Quat q) {
  return std::isfinite(q.w) && std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z);
}

/// Returns q scaled to unit length; the identity for a zero quaternion.
Quat normalized(Quat q);

/// Rotates v by the unit quaternion q.
Vec3 rotate(Quat q, Vec3 v);

/// Rotation of angle_rad about the unit axis.
Quat quat_from_axis_angle(Vec3 axis, double angle_rad);

/// Rotation from Euler angles in degrees, applied to a vector first about the
/// world X axis, then world Y, then world Z (extrinsic X-Y-Z, R = Rz * Ry * Rx).
/// A rotation of 45 degrees about Z tilts a blade lying along X so that its +X
/// end rises.
Quat quat_from_euler_deg(Vec3 euler_deg);

/// Inverse of quat_from_euler_deg (angles in degrees, Y in [-90, 90]).
Vec3 euler_deg_from_quat(Quat q);

/// Spherical linear interpolation along the shorter arc; t in [0, 1].
Quat slerp(Quat a, Quat b, double t);

/// Angle in radians of the rotation that takes a to b (in [0, pi]).
double angle_between(Quat a, Quat b);

}  // namespace terracut
