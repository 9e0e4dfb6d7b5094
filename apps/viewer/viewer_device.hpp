// The viewer's virtual haptic device: what moves the tool when no real
// device is connected. It implements haptics::Device, so the haptic loop
// reads it every tick on its own thread exactly as it reads a Falcon:
//
//  - script source: the tool plays the scenario's whole cut sequence (a Tour):
//    each cut's keyframes, and between two cuts a transit that rises above
//    the terrain, moves over and descends to the next cut's start (a real
//    operator lifts the blade; the transit cuts only air);
//  - mouse source: the tool follows the target pose the drawing thread posts
//    (mouse and keyboard) once per drawn frame. Each new target is reached by
//    a ramp over one frame interval (set_frame_interval_s) from where the
//    previous ramp had got to, and the tool follows that ramp with a
//    first-order lag of kVirtualDeviceLag_s, so targets posted at 10-60 Hz
//    become a smooth 1 kHz motion of steady speed. (A lag alone makes the
//    speed decay within every frame: a saw-tooth at the frame rate that a
//    speed-dependent force, such as the cutting force below its saturation
//    speed, renders as a buzz; docs/viewer.md.)
//
// Play/pause, steps and speed act on the device's own clock: paused, the
// handle holds still and the device says so (paused()): the paced haptic
// loop then holds, ticking nothing and costing no CPU, until Play, a step or
// a stop (a virtual device may pause its loop; a real one never does); a
// step plays a stated time (request_step_s) and holds again. Speed scales the
// script's time and the lag. The device also timestamps each read and write
// with the wall clock, so the viewer sees the loop's period and compute time
// live (LoopStats) without touching the loop's own records.
#pragma once

#include <atomic>
#include <cstdint>
#include <vector>

#include "mailbox.hpp"
#include "terracut/core/blade.hpp"
#include "terracut/core/grid.hpp"
#include "terracut/haptics/device.hpp"
#include "terracut/haptics/workspace.hpp"
#include "terracut/io/scenario.hpp"

namespace terracut::viewer {

/// What moves the tool.
enum class ToolSource : int {
  kScript = 0,  ///< the scenario's cuts, in its sequence (a Tour)
  kMouse = 1,   ///< the mouse and keyboard (posted target poses)
};

/// Time constant of the mouse-driven tool's lag behind the posted target, seconds.
inline constexpr double kVirtualDeviceLag_s = 0.03;

/// A straight move between two poses (position linear, rotation slerp).
struct PoseLeg {
  double start_s = 0.0;     ///< time the leg starts, seconds
  double duration_s = 0.0;  ///< seconds, >= 0
  BladePose from{}, to{};
  int cut = -1;             ///< index into Scenario::cuts when the leg plays a cut, else -1
  int sequence_index = -1;  ///< position in the sequence of that cut, else -1
};

/// The scenario's sequence played as one path: cuts joined by transits.
class Tour {
 public:
  Tour() = default;
  /// clearance_y_m: world Y the transits rise to (above every height).
  Tour(const io::Scenario& scenario, double clearance_y_m, double transit_speed_m_per_s);
  /// A path of straight legs (cut = -1), back to back from time 0.
  explicit Tour(std::vector<PoseLeg> legs);

  double duration_s() const { return duration_s_; }
  bool empty() const { return legs_.empty(); }
  /// The pose at time t_s (held before 0 and after the end).
  BladePose sample(double t_s) const;
  /// The leg playing at t_s (nullptr when empty).
  const PoseLeg* leg_at(double t_s) const;

  /// Fills the three legs of a transit from `from` to `to` over
  /// clearance_y_m (up, across, down), starting at start_s; returns the end
  /// time. Allocates nothing.
  static double transit(PoseLeg (&out)[3], double start_s, const BladePose& from,
                        const BladePose& to, double clearance_y_m, double speed_m_per_s);

 private:
  const io::Scenario* scenario_ = nullptr;  // for the cuts' motions (outlives the tour)
  std::vector<PoseLeg> legs_;
  double duration_s_ = 0.0;
};

/// Timing of the loop as seen by the device, wait-free (relaxed atomics):
/// 1 microsecond bins up to 50 ms.
struct LoopTimingSnapshot {
  std::int64_t ticks = 0;  ///< periods measured
  double period_p50_us = 0.0, period_p99_us = 0.0, period_max_us = 0.0;
  double compute_p50_us = 0.0, compute_p99_us = 0.0, compute_max_us = 0.0;
};

class LoopTiming {
 public:
  static constexpr int kBins = 50000;
  void record_period(double period_s);
  void record_compute(double compute_s);
  LoopTimingSnapshot snapshot() const;
  /// Zeroes the histograms (counts racing with the loop may be lost, never torn).
  void clear();
  /// Largest |period - nominal| since the previous call, seconds (nominal set by set_nominal).
  double take_worst_jitter_s();
  void set_nominal(double period_s) { nominal_ns_ = std::int64_t(period_s * 1e9); }

