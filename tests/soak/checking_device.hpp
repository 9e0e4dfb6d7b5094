// The soak tests' helpers: resident memory, and the checker of the force a device receives (docs/reliability.md):
// a Device between a device and the haptic loop that sees every sample the
// loop reads and every command it writes, and checks the limiter's promises
// on each: the force limit, the rate limit, zero force on a non-finite
// sample, and the watchdog after the device falls silent. Used by the loop
// soak (soak.cpp) and the teleoperation soak (mmt_soak.cpp).
#pragma once

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <vector>

#include "terracut/core/safety.hpp"
#include "terracut/haptics/device.hpp"

namespace terracut::soak {

using haptics::Device;
using haptics::DeviceCommand;
using haptics::DeviceSample;

/// The process's resident memory, bytes (/proc/self/statm).
inline std::int64_t rss_bytes() {
  std::ifstream in("/proc/self/statm");
  std::int64_t pages = 0, resident = 0;
  in >> pages >> resident;
  return resident * std::int64_t(::sysconf(_SC_PAGESIZE));
}

// Runs on the loop's thread; read its figures after the loop has stopped.
class CheckingDevice final : public Device {
 public:
  CheckingDevice(Device& inner, const SafetyParams& safety, double rate_hz)
      : inner_(inner), safety_(safety), tick_s_(1.0 / rate_hz) {}

  std::string_view kind() const override { return inner_.kind(); }
  void start(double t_s) override { inner_.start(t_s); }
  void stop() noexcept override { inner_.stop(); }

  bool read(double t_s, DeviceSample& out) noexcept override {
    const bool got = inner_.read(t_s, out);
    sample_bad_ = false;
    if (got) {
      const bool finite = std::isfinite(out.position_m.x) && std::isfinite(out.position_m.y) &&
                          std::isfinite(out.position_m.z) &&
                          (!out.has_orientation ||
                           (std::isfinite(out.orientation.w) && std::isfinite(out.orientation.x) &&
                            std::isfinite(out.orientation.y) && std::isfinite(out.orientation.z)));
      if (!finite) {
        sample_bad_ = true;
        ++bad_samples;
      } else {
        silent_since_ = -1.0;
        last_good_t_s_ = t_s;
        has_good_ = true;
      }
    }
    return got;
  }

  void write(const DeviceCommand& c) noexcept override {
    inner_.write(c);
    ++writes;
    const Vec3 f = c.force_n;
    const double m = length(f);
    worst_force_n = std::max(worst_force_n, m);
    if (!(m <= safety_.max_force_n * (1 + 1e-12))) fail(c.t_s, "force above max_force_n");
    if (sample_bad_ && !(f.x == 0 && f.y == 0 && f.z == 0)) fail(c.t_s, "a non-finite sample got a force");
    if (has_previous_) {
      const double dt = c.t_s - previous_t_s_;
      // Distance from f to the segment [0, previous]: what the rate limit bounds.
      const double pp = dot(previous_, previous_);
      const double s = pp > 0 ? std::clamp(dot(f, previous_) / pp, 0.0, 1.0) : 0.0;
      const double away = length(f - previous_ * s);
      if (dt > 0) {
        worst_rate_n_per_s = std::max(worst_rate_n_per_s, away / dt);
        worst_change_n_per_s = std::max(worst_change_n_per_s, length(f - previous_) / dt);
      }
      if (!(away <= safety_.max_force_rate_n_per_s * std::max(dt, 0.0) * (1 + 1e-9) + 1e-12))
        fail(c.t_s, "force grew faster than max_force_rate_n_per_s");
    }
    previous_ = f;
    previous_t_s_ = c.t_s;
    has_previous_ = true;

    // The watchdog: a silence begins when the newest good sample is older
    // than a tick. The limiter trips at the first tick more than
    // watchdog_timeout_s after it (later than that when the loop itself ran
    // late and skipped ticks) and fades the force to zero over
    // watchdog_ramp_s from there (one tick of rounding allowed).
    if (has_good_ && c.t_s - last_good_t_s_ > 1.5 * tick_s_) {
      if (silent_since_ < 0.0) {
        silent_since_ = last_good_t_s_;
        tripped_ = false;
        waiting_zero_ = false;
      }
      const bool zero = f.x == 0 && f.y == 0 && f.z == 0;
      const double since = c.t_s - silent_since_;
      if (!tripped_ && since > safety_.watchdog_timeout_s) {  // the watchdog's moment
        tripped_ = true;
        trip_t_s_ = c.t_s;
        ++trips;
        worst_trip_delay_s = std::max(worst_trip_delay_s, since - safety_.watchdog_timeout_s);
        waiting_zero_ = !zero;  // a force to cut: time it
      }
      if (zero && waiting_zero_) {
        waiting_zero_ = false;
        latencies_s.push_back(since);
      }
      if (tripped_ && !zero && c.t_s - trip_t_s_ > safety_.watchdog_ramp_s + tick_s_) {
        char what[160];
        std::snprintf(what, sizeof what, "force %.3g N (flags %u) %.1f ms after the last sample, %.1f ms after the trip",
                      m, c.flags, since * 1e3, (c.t_s - trip_t_s_) * 1e3);
        fail(c.t_s, what);
      }
    }
  }

  void fail(double t_s, const char* what) noexcept {
    // (the loop thread: a message for the first few, then only counted)
    ++failures;
    if (failures <= 10) std::fprintf(stderr, "terracut-soak: t = %.3f s: %s\n", t_s, what);
  }

  /// The force of the newest command.
  Vec3 last_force() const { return previous_; }

  std::int64_t writes = 0;
  std::int64_t bad_samples = 0;
  std::int64_t failures = 0;
  std::int64_t trips = 0;             // silences longer than watchdog_timeout_s
  double worst_force_n = 0.0;
  double worst_rate_n_per_s = 0.0;    // away from [0, previous], per second
  double worst_change_n_per_s = 0.0;  // |change| per second, drops to zero included
  std::vector<double> latencies_s;    // last sample to zero force, per trip with a force to cut
  double worst_trip_delay_s = 0.0;    // trip later than watchdog_timeout_s (late ticks)

 private:
  Device& inner_;
  SafetyParams safety_;
  double tick_s_;
  bool sample_bad_ = false;
  bool has_good_ = false;
  double last_good_t_s_ = 0.0;
  double silent_since_ = -1.0;
  bool tripped_ = false;
  double trip_t_s_ = 0.0;
  bool waiting_zero_ = false;
  Vec3 previous_{};
  double previous_t_s_ = 0.0;
  bool has_previous_ = false;
};

}  // namespace terracut::soak
