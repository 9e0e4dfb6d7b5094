// Fixed-rate pacing of a real-time loop (the 1 kHz haptic loop, `terracut
// run --realtime`), with its timing statistics.
//
// Ticks are scheduled on a fixed grid of absolute deadlines, t0 + k / rate,
// so sleeping errors never accumulate into drift. Each wait sleeps until a
// short time before the deadline (clock_nanosleep with TIMER_ABSTIME on
// POSIX) and busy-waits the rest, because an OS sleep wakes tens of
// microseconds late. When a tick's work runs past the next deadline (an
// overrun), the next tick starts at once and the slots that have passed
// entirely are dropped, so a hiccup never turns into a burst of catch-up ticks.
//
// The pacer records, per tick, the compute time, the period jitter |period -
// 1 / rate| and the wake-up latency (start - deadline), in fixed-size
// histograms: nothing is allocated after construction, however long the loop
// runs. Percentiles are read from the histograms: exact below 128 ns, else
// never below the true value and at most 1/64 (1.6 %) above it; maxima are exact.
//
// Typical use:
//
//   Pacer pacer(PacerSettings{.rate_hz = 1000.0});
//   pacer.start();                              // tick 0 starts now
//   while (running) {
//     const StepOutput& o = sim.step(pose);     // the tick's work
//     pacer.record_compute(o.timers.total_s);   // optional, see record_compute
//     pacer.wait_next();                        // ends the tick, waits, starts the next
//   }
//   LoopStats stats = pacer.stats();
//
// The clock is injectable (PacerClock): tests drive a fake one and get exact,
// repeatable timing.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>

namespace terracut::haptics {

/// Time source and sleeper of a Pacer. The real one is steady_pacer_clock();
/// tests supply a fake whose time advances only when asked.
class PacerClock {
 public:
  virtual ~PacerClock() = default;
  /// Seconds on a monotonic clock (any origin).
  virtual double now_s() = 0;
  /// Blocks until now_s() >= t_s, or somewhat later (an OS sleep). Returns at
  /// once when t_s has passed.
  virtual void sleep_until(double t_s) = 0;
  /// One iteration of a busy-wait (a CPU pause instruction); a fake clock
  /// advances its time here so that a spin ends.
  virtual void relax() {}
};

/// The system's monotonic clock: CLOCK_MONOTONIC with clock_nanosleep
/// (TIMER_ABSTIME) on POSIX, std::chrono::steady_clock elsewhere. Shared and
/// stateless.
std::shared_ptr<PacerClock> steady_pacer_clock();

/// Pacer parameters; validated at construction, read-only while it runs.
struct PacerSettings {
  double rate_hz = 1000.0;  ///< ticks per second, Hz, in (0, 1e6]
  /// The last part of each wait spent busy-waiting instead of sleeping,
  /// seconds, in [0, 1 / rate_hz]. Longer gives more exact wake-ups and burns
  /// more CPU; 0 sleeps all the way. The default covers Linux's 50 us timer slack.
  double spin_s = 100e-6;
};

/// Returns an empty string when settings are valid, else a message naming the field.
std::string validate(const PacerSettings& settings);

/// Durations recorded into a fixed set of logarithmic bins (HDR-histogram
/// style): values are kept in nanoseconds, exact below 128 ns, then with 64
/// bins per power of two (1/64 relative resolution) up to 2^40 ns (about 18
/// minutes; longer values count in the last bin). Records in O(1) and never
/// allocates (the bins are part of the object, 18 KiB).
class DurationHistogram {
 public:
  /// Adds one duration, seconds (negative or NaN counts as 0).
  void record(double duration_s);
  /// Forgets everything recorded.
  void clear();

  std::int64_t count() const { return count_; }
  /// Largest duration recorded, seconds (exact); 0 when empty.
  double max_s() const { return count_ ? double(max_ns_) * 1e-9 : 0.0; }
  /// Mean duration, seconds (exact to the nanosecond rounding); 0 when empty.
  double mean_s() const { return count_ ? sum_ns_ / double(count_) * 1e-9 : 0.0; }
  /// The q-quantile, q in (0, 1], nearest rank, seconds: the upper edge of the
  /// bin holding the rank, capped at the maximum. Never below the true value,
  /// at most 1/64 above it. 0 when empty.
  double percentile_s(double q) const;

  /// Number of bins (for tests and sizing).
  static constexpr int kBins = 128 + 33 * 64;

