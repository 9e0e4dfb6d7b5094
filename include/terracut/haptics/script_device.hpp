// A scenario cut as a device path, and the `script` device that follows it.
#pragma once

#include <cstddef>
#include <vector>

#include "terracut/core/blade.hpp"
#include "terracut/haptics/device.hpp"
#include "terracut/haptics/workspace.hpp"

namespace terracut::haptics {

/// Cuts' keyframes expressed in the device frame: where a device handle
/// has to be for the tool to follow them (position linear between
/// keyframes, rotation slerp, as Motion::sample). One cut, or the strokes of
/// a sequence played one after the other at a rate as a batch run steps
/// them (each cut round(duration x rate) + 1 steps, the next starting on the
/// step after), with the tool lifted between them. Time 0 is the first
/// stroke's start; before it and after the last keyframe the path holds its
/// end poses.
class DevicePath {
 public:
  /// cut: a valid Motion (validate(Motion) is empty); workspace: the mapping.
  /// Throws InputError naming the cut when the motion is invalid.
  DevicePath(const Motion& cut, const Workspace& workspace);
  /// The strokes (at least one, each valid) in order, played at rate_hz
  /// (finite, > 0) as a batch run steps them.
  DevicePath(std::vector<Motion> strokes, double rate_hz, const Workspace& workspace);

  /// The path's length, seconds: the last stroke's start plus its duration.
  double duration_s() const { return starts_s_.back() + strokes_.back().duration_s(); }
  /// The strokes, in order.
  const std::vector<Motion>& strokes() const { return strokes_; }
  /// The stroke a handle at time t_s follows (0 before the first).
  std::size_t stroke_at(double t_s) const;
  /// The tool's world pose at time t_s: the stroke's Motion::sample at the
  /// time from the stroke's start. A time within a millionth of a step of a
  /// step's time (a paced loop's tick) is taken as that step's, counted in
  /// whole steps from the stroke's first as a batch run counts them, so the
  /// poses are a batch run's to the bit.
  BladePose world_pose(double t_s) const;

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
  std::vector<Motion> strokes_;
  std::vector<double> starts_s_;  // each stroke's start on the path, seconds
  std::vector<std::int64_t> starts_step_;  // and in steps at rate_hz_ (multi-stroke paths)
  double rate_hz_ = 0.0;          // 0: one stroke, continuous time
  Workspace workspace_;
};

/// The `script` device: its handle is exactly on the path at every read
/// (position and orientation), whatever force is written; the forces are
/// only recorded. What experiments use: the same motion every run. The
/// first sample of each stroke after the first says the tool was lifted
/// (DeviceSample::lifted), as a batch run lifts it between cuts.
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
  std::size_t stroke_ = 0;  // the stroke of the previous read
  double max_force_n_ = 0.0;
  std::int64_t writes_ = 0;
};

}  // namespace terracut::haptics
