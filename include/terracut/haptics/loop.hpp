// The haptic loop: at a fixed rate (default 1 kHz), on its own thread,
//
//   step1: read the device -> map its workspace to the world -> set the tool
//          pose -> Simulation::begin_step (contact before the cut)
//   step2: Simulation::finish_step (swept cut, soil, the physical force on
//          the tool, then the simulation's step listeners: e.g. rigid
//          bodies, whose force joins it) -> ForceModel::compute (the
//          physical force rendered at the device's filtered motion) ->
//          SafetyLimiter::update -> map the force to the device -> write ->
//          record -> feed the snapshot exchange (optional)
//
// the split where the outside world comes in, as MuJoCo's mj_step1/mj_step2.
// Parameters (LoopParams: settings, force model; the workspace) are
// read-only during a run; the state (limiter, estimator, records, counters)
// lives here, and the simulation it steps (with its listeners) belongs to
// whoever built the loop (the session layer's world).
// A tick allocates nothing and never throws: a bad device sample (non-finite
// position or orientation) is counted and answered with zero force, and the
// loop goes on.
//
// Two ways to run it:
//   - run_deterministic(): synchronously on the calling thread, tick i at
//     t = i / rate exactly, no sleeping; the same inputs give the same records
//     (except the measured compute times). Tests and the `script` device use it.
//   - start() / request_stop() / join(): on its own thread, paced by the
//     Pacer (absolute deadlines, sleep then a short spin), with SCHED_FIFO
//     and locked memory where permitted. A device its user paused (the
//     viewer's virtual one: Device::paused) holds the thread between ticks,
//     costing nothing, and the loop's time leaves the pause out.
#pragma once

#include <atomic>
#include <cstdint>
#include <future>
#include <limits>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "terracut/core/forces.hpp"
#include "terracut/haptics/settings.hpp"
#include "terracut/core/safety.hpp"
#include "terracut/core/simulation.hpp"
#include "terracut/core/stats.hpp"
#include "terracut/haptics/device.hpp"
#include "terracut/haptics/pacer.hpp"
#include "terracut/haptics/realtime.hpp"
#include "terracut/haptics/snapshot.hpp"
#include "terracut/haptics/workspace.hpp"

