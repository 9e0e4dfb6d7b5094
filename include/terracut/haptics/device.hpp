// The device interface of the haptic loop: pose and buttons in, force out.
//
// A device lives in its own frame (CHAI3D's: x toward the operator, y right,
// z up, metres, newtons); the loop maps it to the world (workspace.hpp).
// Backends: ScriptDevice (script_device.hpp), SimHandDevice (sim_hand.hpp)
// and UdpDevice (udp_device.hpp).
//
// read() and write() are called from the loop thread once per tick; they
// never block, never throw and allocate nothing.
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "terracut/core/blade.hpp"
#include "terracut/core/math.hpp"

namespace terracut::haptics {

/// One sample from the device.
struct DeviceSample {
  Vec3 position_m{};             ///< handle position, device frame, metres
  Quat orientation{};            ///< handle orientation, device frame (when has_orientation)
  bool has_orientation = false;  ///< the device measures orientation (a 3-DOF Falcon does not)
  std::uint32_t buttons = 0;     ///< button bits, bit i = button i pressed
  /// The device reconnected with this sample (a new bridge session): the
  /// loop begins a new soft start.
  bool reconnected = false;
  /// The tool was lifted out of the soil before this sample (between two
  /// strokes of a scripted sequence): nothing is swept from the previous
  /// pose, as a batch run lifts it between cuts (Simulation::lift).
  bool lifted = false;
  /// A scripted device knows the world pose its handle stands for: the loop
  /// takes it as it is instead of mapping the handle through the workspace
  /// (whose round trip rounds), so a scripted session steps exactly the
  /// poses a batch run steps. Real devices leave it unset.
  bool has_world_pose = false;
  BladePose world_pose{};
  /// When the device measured the sample on its own clock, seconds (any
  /// origin, never going back within a session); NaN when the device does
  /// not say. The loop estimates the velocity from these times when it has
  /// them: a sample that arrives late over a network is then not read as a
  /// jump in speed.
  double device_time_s = std::numeric_limits<double>::quiet_NaN();
};

/// What the loop sends to the device each tick.
struct DeviceCommand {
  Vec3 force_n{};           ///< force to render, device frame, newtons (safety-limited)
  std::uint32_t flags = 0;  ///< LoopRecord flags of the tick (safety bits and loop bits)
  double t_s = 0.0;         ///< loop time of the tick, seconds
};

/// A named number for the session summary (after the run, never per tick).
struct DeviceStat {
  std::string name;
  double value = 0.0;
};

class Device {
 public:
  virtual ~Device() = default;

  /// "script", "sim" or "udp".
  virtual std::string_view kind() const = 0;

  /// Called once by the loop before the first read, at loop time t_s (s).
  virtual void start(double t_s) { (void)t_s; }

  /// The newest sample at loop time t_s (seconds, non-decreasing). Returns
  /// true and fills `out` when a new sample arrived since the previous call;
  /// false when the device was silent (out is left as it was). The sample's
  /// values are not checked: the loop counts non-finite ones.
  virtual bool read(double t_s, DeviceSample& out) noexcept = 0;

  /// The force to render from now until the next write.
  virtual void write(const DeviceCommand& command) noexcept = 0;

  /// Called once by the loop after the last tick.
  virtual void stop() noexcept {}

  /// True while the device's user has paused it: only a virtual device has
  /// a Pause (the viewer's). The real-time loop (HapticLoop::start) then
  /// holds after the tick it is in, reads and writes nothing and costs no
  /// CPU, until this is false again or a stop is requested; its clock
  /// leaves the pause out. Called by the loop's thread between ticks. A real
  /// device never pauses: a haptic loop must keep answering it.
  virtual bool paused() noexcept { return false; }

  /// Counters for the summary (packets, rejections, hand energy, ...).
  virtual std::vector<DeviceStat> stats() const { return {}; }
};

}  // namespace terracut::haptics
