// A scenario cut as a device path, and the `script` device that follows it.
#pragma once

#include <cstddef>
#include <vector>

#include "terracut/core/blade.hpp"
#include "terracut/haptics/device.hpp"
#include "terracut/haptics/workspace.hpp"

namespace terracut::haptics {

/// A cut's keyframes expressed in the device frame: where a device handle
/// has to be for the tool to follow the cut (position linear between
/// keyframes, rotation slerp, as Motion::sample). Time 0 is the cut's start;
/// before it and after the last keyframe the path holds its end poses.
class DevicePath {
 public:
  /// cut: a valid Motion (validate(Motion) is empty); workspace: the mapping.
  /// Throws InputError naming the cut when the motion is invalid.
  DevicePath(const Motion& cut, const Workspace& workspace);

  double duration_s() const { return cut_.duration_s(); }
  const Motion& cut() const { return cut_; }

  /// Handle position at time t_s, device metres.
  Vec3 position_m(double t_s) const;
  /// Handle velocity at time t_s (the keyframe segment's), device m/s; 0
  /// outside the keyframes' span. At a keyframe, the segment that starts there.
  Vec3 velocity_m_per_s(double t_s) const;
  /// Handle orientation at time t_s, device frame.
  Quat orientation(double t_s) const;
  /// Largest segment speed of the path, device m/s.
  double max_speed_m_per_s() const;

 private:
  Motion cut_;
  Workspace workspace_;
};

/// The `script` device: its handle is exactly on the path at every read
/// (position and orientation), whatever force is written; the forces are
/// only recorded. What experiments use: the same motion every run.
class ScriptDevice final : public Device {
 public:
  explicit ScriptDevice(DevicePath path);

  std::string_view kind() const override { return "script"; }
  void start(double t_s) override { start_t_s_ = t_s; }
  bool read(double t_s, DeviceSample& out) noexcept override;
  void write(const DeviceCommand& command) noexcept override;
  std::vector<DeviceStat> stats() const override;

  const DevicePath& path() const { return path_; }

 private:
  DevicePath path_;
  double start_t_s_ = 0.0;
  double max_force_n_ = 0.0;
  std::int64_t writes_ = 0;
};

}  // namespace terracut::haptics