namespace terracut::haptics {

/// Loop flag bits of a record (the low five are SafetyFlags::bits()).
inline constexpr std::uint32_t kFlagClamped = 1u;
inline constexpr std::uint32_t kFlagRateLimited = 2u;
inline constexpr std::uint32_t kFlagRamping = 4u;
inline constexpr std::uint32_t kFlagWatchdog = 8u;
inline constexpr std::uint32_t kFlagNonfinite = 16u;
/// The device's sample of this tick was not finite: ignored, zero force.
inline constexpr std::uint32_t kFlagBadSample = 32u;
/// No new device sample this tick (the previous one was used).
inline constexpr std::uint32_t kFlagSilent = 64u;
/// The previous tick's work ran past this tick's deadline: it started late (Tick::after_overrun).
inline constexpr std::uint32_t kFlagMissedDeadline = 128u;
/// The device reconnected this tick (a new soft start began).
inline constexpr std::uint32_t kFlagReconnected = 256u;
/// The device's sample starts a new stroke (DeviceSample::lifted): the
/// simulation was lifted, nothing swept from the previous pose.
inline constexpr std::uint32_t kFlagLifted = 512u;

/// One tick, as recorded (one row of haptics.csv).
struct LoopRecord {
  std::int64_t tick = 0;          ///< tick index, from 0
  double t_s = 0.0;               ///< loop time of the tick, seconds (tick start)
  Vec3 device_position_m{};       ///< device handle, device frame, metres (last good sample)
  BladePose tool{};               ///< tool pose, world
  double contact_length_m = 0.0;  ///< blade length in soil, metres (before the cut)
  double cut_depth_m = 0.0;  ///< depth of undisturbed soil ahead of the edge (the physical force's), metres
  double removed_volume_m3 = 0.0;  ///< volume cut this tick, m^3
  Vec3 velocity_m_per_s{};         ///< estimated tool velocity, world m/s
  /// The physical force on the tool, world N (StepOutput::force.total_n):
  /// what the soil and the bodies do, whatever the device renders.
  Vec3 physical_force_world_n{};
  /// The rendered force in world newtons, before force_scale: the physical
  /// force under the device's low-speed damper and gain, plus the surface
  /// proxy (ForceOutput::world_n); the step listeners' part is body_force_world_n.
  Vec3 force_world_n{};
  /// The step listeners' part of force_world_n (e.g. rigid bodies pushing
  /// the blade's plate: StepOutput::listener_force_world_n), world N; zero
  /// without listeners.
  Vec3 body_force_world_n{};
  /// The penetration model's part of force_world_n (vertical, +Y up), world N.
  double penetration_force_n = 0.0;
  /// The cutting model's part of force_world_n, world N, and what it is the
  /// lower of: the soil's force before the low-speed cap and the cap, N
  /// (ForceOutput::cutting_uncapped_n, cutting_cap_n).
  Vec3 cutting_force_world_n{};
  double cutting_uncapped_n = 0.0;
  double cutting_cap_n = 0.0;
  /// Twist torque on the tool about world +Y, N m (not in any force: a 3-DOF
  /// device cannot render it).
  double twist_torque_n_m = 0.0;
  double yaw_rate_rad_per_s = 0.0;  ///< estimated tool yaw rate about world +Y, rad/s
  Vec3 force_device_n{};           ///< force sent, device frame, device N (after safety)
  std::uint32_t flags = 0;         ///< kFlag* bits
  double period_s = 0.0;           ///< time since the previous tick's start, seconds
  double compute_s = 0.0;          ///< time from the tick's start to the force written, seconds
};

/// Counters of a run (besides the limiter's own).
struct LoopCounters {
  std::int64_t ticks = 0;             ///< ticks run
  std::int64_t samples = 0;           ///< new device samples read
  std::int64_t silent_ticks = 0;      ///< ticks without a new sample
  std::int64_t bad_samples = 0;       ///< non-finite samples (counted warnings, zero force)
  std::int64_t reconnects = 0;        ///< device reconnections (new soft starts)
  std::int64_t missed_deadlines = 0;  ///< ticks started late after an overrun (kFlagMissedDeadline)
  std::int64_t records_dropped = 0;   ///< oldest records overwritten (capacity reached)
};

/// Percentiles of a per-tick time, microseconds (core/stats.hpp).
using TimePercentiles = TimingStats;

/// The range of a haptic loop's rate, Hz: narrower than a simulation's
/// (kRateRange), since a device is paced and answered every tick.
inline constexpr Range kLoopRateRange{"rate_hz", 10.0, 10000.0, RangeEnds::kClosed};

/// The loop's parameters: the haptic settings, validated once, with their
/// derived values computed once (the force model's workspace scale, loop
/// rate and largest contact length) and the force model built once (its
/// device check made). Read-only during a run.
class LoopParams {
 public:
  /// settings: as parsed (any derived force fields are replaced); blade: the
  /// scenario's blade (its length bounds the contact); rate_hz: the loop's
  /// rate, the simulation's (the scenario's rate_hz, or a program's
  /// override), in kLoopRateRange. Throws InputError "haptics.FIELD ..."
  /// naming the bad field, including a ForceModel refusal ("haptics.forces.
  /// ..."), or "rate_hz ..." for a rate out of the loop's range.
  LoopParams(const HapticSettings& settings, const BladeSpec& blade, double rate_hz);

  /// The settings with the derived force fields filled in.
  const HapticSettings& settings() const { return settings_; }
  /// The loop rate, Hz (kept once, as the force model's loop_rate_hz): the
  /// simulation the loop steps must run at this rate.
  double rate_hz() const { return settings_.forces.loop_rate_hz; }
  /// The force model (after the device check).
  const ForceModel& force_model() const { return model_; }