 private:
  std::vector<std::atomic<std::uint32_t>> period_hist_ =
      std::vector<std::atomic<std::uint32_t>>(kBins);
  std::vector<std::atomic<std::uint32_t>> compute_hist_ =
      std::vector<std::atomic<std::uint32_t>>(kBins);
  std::atomic<std::int64_t> ticks_{0};
  std::atomic<std::int64_t> period_max_ns_{0}, compute_max_ns_{0}, worst_jitter_ns_{0};
  std::int64_t nominal_ns_ = 1000000;
};

class ViewerDevice final : public haptics::Device {
 public:
  /// workspace: the loop's mapping (world targets are sent in device
  /// coordinates); tour: the script (must outlive the device); start: the
  /// tool's first pose; rate_hz: the loop rate (a single step advances
  /// 1 / rate_hz); timing: where reads and writes are timestamped with the
  /// wall clock (real-time loop), or nullptr for none; it must outlive the device.
  ViewerDevice(const haptics::Workspace& workspace, const Tour& tour, const BladePose& start,
               double rate_hz, double clearance_y_m, double transit_speed_m_per_s,
               LoopTiming* timing);

  std::string_view kind() const override { return "viewer"; }
  void start(double t_s) override;
  bool read(double t_s, haptics::DeviceSample& out) noexcept override;
  void write(const haptics::DeviceCommand& command) noexcept override;
  /// Paused and no step to play: the paced loop holds (Device::paused).
  /// Called by the loop's thread.
  bool paused() noexcept override;

  // --- controls, from any thread ---
  void set_playing(bool playing) { playing_.store(playing); }
  bool playing() const { return playing_.load(); }
  void set_speed(double speed);
  double speed() const { return speed_.load(); }
  void request_steps(int n) { step_requests_.fetch_add(n); }
  /// While paused: play step_s more seconds of device time at the device's
  /// speed (as if playing, over as many ticks), then hold still again. A
  /// Step that is seen, unlike one loop period.
  void request_step_s(double step_s);
  /// True while a requested step is still being played.
  bool stepping() const { return step_budget_s_.load(std::memory_order_relaxed) > 0.0; }
  /// The device's own clock, seconds: the device time played so far (by
  /// either source); it stands still while paused.
  double clock_s() const { return clock_published_.load(std::memory_order_relaxed); }
  void set_source(ToolSource source) { source_.store(int(source)); }
  ToolSource source() const { return ToolSource(source_.load()); }
  void set_target(const BladePose& pose) { target_.write(pose); }
  /// Time constant of the mouse-driven tool's lag, seconds, clamped to
  /// [kVirtualDeviceLag_s, 1]; the viewer lengthens it when it draws slowly,
  /// so the tool glides between sparse targets instead of stopping and going.
  void set_lag_s(double lag_s);
  /// The drawing thread's frame interval, seconds: each posted target is
  /// ramped to over this much device time. Clamped to [0, 0.25]; 0 (the
  /// default) jumps the goal to each target at once (the lag alone).
  void set_frame_interval_s(double interval_s);
  /// Script time played so far, seconds, and whether the tour has ended.
  double script_time_s() const { return script_time_published_.load(); }
  bool script_finished() const { return script_finished_.load(); }
  /// Stop playing when the tour ends (paced viewer) or keep ticking (headless).
  void set_pause_at_end(bool pause) { pause_at_end_ = pause; }

  /// The timing this device records into (nullptr when none).
  LoopTiming* timing() { return timing_; }

 private:
  haptics::Workspace workspace_;
  const Tour& tour_;
  double dt_s_;
  double clearance_y_m_;
  double transit_speed_m_per_s_;
  LoopTiming* timing_;
  bool pause_at_end_ = true;

  // Loop-thread state.
  double previous_t_s_ = 0.0;
  bool started_ = false;
  double script_time_s_ = 0.0;
  BladePose pose_{};         // the handle's pose, world
  BladePose mouse_target_{};  // where the ramp goes
  BladePose ramp_from_{};     // where the ramp started
  double ramp_t_s_ = 0.0;     // device time since it started
  double ramp_len_s_ = 0.0;   // its length
  ToolSource active_ = ToolSource::kScript;
  PoseLeg transit_[3]{};     // a transit back to the script after the mouse
  double transit_time_s_ = 0.0;
  bool in_transit_ = false;
  std::int64_t read_wall_ns_ = 0;
  std::int64_t previous_wall_ns_ = 0;
  bool held_ = false;  // the loop held for a pause: the next read's gap is no period

  // Shared.
  std::atomic<bool> playing_{true};
  std::atomic<double> speed_{1.0};
  std::atomic<double> lag_s_{kVirtualDeviceLag_s};
  std::atomic<double> frame_interval_s_{0.0};
  std::atomic<int> step_requests_{0};
  std::atomic<double> step_budget_s_{0.0};
  std::atomic<double> clock_published_{0.0};
  double clock_s_ = 0.0;  // loop thread
  std::atomic<int> source_{0};
  std::atomic<double> script_time_published_{0.0};
  std::atomic<bool> script_finished_{false};
  Mailbox<BladePose> target_;
};

/// The benchmark's workload: the blade ploughs back and forth along Z across
/// the terrain's middle, the first pass at 3/4 of max_height_m, each next one
/// lower by 1/12 of it, down to the ground, at speed_m_per_s; then it keeps
/// ploughing at the ground (passes_at_ground passes). A steady, deterministic
/// cut of any length.
Tour plough_tour(const GridSpec& spec, double max_height_m, double blade_length_m,
                 double speed_m_per_s, int passes_at_ground);

/// Samples a leg at local time (seconds from its start).
BladePose sample_leg(const PoseLeg& leg, const io::Scenario* scenario, double t_s);

}  // namespace terracut::viewer
