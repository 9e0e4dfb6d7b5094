// The link emulator: delay, jitter, loss (independent and Gilbert-Elliott),
// reordering and reliable delivery, with statistical tolerances from the
// sample size; determinism for a seed.
#include "terracut/net/emulator.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "terracut/core/error.hpp"

namespace terracut::net {
namespace {

constexpr int kN = 20000;
// Four standard deviations of a proportion p estimated from n draws.
double tolerance(double p, int n) { return 4.0 * std::sqrt(p * (1.0 - p) / n) + 1e-12; }

TEST(Emulator, DelayOnly) {
  LinkConditions c;
  c.delay_s = 0.05;
  LinkEmulator e(c);
  for (int i = 0; i < 100; ++i) {
    const auto t = e.schedule(i * 0.001, false);
    ASSERT_TRUE(t);
    EXPECT_DOUBLE_EQ(*t, i * 0.001 + 0.05);
  }
  EXPECT_EQ(e.counters().lost, 0);
}

TEST(Emulator, JitterStaysInItsBandAndReorders) {
  LinkConditions c;
  c.delay_s = 0.05;
  c.jitter_s = 0.005;
  LinkEmulator e(c);
  int overtaken = 0;
  double last = 0.0;
  for (int i = 0; i < kN; ++i) {
    const double now = i * 0.001;
    const double t = *e.schedule(now, false);
    EXPECT_GE(t - now, 0.045 - 1e-12);
    EXPECT_LE(t - now, 0.055 + 1e-12);
    if (t < last) ++overtaken;
    last = std::max(last, t);
  }
  // 10 ms of spread over 1 ms spacing: many datagrams arrive out of order.
  EXPECT_GT(overtaken, kN / 10);
}

TEST(Emulator, IndependentLossRate) {
  LinkConditions c;
  c.loss = 0.1;
  LinkEmulator e(c);
  int lost = 0;
  for (int i = 0; i < kN; ++i) lost += e.schedule(i * 0.001, false) ? 0 : 1;
  EXPECT_NEAR(double(lost) / kN, 0.1, tolerance(0.1, kN));
  EXPECT_EQ(e.counters().lost, lost);
}

TEST(Emulator, GilbertElliottLosesInBursts) {
  // Stationary bad-state probability p/(p+r) = 0.01/(0.01+0.2) = 4.76 %;
  // mean burst length 1/r = 5 datagrams.
  LinkConditions c;
  c.burst.p_good_to_bad = 0.01;
  c.burst.p_bad_to_good = 0.2;
  c.burst.loss_bad = 1.0;
  LinkEmulator e(c);
  const int n = 200000;
  int lost = 0, bursts = 0;
  bool previous = false;
  for (int i = 0; i < n; ++i) {
    const bool l = !e.schedule(i * 0.001, false);
    lost += l;
    if (l && !previous) ++bursts;
    previous = l;
  }
  const double pi_bad = 0.01 / 0.21;
  EXPECT_NEAR(double(lost) / n, pi_bad, 0.25 * pi_bad);
  const double mean_burst = double(lost) / bursts;
  EXPECT_NEAR(mean_burst, 5.0, 1.0);
}

TEST(Emulator, HeldBackDatagramsAreOvertaken) {
  LinkConditions c;
  c.delay_s = 0.01;
  c.reorder = 0.05;
  c.reorder_delay_s = 0.003;
  LinkEmulator e(c);
  int held = 0;
  for (int i = 0; i < kN; ++i) {
    const double now = i * 0.001;
    const double t = *e.schedule(now, false);
    if (t - now > 0.01 + 1e-9) {
      ++held;
      EXPECT_NEAR(t - now, 0.013, 1e-9);
    }
  }
  EXPECT_NEAR(double(held) / kN, 0.05, tolerance(0.05, kN));
}

TEST(Emulator, ReliableIsNeverLostAndStaysInOrder) {
  LinkConditions c;
  c.delay_s = 0.02;
  c.jitter_s = 0.01;
  c.loss = 0.3;
  LinkEmulator e(c);
  double last = 0.0;
  int late = 0;
  for (int i = 0; i < 5000; ++i) {
    const auto t = e.schedule(i * 0.01, true);
    ASSERT_TRUE(t);
    EXPECT_GE(*t, last);
    // A loss costs a retransmission timeout of 2 x delay + 20 ms = 60 ms.
    if (*t - i * 0.01 > 0.03 + 0.06 - 1e-9) ++late;
    last = *t;
  }
  EXPECT_GT(e.counters().retransmits, 0);
  EXPECT_NEAR(double(e.counters().retransmits) / 5000, 0.3 / 0.7, 0.06);  // geometric mean
  EXPECT_GT(late, 0);
}

TEST(Emulator, SameSeedSameSchedule) {
  LinkConditions c;
  c.delay_s = 0.1;
  c.jitter_s = 0.02;
  c.loss = 0.05;
  c.reorder = 0.01;
  c.seed = 42;
  LinkEmulator a(c), b(c);
  c.seed = 43;
  LinkEmulator other(c);
  int differ = 0;
  for (int i = 0; i < 2000; ++i) {
    const auto x = a.schedule(i * 0.001, false);
    const auto y = b.schedule(i * 0.001, false);
    const auto z = other.schedule(i * 0.001, false);
    ASSERT_EQ(x.has_value(), y.has_value());
    if (x) {
      EXPECT_EQ(*x, *y);
    }
    if (x.has_value() != z.has_value() || (x && *x != *z)) ++differ;
  }
  EXPECT_GT(differ, 1000);
}

TEST(Emulator, BadConditionsNameTheField) {
  LinkConditions c;
  c.loss = 1.0;
  EXPECT_NE(validate(c).find("loss"), std::string::npos);
  c = {};
  c.delay_s = -1;
  EXPECT_NE(validate(c).find("delay_s"), std::string::npos);
  c = {};
  c.burst.p_bad_to_good = 0;
  EXPECT_NE(validate(c).find("burst.p_bad_to_good"), std::string::npos);
  c = {};
  c.jitter_s = std::nan("");
  EXPECT_THROW(LinkEmulator e(c), InputError);
}

}  // namespace
}  // namespace terracut::net