 private:
  HapticSettings settings_;
  ForceModel model_;
};

/// How to run a loop.
struct LoopOptions {
  /// Ticks to run, >= 1 (the session: round(duration * rate)).
  std::int64_t ticks = 1000;
  /// Records kept (a ring: the newest are kept), >= 0; 0 keeps none.
  std::size_t record_capacity = 0;
  /// Real-time mode only: ask for SCHED_FIFO at this priority and lock memory.
  bool realtime = true;
  int realtime_priority = 80;
  bool lock_memory = true;
  /// Real-time mode: the pacer's clock; null: the system's monotonic clock.
  /// Tests pass a fake one (run_deterministic always uses its own).
  std::shared_ptr<PacerClock> clock;
  /// Optional viewer feed, fed every tick from the loop thread (one writer);
  /// must outlive the loop and be built on the same grid size.
  SnapshotExchange* snapshot = nullptr;
  /// > 0: the loop ends by itself once the device, after its first sample,
  /// has sent nothing for this long, seconds (a UDP device whose session
  /// ended). 0: only options.ticks or a stop request end it.
  double end_after_silence_s = 0.0;
  /// Optional: the rigid bodies simulated with the terrain (a step listener
  /// of the simulation that also says where the bodies are), for the
  /// snapshot's frames; must outlive the loop. Null: frames carry no bodies.
  const BodySource* bodies = nullptr;
};

class HapticLoop {
 public:
  /// params: the loop's validated parameters; sim: the simulation it steps
  /// (with its listeners), at params.rate_hz(); default_orientation: the tool
  /// orientation when neither settings.tool_rotation_deg nor the device gives
  /// one. The simulation and the device must outlive the loop. Throws
  /// InputError when the simulation's rate is not the loop's, or on bad
  /// options.
  HapticLoop(const LoopParams& params, Simulation& sim, Quat default_orientation, Device& device,
             const LoopOptions& options);
  ~HapticLoop();
  HapticLoop(const HapticLoop&) = delete;
  HapticLoop& operator=(const HapticLoop&) = delete;

  // --- one tick, in two halves ------------------------------------------

  /// Phase 1 at loop time t_s: read the device, map it, set the tool pose and
  /// measure contact (Simulation::begin_step).
  void step1(double t_s) noexcept;
  /// Phase 2: cut, force, safety, write the device, record. period_s: time
  /// since the previous tick's start (0 for the first); compute_s: the tick's
  /// compute time so far; missed_deadline: the tick started late. Returns
  /// the tick's record (valid until the next tick).
  const LoopRecord& step2(double period_s, double compute_s, bool missed_deadline) noexcept;

  // --- running ----------------------------------------------------------

  /// Runs options.ticks ticks synchronously at t = i / rate (no sleeping).
  void run_deterministic();
  /// Starts the loop thread (real-time mode) and returns once it has set up
  /// its scheduling (realtime_status() is then valid). Throws
  /// std::logic_error when running.
  void start();
  /// Asks the thread to stop after its current tick (safe from any thread,
  /// and from a signal handler through the flag).
  void request_stop() { stop_requested_.store(true, std::memory_order_relaxed); }
  /// Waits for the thread to end (it ends after options.ticks or a stop request).
  void join();
  /// While the device is paused (Device::paused) the thread looks at it
  /// again every this many seconds, and at a stop request.
  static constexpr double kPausePoll_s = 0.005;
  /// True while the loop thread runs.
  bool running() const { return running_.load(std::memory_order_acquire); }

  // --- results (read after the run) -------------------------------------

  const HapticSettings& settings() const { return params_.settings(); }
  const LoopParams& params() const { return params_; }
  const ForceModel& force_model() const { return params_.force_model(); }
  const SafetyLimiter& safety() const { return safety_; }
  const Simulation& simulation() const { return sim_; }
  const Workspace& workspace() const { return workspace_; }
  const LoopCounters& counters() const { return counters_; }
  const LoopRecord& last() const { return last_; }
  /// The tool's estimated yaw rate about world +Y, rad/s (filtered as the velocity).
  double yaw_rate_rad_per_s() const { return yaw_rate_rad_per_s_; }
  /// The tool's estimated acceleration, world m/s^2: the filtered velocity's
  /// backward difference, low-passed at kAccelerationCutoffHz. The soil a
  /// bucket carries resists it (its inertia, in the force).
  Vec3 acceleration_m_per_s2() const { return acceleration_m_per_s2_; }
  /// Cut-off of the acceleration's first-order low-pass, Hz: a tenth of the
  /// velocity's default 100 Hz, so that device noise differentiated twice
  /// does not reach the hand (at 10 um of position noise and 1 kHz the raw
  /// second difference is about 10 m/s^2); a 16 ms time constant.
  static constexpr double kAccelerationCutoffHz = 10.0;
  /// Standard gravity, m/s^2: the carried soil's mass is its weight (unit
  /// weight x volume) over this (the Bullet world's default gravity).
  static constexpr double kGravityM_s2 = 9.81;
  /// The kept records, oldest first.
  std::vector<LoopRecord> records() const;
  /// Percentiles over the kept records: the period's deviation from the
  /// nominal period |period - 1/rate| (jitter), the period, and the compute time.
  TimePercentiles jitter() const;
  TimePercentiles period() const;
  TimePercentiles compute() const;
  /// The pacer's statistics of the run (every tick, histogram percentiles):
  /// missed deadlines, skipped slots, compute, period jitter, wake latency.
  const LoopStats& pacer_stats() const { return pacer_stats_; }
  /// What the real-time request obtained (empty message in deterministic mode).
  const RealtimeStatus& realtime_status() const { return realtime_; }
  /// Largest |force sent| over the run, device N.
  double max_device_force_n() const { return max_device_force_n_; }
  /// Largest |listeners' force| over the run (every tick, kept or not), world N.
  double max_body_force_n() const { return max_body_force_n_; }
  /// Watchdog trips between the device's first and its newest sample: the
  /// silences of a device that was sending. The waits before the first
  /// sample and after the last are expected and not counted here.
  std::int64_t watchdog_trips_while_active() const {
    return trips_at_newest_sample_ - trips_before_first_sample_;
  }
  /// True when the loop ended because the device fell silent
  /// (LoopOptions::end_after_silence_s).
  bool ended_with_device() const { return ended_with_device_; }

