// The safety limiter's state machine (see safety.hpp for the order of the
// stages and docs/forces.md for the defaults).
#include "terracut/core/safety.hpp"

#include <algorithm>
#include <cmath>

#include "terracut/core/error.hpp"
#include "terracut/core/format.hpp"

namespace terracut {

namespace {

constexpr Range kRanges[] = {
    {"max_force_n", 0.0, kRangeMax, RangeEnds::kOpenLow},
    {"max_force_rate_n_per_s", 0.0, kRangeMax, RangeEnds::kOpenLow},
    {"rise_time_s", 0.0, kRangeMax, RangeEnds::kClosed},
    {"watchdog_timeout_s", 0.0, kRangeMax, RangeEnds::kOpenLow},
    {"watchdog_ramp_s", 0.0, kRangeMax, RangeEnds::kClosed},
};

std::string check(std::string_view field, double value) {
  return terracut::check(find_range(kRanges, field), value);
}

// The point of `target` reachable from `previous` in one sample: anything
// within `radius` of the segment from zero to `previous` (shrinking toward
// zero is free; growing or turning costs rate * dt).
Vec3 rate_limit(Vec3 previous, Vec3 target, double radius, bool& limited) {
  double pp = dot(previous, previous);
  double s = pp > 0.0 ? std::clamp(dot(target, previous) / pp, 0.0, 1.0) : 0.0;
  Vec3 base = previous * s;
  Vec3 step = target - base;
  double distance = length(step);
  if (distance <= radius) return target;
  limited = true;
  return base + step * (radius / distance);
}

}  // namespace

std::string validate(const SafetyParams& params) {
  if (auto m = check("max_force_n", params.max_force_n); !m.empty()) return m;
  if (auto m = check("max_force_rate_n_per_s", params.max_force_rate_n_per_s); !m.empty())
    return m;
  if (auto m = check("rise_time_s", params.rise_time_s); !m.empty()) return m;
  if (auto m = check("watchdog_timeout_s", params.watchdog_timeout_s); !m.empty()) return m;
  return check("watchdog_ramp_s", params.watchdog_ramp_s);
}

std::span<const Range> safety_ranges() { return kRanges; }

SafetyLimiter::SafetyLimiter(const SafetyParams& params) : params_(params) {
  if (auto m = validate(params); !m.empty()) throw InputError(m);
}

void SafetyLimiter::restart(double t_s) noexcept {
  started_ = true;
  start_t_s_ = t_s;
  last_output_ = {};
  ++counters_.restarts;
}

SafetyOutput SafetyLimiter::update(double t_s, Vec3 force_n,
                                   double last_device_sample_t_s) noexcept {
  SafetyOutput out;
  ++counters_.samples;

  // 1. Non-finite time or force: zero force and a warning; the rate limit
  // then rebuilds the force from zero. A finite time still advances the clock.
  bool time_ok = std::isfinite(t_s);
  double dt = 0.0;
  if (time_ok) {
    dt = has_time_ ? std::max(0.0, t_s - last_t_s_) : 0.0;
    last_t_s_ = has_time_ ? std::max(last_t_s_, t_s) : t_s;
    has_time_ = true;
  }
  if (!time_ok || !is_finite(force_n)) {
    out.flags.nonfinite = true;
    ++counters_.nonfinite;
    last_output_ = {};
    return out;
  }
  if (!started_) restart(t_s);

  Vec3 target;
  bool silent = !(t_s - last_device_sample_t_s <= params_.watchdog_timeout_s);
  if (silent) {
    // 2. Watchdog: fade the force held at the trip to zero.
    if (!watchdog_active_) {
      watchdog_active_ = true;
      trip_t_s_ = t_s;
      trip_force_n_ = last_output_;
      ++counters_.watchdog_trips;
    }
    double fade = params_.watchdog_ramp_s > 0.0
                      ? std::max(0.0, 1.0 - (t_s - trip_t_s_) / params_.watchdog_ramp_s)
                      : 0.0;
    target = trip_force_n_ * fade;
    out.gain = fade;
    out.flags.watchdog = true;
  } else {
    if (watchdog_active_) {
      // The device is heard again: a new soft start.
      watchdog_active_ = false;
      restart(t_s);
    }
    // 3. Magnitude clamp.
    double magnitude = length(force_n);
    if (magnitude > params_.max_force_n) {
      force_n = force_n * (params_.max_force_n / magnitude);
      out.flags.clamped = true;
    }
    // 4. Soft-start gain.
    double gain = params_.rise_time_s > 0.0
                      ? std::clamp((t_s - start_t_s_) / params_.rise_time_s, 0.0, 1.0)
                      : 1.0;
    out.flags.ramping = gain < 1.0;
    out.gain = gain;
    target = force_n * gain;
  }

  // 5. Rate limit against the previous output.
  Vec3 force =
      rate_limit(last_output_, target, params_.max_force_rate_n_per_s * dt, out.flags.rate_limited);

  // 6. Last check: finite and within the maximum.
  if (!is_finite(force)) {
    force = {};
    out.flags.nonfinite = true;
  } else if (double m = length(force); m > params_.max_force_n) {
    force = force * (params_.max_force_n / m);
  }
  out.force_n = force;
  last_output_ = force;

  counters_.clamped += out.flags.clamped;
  counters_.rate_limited += out.flags.rate_limited;
  counters_.ramping += out.flags.ramping;
  counters_.watchdog += out.flags.watchdog;
  counters_.nonfinite += out.flags.nonfinite;
  return out;
}

}  // namespace terracut
