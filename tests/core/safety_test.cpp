// Tests of the safety limiter: every limit (clamp, rate, rise, watchdog,
// non-finite input), the counters, and a fixed-seed fuzz of the invariants
// (finite, within the maximum, growth within the rate).
#include "terracut/core/safety.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "terracut/core/error.hpp"

namespace terracut {
namespace {

constexpr double kT = 1e-3;  // 1 kHz loop
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// A limiter with only the limit under test active (the others out of reach).
SafetyParams only(double max_force = 1e9, double rate = 1e12, double rise = 0.0,
                  double timeout = 1e9, double ramp = 0.1) {
  SafetyParams p;
  p.max_force_n = max_force;
  p.max_force_rate_n_per_s = rate;
  p.rise_time_s = rise;
  p.watchdog_timeout_s = timeout;
  p.watchdog_ramp_s = ramp;
  return p;
}

TEST(Safety, DefaultsAreAFalconsAndValid) {
  SafetyParams p;
  EXPECT_TRUE(validate(p).empty());
  EXPECT_EQ(p.max_force_n, 8.0);
  EXPECT_EQ(p.watchdog_timeout_s, 0.05);
  EXPECT_GT(p.max_force_rate_n_per_s, 0.0);
  EXPECT_GT(p.rise_time_s, 0.0);
}

TEST(Safety, ValidateNamesTheField) {
  auto message = [](SafetyParams p) { return validate(p); };
  SafetyParams p;
  p.max_force_n = 0.0;
  EXPECT_NE(message(p).find("max_force_n"), std::string::npos);
  p = {};
  p.max_force_rate_n_per_s = -1.0;
  EXPECT_NE(message(p).find("max_force_rate_n_per_s"), std::string::npos);
  p = {};
  p.rise_time_s = kNaN;
  EXPECT_NE(message(p).find("rise_time_s"), std::string::npos);
  p = {};
  p.watchdog_timeout_s = 0.0;
  EXPECT_NE(message(p).find("watchdog_timeout_s"), std::string::npos);
  p = {};
  p.watchdog_ramp_s = kInf;
  EXPECT_NE(message(p).find("watchdog_ramp_s"), std::string::npos);
  EXPECT_THROW(SafetyLimiter{p}, InputError);
  p = {};
  p.rise_time_s = 0.0;  // zero rise and zero ramp are allowed (no soft start, cut at once)
  p.watchdog_ramp_s = 0.0;
  EXPECT_TRUE(validate(p).empty());
}

TEST(Safety, ClampsTheMagnitudeKeepingTheDirection) {
  SafetyLimiter s(only(8.0));
  Vec3 in{12.0, -9.0, 0.0};  // 15 N
  SafetyOutput out;
  for (int n = 0; n < 3; ++n) out = s.update(n * kT, in, n * kT);
  EXPECT_NEAR(length(out.force_n), 8.0, 1e-12);
  EXPECT_NEAR(out.force_n.x, 12.0 * 8.0 / 15.0, 1e-12);
  EXPECT_NEAR(out.force_n.y, -9.0 * 8.0 / 15.0, 1e-12);
  EXPECT_TRUE(out.flags.clamped);
  EXPECT_EQ(s.counters().clamped, 3);
  // Below the maximum: untouched.
  out = s.update(3 * kT, {1.0, 2.0, 3.0}, 3 * kT);
  EXPECT_FALSE(out.flags.clamped);
  EXPECT_EQ(out.force_n.z, 3.0);
}

TEST(Safety, RateLimitsGrowthButNotRelease) {
  SafetyLimiter s(only(8.0, 1000.0));  // 1 N per 1 ms sample
  s.update(0.0, {}, 0.0);
  // A 5 N step builds up 1 N per sample.
  for (int n = 1; n <= 5; ++n) {
    SafetyOutput out = s.update(n * kT, {5.0, 0.0, 0.0}, n * kT);
    EXPECT_NEAR(out.force_n.x, double(n), 1e-9) << n;
    EXPECT_EQ(out.flags.rate_limited, n < 5) << n;
  }
  EXPECT_EQ(s.counters().rate_limited, 4);
  // Release to zero: at once.
  SafetyOutput out = s.update(6 * kT, {}, 6 * kT);
  EXPECT_EQ(length(out.force_n), 0.0);
  EXPECT_FALSE(out.flags.rate_limited);
  // Back to 5 N, then a reversal to -5 N: the positive part drops at once,
  // the negative one grows at the rate.
  for (int n = 7; n <= 12; ++n) s.update(n * kT, {5.0, 0.0, 0.0}, n * kT);
  EXPECT_NEAR(s.last_force_n().x, 5.0, 1e-9);
  out = s.update(13 * kT, {-5.0, 0.0, 0.0}, 13 * kT);
  EXPECT_NEAR(out.force_n.x, -1.0, 1e-9);
  EXPECT_TRUE(out.flags.rate_limited);
  // A turn of 90 degrees at constant magnitude: the change is limited.
  for (int n = 14; n <= 30; ++n) s.update(n * kT, {0.0, 0.0, 4.0}, n * kT);
  out = s.update(31 * kT, {0.0, 4.0, 0.0}, 31 * kT);
  EXPECT_TRUE(out.flags.rate_limited);
  EXPECT_NEAR(out.force_n.y, 1.0, 1e-9);
  EXPECT_NEAR(out.force_n.z, 0.0, 1e-9);  // the old direction released
  // Time standing still (or stepping back) allows no growth.
  SafetyLimiter t(only(8.0, 1000.0));
  t.update(0.0, {}, 0.0);
  t.update(0.010, {3.0, 0.0, 0.0}, 0.010);
  EXPECT_NEAR(t.last_force_n().x, 3.0, 1e-9);  // 10 ms allow 10 N
  EXPECT_NEAR(t.update(0.010, {6.0, 0.0, 0.0}, 0.010).force_n.x, 3.0, 1e-9);
  EXPECT_NEAR(t.update(0.005, {6.0, 0.0, 0.0}, 0.010).force_n.x, 3.0, 1e-9);
}

TEST(Safety, SoftStartRisesOverTheRiseTime) {
  SafetyLimiter s(only(8.0, 1e12, 0.5));
  s.restart(1.0);
  EXPECT_EQ(s.counters().restarts, 1);
  for (int n = 0; n <= 600; n += 50) {
    double t = 1.0 + n * kT;
    SafetyOutput out = s.update(t, {0.0, 4.0, 0.0}, t);
    double gain = std::min(1.0, n * kT / 0.5);
    EXPECT_NEAR(out.gain, gain, 1e-12) << n;
    EXPECT_NEAR(out.force_n.y, 4.0 * gain, 1e-9) << n;
    EXPECT_EQ(out.flags.ramping, gain < 1.0) << n;
  }
  // A restart (e.g. the device reconnected) ramps again from zero.
  s.restart(2.0);
  EXPECT_EQ(s.counters().restarts, 2);
  SafetyOutput out = s.update(2.1, {0.0, 4.0, 0.0}, 2.1);
  EXPECT_NEAR(out.force_n.y, 4.0 * 0.2, 1e-9);
  EXPECT_TRUE(out.flags.ramping);
  // Without start() the first update starts the ramp.
  SafetyLimiter u(only(8.0, 1e12, 0.5));
  EXPECT_EQ(length(u.update(3.0, {1.0, 0.0, 0.0}, 3.0).force_n), 0.0);
  EXPECT_NEAR(u.update(3.25, {1.0, 0.0, 0.0}, 3.25).force_n.x, 0.5, 1e-9);
  EXPECT_EQ(u.counters().restarts, 1);
}

TEST(Safety, WatchdogRampsASilentDeviceToZeroAndSoftStartsOnReturn) {
  SafetyParams p = only(8.0, 1e12, 0.2, 0.05, 0.1);
  SafetyLimiter s(p);
  s.restart(0.0);
  // Run 0.5 s with a live device: 4 N out.
  int n = 0;
  for (; n <= 500; ++n) s.update(n * kT, {4.0, 0.0, 0.0}, n * kT);
  EXPECT_NEAR(s.last_force_n().x, 4.0, 1e-9);
  // The device falls silent after a sample stamped 0.5005 s (between loop
  // samples, so no comparison is a tie). Up to 50 ms later: normal.
  const double last_seen = 0.5005;
  for (; n <= 550; ++n) {
    SafetyOutput out = s.update(n * kT, {4.0, 0.0, 0.0}, last_seen);
    EXPECT_FALSE(out.flags.watchdog) << n;
    EXPECT_NEAR(out.force_n.x, 4.0, 1e-9);
  }
  // Beyond 50 ms: tripped; the 4 N fade linearly to zero over 100 ms.
  for (; n <= 700; ++n) {
    double t = n * kT;
    SafetyOutput out = s.update(t, {4.0, 0.0, 0.0}, last_seen);
    EXPECT_TRUE(out.flags.watchdog) << n;
    double fade = std::max(0.0, 1.0 - (t - 0.551) / 0.1);
    EXPECT_NEAR(out.force_n.x, 4.0 * fade, 1e-9) << n;
  }
  EXPECT_TRUE(s.watchdog_active());
  EXPECT_EQ(s.counters().watchdog_trips, 1);
  EXPECT_EQ(s.counters().watchdog, 150);
  EXPECT_EQ(length(s.last_force_n()), 0.0);
  // The device is heard again: a soft start from zero.
  SafetyOutput back = s.update(0.701, {4.0, 0.0, 0.0}, 0.701);
  EXPECT_FALSE(s.watchdog_active());
  EXPECT_FALSE(back.flags.watchdog);
  EXPECT_TRUE(back.flags.ramping);
  EXPECT_EQ(back.force_n.x, 0.0);
  EXPECT_EQ(s.counters().restarts, 2);
  SafetyOutput later = s.update(0.801, {4.0, 0.0, 0.0}, 0.801);
  EXPECT_NEAR(later.force_n.x, 4.0 * 0.5, 1e-9);
  // A zero ramp cuts at once; a non-finite device time counts as silence.
  SafetyLimiter c(only(8.0, 1e12, 0.0, 0.05, 0.0));
  c.update(0.0, {2.0, 0.0, 0.0}, 0.0);
  EXPECT_EQ(c.update(0.001, {2.0, 0.0, 0.0}, kNaN).force_n.x, 0.0);
  EXPECT_TRUE(c.watchdog_active());
}

TEST(Safety, NonFiniteInputGivesZeroAndAWarning) {
  SafetyLimiter s(only(8.0, 1000.0));
  for (int n = 0; n <= 10; ++n) s.update(n * kT, {3.0, 0.0, 0.0}, n * kT);
  ASSERT_NEAR(s.last_force_n().x, 3.0, 1e-9);
  int n = 11;
  for (Vec3 bad : {Vec3{kNaN, 0.0, 0.0}, Vec3{0.0, kInf, 0.0}, Vec3{0.0, 0.0, -kInf}}) {
    SafetyOutput out = s.update(n * kT, bad, n * kT);
    ++n;
    EXPECT_TRUE(out.flags.nonfinite);
    EXPECT_EQ(length(out.force_n), 0.0);
  }
  SafetyOutput t = s.update(kNaN, {1.0, 0.0, 0.0}, 0.0);
  EXPECT_TRUE(t.flags.nonfinite);
  EXPECT_EQ(length(t.force_n), 0.0);
  EXPECT_EQ(s.counters().nonfinite, 4);
  // Afterwards the force is rebuilt from zero at the rate, not stepped back.
  SafetyOutput next = s.update(n * kT, {3.0, 0.0, 0.0}, n * kT);
  EXPECT_FALSE(next.flags.nonfinite);
  EXPECT_NEAR(next.force_n.x, 1.0, 1e-9);
  EXPECT_EQ(s.counters().samples, n + 2);  // samples 0..n-1, the NaN time, and `next`
}

// Invariants over random inputs: finite, within the maximum, and never more
// than rate * dt away from the segment between zero and the previous output.
TEST(Safety, FuzzKeepsTheInvariants) {
  SafetyParams p;  // the defaults
  SafetyLimiter s(p);
  std::mt19937 rng(1234);
  std::uniform_real_distribution<double> comp(-30.0, 30.0), u01(0.0, 1.0);
  double t = 0.0, device_t = 0.0;
  for (int n = 0; n < 200000; ++n) {
    t += u01(rng) < 0.01 ? 0.02 * u01(rng) : kT;  // occasional late samples
    // The device misses a sample now and then, and is silent for 1000
    // samples out of every 20000.
    bool long_silence = n % 20000 >= 19000;
    if (!long_silence && u01(rng) < 0.995) device_t = t;
    Vec3 f{comp(rng), comp(rng), comp(rng)};
    double r = u01(rng);
    if (r < 0.001) {
      f.x = kNaN;
    } else if (r < 0.002) {
      f.y = kInf;
    } else if (r < 0.3) {
      f = f * 0.1;
    }
    SafetyOutput out = s.update(t, f, device_t);
    ASSERT_TRUE(is_finite(out.force_n)) << n;
    ASSERT_LE(length(out.force_n), p.max_force_n * (1.0 + 1e-12)) << n;
    ASSERT_GE(out.gain, 0.0);
    ASSERT_LE(out.gain, 1.0);
  }
  const SafetyCounters& c = s.counters();
  EXPECT_EQ(c.samples, 200000);
  EXPECT_GT(c.nonfinite, 100);
  EXPECT_GT(c.clamped, 1000);
  EXPECT_GT(c.rate_limited, 1000);
  EXPECT_GE(c.watchdog_trips, 10);  // one per long silence at least
  // The implicit start, and one per return of the device.
  EXPECT_EQ(c.restarts, 1 + c.watchdog_trips - (s.watchdog_active() ? 1 : 0));
}

TEST(Safety, GrowthNeverExceedsTheRate) {
  SafetyParams p = only(8.0, 1000.0, 0.0);
  SafetyLimiter s(p);
  std::mt19937 rng(99);
  std::uniform_real_distribution<double> comp(-10.0, 10.0), u01(0.0, 1.0);
  double t = 0.0;
  Vec3 prev{};
  s.update(t, {}, t);
  for (int n = 0; n < 100000; ++n) {
    double t_prev = t;
    t += u01(rng) < 0.05 ? 5 * kT * u01(rng) : kT;
    double dt = t - t_prev;  // the elapsed time as the limiter sees it
    Vec3 target = u01(rng) < 0.1 ? Vec3{} : Vec3{comp(rng), comp(rng), comp(rng)};
    Vec3 out = s.update(t, target, t).force_n;
    // Distance from the segment [0, prev] is at most rate * dt.
    double pp = dot(prev, prev);
    double k = pp > 0.0 ? std::clamp(dot(out, prev) / pp, 0.0, 1.0) : 0.0;
    // Rounding: a few ulps of forces of ~10 N.
    ASSERT_LE(length(out - prev * k), p.max_force_rate_n_per_s * dt + 1e-13)
        << n << " excess " << length(out - prev * k) - p.max_force_rate_n_per_s * dt;
    prev = out;
  }
}

}  // namespace
}  // namespace terracut
