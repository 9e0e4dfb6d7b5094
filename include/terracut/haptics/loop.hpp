// The haptic loop: at a fixed rate (default 1 kHz), on its own thread,
//
//   step1: read the device -> map its workspace to the world -> set the tool
//          pose -> Simulation::begin_step (contact before the cut)
//   step2: Simulation::finish_step (swept cut) -> LoopEngine::after_cut
//          (optional: e.g. rigid bodies; an extra world force) ->
//          ForceModel::compute (+ the engine's force) -> SafetyLimiter::update
//          -> map the force to the device -> write -> record -> feed the
//          snapshot exchange (optional)
//
// the split where the outside world comes in, as MuJoCo's mj_step1/mj_step2.
// Parameters (settings, force model, workspace) are read-only during a run;
// the state (simulation, limiter, estimator, records, counters) lives here.
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
//     and locked memory where permitted.
#pragma once

#include <atomic>
#include <cstdint>
#include <future>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "terracut/core/forces.hpp"
#include "terracut/core/haptic_settings.hpp"
#include "terracut/core/safety.hpp"
#include "terracut/core/simulation.hpp"
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

/// One tick, as recorded (one row of haptics.csv).
struct LoopRecord {
  std::int64_t tick = 0;          ///< tick index, from 0
  double t_s = 0.0;               ///< loop time of the tick, seconds (tick start)
  Vec3 device_position_m{};       ///< device handle, device frame, metres (last good sample)
  BladePose tool{};               ///< tool pose, world
  double contact_length_m = 0.0;  ///< blade length in soil, metres (before the cut)
  double cut_depth_m = 0.0;  ///< depth given to the earthmoving model, metres (0 without contact)
  double removed_volume_m3 = 0.0;  ///< volume cut this tick, m^3
  Vec3 velocity_m_per_s{};         ///< estimated tool velocity, world m/s
  /// World force on the tool, world N: the force models' (cutting + surface)
  /// plus the engine's (body_force_world_n).
  Vec3 force_world_n{};
  /// The engine's part of force_world_n (e.g. rigid bodies pushing the
  /// blade's plate), world N; zero without an engine.
  Vec3 body_force_world_n{};
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

/// Percentiles of a per-tick time, microseconds.
struct TimePercentiles {
  double p50_us = 0.0;
  double p99_us = 0.0;
  double max_us = 0.0;
  double mean_us = 0.0;
};

/// An optional engine stepped by the loop with the simulation (the haptics
/// layer knows none: e.g. the Bullet rigid-body world of the apps, which
/// makes an operator feel the blade hitting a rock). The loop calls, on its
/// own thread:
///
///   attach(sim)      once, from the HapticLoop constructor, before any tick
///   after_cut(out)   each tick the simulation is stepped, right after
///                    Simulation::finish_step and before the force goes to
///                    the safety limiter; the returned world force is added
///                    to the force models' world force and scaled to the
///                    device with the same force_scale
///   lifted()         when the loop lifts the tool (Simulation::lift: the
///                    next pose is a jump, not a sweep)
///   fill_frame(f)    each tick a snapshot exchange is fed, before publish
///   detach()         once, from the HapticLoop destructor after its thread
///                    has ended: drop every reference to the simulation
///
/// On ticks where the simulation is not stepped (no device sample yet, or a
/// non-finite one) after_cut is not called: the engine stands still, as the
/// terrain does. after_cut, lifted and fill_frame run inside a tick: they
/// must not allocate, block or throw. The engine must outlive the loop.
class LoopEngine {
 public:
  virtual ~LoopEngine() = default;
  /// Builds the engine over the loop's simulation (its grid, rate and blade);
  /// may allocate and throw InputError naming the bad field.
  virtual void attach(Simulation& sim) = 0;
  /// One step after the simulation's: returns the extra world force on the
  /// tool, world N (finite; a non-finite value is caught by the safety
  /// limiter like any other).
  virtual Vec3 after_cut(const StepOutput& out) noexcept = 0;
  /// The tool was lifted: the next pose is a jump.
  virtual void lifted() noexcept {}
  /// Writes the engine's part of a viewer frame (body poses); the default
  /// writes no bodies.
  virtual void fill_frame(ViewFrame& frame) const noexcept {
    frame.body_count = 0;
    frame.body_total = 0;
  }
  /// The loop is being destroyed: release whatever refers to its simulation.
  virtual void detach() noexcept {}
  /// After the run: flush and close the engine's files (idempotent). Throws
  /// InputError naming a file that could not be written.
  virtual void finish() {}
  /// After the run: the key and the JSON object text of the engine's entry in
  /// a session's summary.json; an empty key adds none.
  virtual std::string summary_key() const { return {}; }
  virtual std::string summary_json() const { return {}; }
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
  /// Optional engine stepped with the simulation (LoopEngine); must outlive
  /// the loop. Attached by the constructor.
  LoopEngine* engine = nullptr;
};

class HapticLoop {
 public:
  /// settings: as parsed (derived force fields are filled in here from the
  /// blade length); sim: the scenario's simulation parameters (rate_hz is
  /// replaced by settings.rate_hz); heights: rows x cols initial heights;
  /// default_orientation: the tool orientation when neither
  /// settings.tool_rotation_deg nor the device gives one. The device must
  /// outlive the loop. Throws InputError naming the field on bad settings
  /// (including a ForceModel refusal).
  HapticLoop(const HapticSettings& settings, const SimParams& sim, std::vector<float> heights,
             Quat default_orientation, Device& device, const LoopOptions& options);
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
  /// True while the loop thread runs.
  bool running() const { return running_.load(std::memory_order_acquire); }

  // --- results (read after the run) -------------------------------------

  const HapticSettings& settings() const { return settings_; }
  const ForceModel& force_model() const { return model_; }
  const SafetyLimiter& safety() const { return safety_; }
  const Simulation& simulation() const { return sim_; }
  const Workspace& workspace() const { return workspace_; }
  const LoopCounters& counters() const { return counters_; }
  /// The attached engine, or nullptr.
  LoopEngine* engine() const { return options_.engine; }
  const LoopRecord& last() const { return last_; }
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
  /// Largest |engine force| over the run (every tick, kept or not), world N.
  double max_body_force_n() const { return max_body_force_n_; }

 private:
  void thread_main(std::promise<void>& ready);
  void paced_tick(Pacer& pacer, PacerClock& measure, const Tick& tick, double origin_s,
                  bool fake) noexcept;
  void patch_compute(double compute_s) noexcept;
  void record(const LoopRecord& r) noexcept;
  double cut_depth(const StepOutput& out) const noexcept;
  TimePercentiles percentiles(double LoopRecord::*field, bool deviation) const;

  HapticSettings settings_;
  Device& device_;
  LoopOptions options_;
  Workspace workspace_;
  ForceModel model_;
  SafetyLimiter safety_;
  Simulation sim_;
  Quat default_orientation_{};
  Quat fixed_orientation_{};
  bool has_fixed_orientation_ = false;
  double filter_rc_s_ = 0.0;  // low-pass time constant, 0 = off
  double lookahead_m_ = 0.0;  // depth_lookahead_m of the grid

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
  double t_s_ = 0.0;
  std::uint32_t tick_flags_ = 0;
  Vec3 device_position_m_{};
  LoopCounters counters_{};
  LoopRecord last_{};
  double max_device_force_n_ = 0.0;
  double max_body_force_n_ = 0.0;

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
