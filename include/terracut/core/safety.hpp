// The safety limiter: the last stage before a force reaches a device held by
// a person. A small state machine, parameters apart from state; update() is
// called once per haptic sample, allocates nothing and never throws.
//
// Per sample, in this order:
//   1. non-finite time or force -> zero force, flag `nonfinite`, counted;
//   2. watchdog: no device sample for longer than watchdog_timeout_s -> the
//      force at that moment is ramped linearly to zero over watchdog_ramp_s
//      and held at zero until the device is heard again (flag `watchdog`);
//      when it is, a new soft start begins;
//   3. magnitude clamp to max_force_n (flag `clamped`);
//   4. soft start: the force is multiplied by a gain rising linearly from 0 to
//      1 over rise_time_s after the first sample, restart() or the watchdog's recovery
//      (flag `ramping` while the gain is below 1);
//   5. rate limit: the force may grow, or turn, by at most
//      max_force_rate_n_per_s * dt per sample; it may always shrink toward
//      zero at once (flag `rate_limited`);
//   6. a last check that the output is finite and within max_force_n.
// All limits have defaults that are safe for a Novint Falcon (8 N).
#pragma once

#include <cstdint>
#include <span>
#include <string>

#include "terracut/core/math.hpp"
#include "terracut/core/ranges.hpp"

namespace terracut {

/// Limits of the safety limiter; read-only during a run. Device units.
struct SafetyParams {
  /// Largest force magnitude sent to the device, N, finite, > 0. Default: the
  /// Novint Falcon's maximum, 8 N (CHAI3D's Novint Falcon device
  /// specification, cFalconDevice; www.chai3d.org).
  double max_force_n = 8.0;
  /// Largest growth of the force vector per second, N/s, finite, > 0. The
  /// default lets the full 8 N build up in 8 ms: above the rate of a hand
  /// pressing at 0.3 m/s into a 3000 N/m wall (900 N/s), below a step.
  double max_force_rate_n_per_s = 1000.0;
  /// Soft start: time for the force gain to rise from 0 to 1 after start,
  /// restart or the device's reconnection, seconds, finite, >= 0 (0: none).
  double rise_time_s = 1.0;
  /// Watchdog: the device is silent when its newest sample is older than
  /// this, seconds, finite, > 0. Default 50 ms (50 samples at 1 kHz).
  double watchdog_timeout_s = 0.05;
  /// Time to ramp the force to zero once the watchdog trips, seconds, finite,
  /// >= 0 (0: cut at once). Default 100 ms.
  double watchdog_ramp_s = 0.1;
};

/// Returns an empty string when params are valid, else a message naming the field.
std::string validate(const SafetyParams& params);
/// The ranges of SafetyParams' fields, which validate() checks (core/ranges.hpp).
std::span<const Range> safety_ranges();

/// What the limiter did to one sample (for a recorder to log).
struct SafetyFlags {
  bool clamped = false;       ///< the input force was above max_force_n
  bool rate_limited = false;  ///< the output was held back by the rate limit
  bool ramping = false;       ///< the soft-start gain was below 1
  bool watchdog = false;      ///< the device was silent; output ramped or zero
  bool nonfinite = false;     ///< non-finite time, input or output; output zero

  /// The flags as bits: clamped 1, rate_limited 2, ramping 4, watchdog 8, nonfinite 16.
  std::uint32_t bits() const {
    return (clamped ? 1u : 0u) | (rate_limited ? 2u : 0u) | (ramping ? 4u : 0u) |
           (watchdog ? 8u : 0u) | (nonfinite ? 16u : 0u);
  }
  bool any() const { return bits() != 0; }
};

/// One limited sample.
struct SafetyOutput {
  Vec3 force_n{};     ///< the force to send, N, |force| <= max_force_n, finite
  double gain = 0.0;  ///< soft-start gain in [0, 1] (watchdog: remaining fraction)
  SafetyFlags flags{};
};

/// Counts since construction (each flag counted per sample).
struct SafetyCounters {
  std::int64_t samples = 0;
  std::int64_t clamped = 0;
  std::int64_t rate_limited = 0;
  std::int64_t ramping = 0;
  std::int64_t watchdog = 0;        ///< samples answered by the watchdog
  std::int64_t watchdog_trips = 0;  ///< times the device went silent
  std::int64_t nonfinite = 0;       ///< warnings: non-finite time, input or output
  std::int64_t restarts = 0;        ///< soft starts begun (start, restart, reconnection)
};

/// The limiter's state machine.
class SafetyLimiter {
 public:
  /// Throws InputError naming the bad field.
  explicit SafetyLimiter(const SafetyParams& params = {});

  const SafetyParams& params() const { return params_; }
  const SafetyCounters& counters() const { return counters_; }

  /// Begins a soft start at time t_s (seconds): the gain restarts from 0 and
  /// the output from zero. Call at start and when a device reconnects. The
  /// first update() starts implicitly when restart() was not called.
  void restart(double t_s) noexcept;

  /// Limits one force. t_s: loop time, seconds, non-decreasing (a step back
  /// counts as no time passing). force_n: requested device force, N.
  /// last_device_sample_t_s: loop time of the newest device sample (pose)
  /// received; the watchdog compares it with t_s.
  SafetyOutput update(double t_s, Vec3 force_n, double last_device_sample_t_s) noexcept;

  /// Zeroes the output at once, outside update(): for a bad device sample,
  /// which the haptic loop answers with zero force even while the watchdog
  /// is fading an older force out. The next update() builds the force up
  /// from zero under the rate limit. Counts nothing (the caller counts why).
  void zero_output() noexcept { last_output_ = {}; }
  /// The last output force (zero before the first update).
  Vec3 last_force_n() const { return last_output_; }
  /// Whether the watchdog currently holds the device as silent.
  bool watchdog_active() const { return watchdog_active_; }

 private:
  SafetyParams params_;
  SafetyCounters counters_;
  bool started_ = false;
  double start_t_s_ = 0.0;  // soft start began here
  bool has_time_ = false;
  double last_t_s_ = 0.0;  // time of the previous sample
  Vec3 last_output_{};
  bool watchdog_active_ = false;
  double trip_t_s_ = 0.0;  // watchdog tripped here
  Vec3 trip_force_n_{};    // output at that moment
};

}  // namespace terracut