 private:
  static int bin_of(std::uint64_t ns);
  static std::uint64_t upper_edge_ns(int bin);

  std::array<std::uint64_t, kBins> bins_{};
  std::int64_t count_ = 0;
  std::uint64_t max_ns_ = 0;
  double sum_ns_ = 0.0;
};

/// p50, p99 and maximum of one per-tick time, seconds.
struct TimeStats {
  double p50_s = 0.0;
  double p99_s = 0.0;
  double max_s = 0.0;
  double mean_s = 0.0;
  std::int64_t count = 0;  ///< samples behind the figures
};

/// What a Pacer saw since start() (or reset_stats()).
struct LoopStats {
  double rate_hz = 0.0;               ///< the nominal rate
  std::int64_t ticks = 0;             ///< ticks ended (calls to wait_next)
  /// Ticks whose work ran past the next tick's deadline (overruns).
  std::int64_t missed_deadlines = 0;
  /// Schedule slots dropped entirely after overruns (ticks that never ran).
  std::int64_t skipped_slots = 0;
  TimeStats compute;                  ///< compute time per tick
  /// |start - previous start - 1 / rate_hz| per tick after the first.
  TimeStats period_jitter;
  /// start - deadline (>= 0) per tick after the first: how late the wait woke.
  TimeStats wake_latency;
};

/// The start of a tick, as wait_next reports it.
struct Tick {
  std::int64_t index = 0;   ///< ticks started before this one (0 for the first)
  std::int64_t slot = 0;    ///< its slot on the schedule grid (index + slots skipped so far)
  double deadline_s = 0.0;  ///< scheduled start, clock seconds
  double start_s = 0.0;     ///< actual start, clock seconds
  double period_s = 0.0;    ///< start - previous tick's start, seconds
  /// The previous tick's work ran past this tick's deadline (this tick starts late).
  bool after_overrun = false;
};

/// Paces a loop at a fixed rate. Not thread-safe: one loop thread calls
/// start, record_compute and wait_next; stats may be read from that thread
/// (or after the loop has stopped). No call allocates or throws after
/// construction.
class Pacer {
 public:
  /// Throws terracut::InputError naming the bad field. clock: the time source,
  /// the system's monotonic clock when null.
  explicit Pacer(const PacerSettings& settings, std::shared_ptr<PacerClock> clock = nullptr);

  const PacerSettings& settings() const { return settings_; }
  /// The nominal period, seconds.
  double period_s() const { return period_s_; }

  /// Anchors the schedule at the clock's present time and starts tick 0 at
  /// once; clears the statistics. Calling it again restarts the schedule.
  Tick start();

  /// Sets the compute time of the current tick, seconds, e.g. the
  /// simulation's own step timer. Without it the tick's compute time is
  /// measured: from its start to the call of wait_next.
  void record_compute(double compute_s);

  /// Ends the current tick (records its compute time), waits for the next
  /// tick's deadline (sleep, then spin), starts it and returns it. After an
  /// overrun it returns at once (see the file comment). Calls before start()
  /// start the schedule.
  Tick wait_next();

  /// The caller holds its loop (a paused device, Device::paused): ends the
  /// current tick as wait_next does (its compute time up to now), and waits
  /// for no deadline until resume().
  void hold();
  /// After a hold: starts the next tick at once, the schedule re-anchored at
  /// the present time. The gap is no period of the loop: the tick's period_s
  /// is the nominal one, and no jitter, wake latency or missed deadline is
  /// recorded for it.
  Tick resume();

  /// The statistics so far.
  LoopStats stats() const;
  /// Clears the statistics; the schedule goes on.
  void reset_stats();

 private:
  PacerSettings settings_;
  /// Records the current tick's compute time and counts it; returns the time
  /// it ended.
  double end_tick();

  std::shared_ptr<PacerClock> clock_;
  double period_s_ = 0.0;
  bool started_ = false;
  bool held_ = false;          // between hold() and resume()
  double origin_s_ = 0.0;      // the schedule's t0
  Tick tick_{};                // the current tick
  double recorded_compute_s_ = -1.0;  // record_compute's value for the current tick, < 0 if none
  std::int64_t ticks_ = 0;
  std::int64_t missed_ = 0;
  std::int64_t skipped_ = 0;
  DurationHistogram compute_;
  DurationHistogram jitter_;
  DurationHistogram latency_;
};

}  // namespace terracut::haptics
