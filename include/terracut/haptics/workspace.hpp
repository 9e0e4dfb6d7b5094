// The mapping between a haptic device's workspace and the world, as haptics
// frameworks do it: a scale, an offset and a fixed rotation from the
// device's axes (CHAI3D: x toward the operator, y right, z up) to the world's
// (Y up). See terracut/haptics/settings.hpp for the convention:
//
//   world position = offset + scale * R * device position,  R = Ry(yaw) * P
//   P: device x -> world +Z, device y -> world +X, device z -> world +Y
//
// Directions (velocities, forces) use R alone; orientations are conjugated,
// so the identity on the device is the identity in the world and a turn
// about a device axis is a turn about the matching world axis.
#pragma once

#include "terracut/core/blade.hpp"
#include "terracut/haptics/device.hpp"
#include "terracut/haptics/settings.hpp"
#include "terracut/core/math.hpp"

namespace terracut::haptics {

class Workspace {
 public:
  /// The mapping of the settings (validated by validate(HapticSettings)).
  explicit Workspace(const WorkspaceMapping& mapping);

  const WorkspaceMapping& mapping() const { return mapping_; }
  /// R as a unit quaternion (device axes -> world axes).
  Quat rotation() const { return rotation_; }

  /// Device position (device metres) -> world position (world metres).
  Vec3 to_world(Vec3 device_m) const;
  /// World position -> device position (the inverse of to_world).
  Vec3 to_device(Vec3 world_m) const;
  /// A direction or velocity: device axes -> world axes, no scale.
  Vec3 direction_to_world(Vec3 device) const;
  /// A direction or force: world axes -> device axes, no scale.
  Vec3 direction_to_device(Vec3 world) const;
  /// A device-frame rotation -> the same rotation about the matching world axes.
  Quat orientation_to_world(Quat device) const;
  /// Inverse of orientation_to_world.
  Quat orientation_to_device(Quat world) const;
  /// The sample a 6-DOF device holding the tool at this world pose reads:
  /// position and orientation in the device frame, no buttons, not a
  /// reconnection (the other fields of out are left as they are).
  void fill_sample(const BladePose& world_pose, DeviceSample& out) const;

 private:
  WorkspaceMapping mapping_;
  Quat rotation_{};
  Quat inverse_{};
};

}  // namespace terracut::haptics
