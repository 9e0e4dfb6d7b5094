#include "terracut/haptics/workspace.hpp"

#include <cmath>
#include <numbers>

namespace terracut::haptics {
namespace {

Quat conjugate(Quat q) { return {q.w, -q.x, -q.y, -q.z}; }

// P: device x -> world +Z, y -> +X, z -> +Y. A turn of 240 degrees (-120)
// about the diagonal (1, 1, 1) / sqrt(3) maps e_x -> e_z, e_y -> e_x, e_z -> e_y.
Quat device_axes_to_world() {
  const double s = 1.0 / std::sqrt(3.0);
  return quat_from_axis_angle({s, s, s}, -2.0 * std::numbers::pi / 3.0);
}

}  // namespace

Workspace::Workspace(const WorkspaceMapping& mapping) : mapping_(mapping) {
  const Quat yaw =
      quat_from_axis_angle({0.0, 1.0, 0.0}, mapping.yaw_deg * std::numbers::pi / 180.0);
  rotation_ = normalized(yaw * device_axes_to_world());
  inverse_ = conjugate(rotation_);
}

Vec3 Workspace::to_world(Vec3 device_m) const {
  return mapping_.offset_m + rotate(rotation_, device_m) * mapping_.scale;
}

Vec3 Workspace::to_device(Vec3 world_m) const {
  return rotate(inverse_, world_m - mapping_.offset_m) * (1.0 / mapping_.scale);
}

Vec3 Workspace::direction_to_world(Vec3 device) const { return rotate(rotation_, device); }

Vec3 Workspace::direction_to_device(Vec3 world) const { return rotate(inverse_, world); }

Quat Workspace::orientation_to_world(Quat device) const {
  return normalized(rotation_ * device * inverse_);
}

Quat Workspace::orientation_to_device(Quat world) const {
  return normalized(inverse_ * world * rotation_);
}

void Workspace::fill_sample(const BladePose& world_pose, DeviceSample& out) const {
  out.position_m = to_device(world_pose.position_m);
  out.orientation = orientation_to_device(world_pose.orientation);
  out.has_orientation = true;
  out.buttons = 0;
  out.reconnected = false;
}

}  // namespace terracut::haptics