 private:
  void thread_main(std::promise<void>& ready);
  void paced_tick(Pacer& pacer, PacerClock& measure, const Tick& tick, double origin_s,
                  bool fake) noexcept;
  void patch_compute(double compute_s) noexcept;
  void record(const LoopRecord& r) noexcept;
  // step1's phases.
  bool read_device(double t_s) noexcept;
  BladePose tool_pose() const noexcept;
  void estimate_velocity(const BladePose& pose, double t_s) noexcept;
  // step2's phases.
  ForceOutput rendered_force(const StepOutput& out) const noexcept;
  LoopRecord& write_record(const StepOutput& out, const ForceOutput& force,
                           const DeviceCommand& command, double period_s,
                           double compute_s) noexcept;
  void publish_frame(const StepOutput& out, const ForceOutput& force,
                     const DeviceCommand& command, double period_s,
                     double compute_s) noexcept;
  TimePercentiles percentiles(double LoopRecord::*field, bool deviation) const;

  LoopParams params_;
  Device& device_;
  LoopOptions options_;
  Workspace workspace_;
  SafetyLimiter safety_;
  Simulation& sim_;
  Quat default_orientation_{};
  Quat fixed_orientation_{};
  bool has_fixed_orientation_ = false;
  double filter_rc_s_ = 0.0;  // low-pass time constant, 0 = off

  // State.
  bool started_ = false;
  bool stepped_ = false;      // the simulation was stepped this tick
  StepOutput not_stepped_{};  // what step2 reads when it was not: no contact, no cut
  DeviceSample sample_{};     // last good device sample
  bool has_sample_ = false;
  double last_sample_t_s_ = -1e300;  // loop time of the newest good sample
  Vec3 previous_tool_m_{};           // tool position at the previous good sample
  double previous_tool_t_s_ = 0.0;
  bool has_previous_tool_ = false;
  Vec3 velocity_m_per_s_{};
  Vec3 acceleration_m_per_s2_{};     // filtered, world
  double previous_yaw_rad_ = 0.0;    // the edge's heading at the previous good sample
  double previous_device_t_s_ = std::numeric_limits<double>::quiet_NaN();  // its device time
  double yaw_rate_rad_per_s_ = 0.0;  // filtered, about world +Y
  double t_s_ = 0.0;
  std::uint32_t tick_flags_ = 0;
  Vec3 device_position_m_{};
  LoopCounters counters_{};
  LoopRecord last_{};
  double max_device_force_n_ = 0.0;
  double max_body_force_n_ = 0.0;
  std::int64_t trips_before_first_sample_ = 0;
  std::int64_t trips_at_newest_sample_ = 0;
  bool ended_with_device_ = false;

  std::vector<LoopRecord> records_;  // ring of options_.record_capacity
  std::size_t next_record_ = 0;
  bool records_wrapped_ = false;

  RealtimeStatus realtime_{};
  LoopStats pacer_stats_{};
  std::thread thread_;
  std::atomic<bool> stop_requested_{false};
  std::atomic<bool> running_{false};
};

}  // namespace terracut::haptics
