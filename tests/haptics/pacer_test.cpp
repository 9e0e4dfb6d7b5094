// The pacer: an exact schedule on a fake clock, jitter and wake-up latency
// from scripted oversleeps, overruns counted and skipped without drift, the
// histogram's accuracy, no allocation per tick, and a short sanity run on the
// real clock (no timing thresholds).
#include "terracut/haptics/pacer.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <new>
#include <random>
#include <vector>

#include "terracut/core/error.hpp"

#include "../support/counting_new.hpp"

namespace terracut::haptics {
namespace {

// Histogram resolution: a percentile is never below the true value and at
// most 1/64 above it (plus the nanosecond rounding).
constexpr double kResolution = 1.0 / 64.0;

/// A clock whose time moves only when the test says so: work(s) is the
/// loop's compute, sleep_until jumps to the target plus a scripted oversleep
/// (cycled), relax() advances by relax_step_s (a spin iteration).
class FakeClock : public PacerClock {
 public:
  double t = 1000.0;
  double relax_step_s = 1e-6;
  std::vector<double> oversleep_s;
  long sleeps = 0;
  long relaxes = 0;

  double now_s() override { return t; }
  void sleep_until(double target) override {
    double extra = oversleep_s.empty() ? 0.0 : oversleep_s[size_t(sleeps) % oversleep_s.size()];
    ++sleeps;
    if (target > t) t = target + extra;
  }
  void relax() override {
    ++relaxes;
    t += relax_step_s;
  }
  void work(double s) { t += s; }
};

PacerSettings settings(double rate_hz, double spin_s) {
  PacerSettings s;
  s.rate_hz = rate_hz;
  s.spin_s = spin_s;
  return s;
}

// A percentile read from the histogram against the true value.
void expect_percentile(double got, double truth, const char* what) {
  EXPECT_GE(got, truth - 1e-9) << what;
  EXPECT_LE(got, truth * (1.0 + kResolution) + 1e-9) << what;
}

// With exact sleeps, every tick starts on its deadline: no jitter, no
// latency, no drift after many ticks, and the compute time is what the loop spent.
TEST(Pacer, ExactScheduleOnAFakeClock) {
  auto clock = std::make_shared<FakeClock>();
  Pacer pacer(settings(1000.0, 0.0), clock);
  Tick first = pacer.start();
  EXPECT_EQ(first.index, 0);
  EXPECT_EQ(first.start_s, 1000.0);
  Tick t{};
  for (int i = 0; i < 5000; ++i) {
    clock->work(0.3e-3);
    t = pacer.wait_next();
    ASSERT_EQ(t.index, i + 1);
    ASSERT_EQ(t.slot, i + 1);
    ASSERT_FALSE(t.after_overrun);
    ASSERT_EQ(t.start_s, t.deadline_s);
  }
  // Deadlines are computed from the origin, not accumulated.
  EXPECT_EQ(t.deadline_s, 1000.0 + 5000 * 1e-3);
  LoopStats s = pacer.stats();
  EXPECT_EQ(s.ticks, 5000);
  EXPECT_EQ(s.missed_deadlines, 0);
  EXPECT_EQ(s.skipped_slots, 0);
  EXPECT_EQ(s.compute.count, 5000);
  expect_percentile(s.compute.p50_s, 0.3e-3, "compute p50");
  expect_percentile(s.compute.p99_s, 0.3e-3, "compute p99");
  EXPECT_NEAR(s.compute.max_s, 0.3e-3, 1e-9);
  EXPECT_NEAR(s.compute.mean_s, 0.3e-3, 1e-9);
  EXPECT_LE(s.period_jitter.max_s, 1e-9);
  EXPECT_LE(s.wake_latency.max_s, 1e-9);
  EXPECT_EQ(s.rate_hz, 1000.0);
}

// After a hold (the loop's device paused) the next tick starts at once, the
// schedule moved to it: the gap counts as no period, no jitter, no latency
// and no missed deadline, and the ticks after it are on the new grid.
TEST(Pacer, ResumeAfterAHoldStartsANewGridWithoutCountingTheGap) {
  auto clock = std::make_shared<FakeClock>();
  Pacer pacer(settings(1000.0, 0.0), clock);
  pacer.start();
  for (int i = 0; i < 10; ++i) {
    clock->work(0.2e-3);
    pacer.wait_next();
  }
  clock->work(0.2e-3);
  pacer.hold();
  clock->work(3.2567);  // the hold
  const double now = clock->t;
  const Tick r = pacer.resume();
  EXPECT_EQ(r.index, 11);
  EXPECT_EQ(r.slot, 11);
  EXPECT_EQ(r.start_s, now);
  EXPECT_EQ(r.deadline_s, now);
  EXPECT_EQ(r.period_s, 1e-3);
  EXPECT_FALSE(r.after_overrun);
  Tick t{};
  for (int i = 0; i < 5; ++i) {
    clock->work(0.2e-3);
    t = pacer.wait_next();
    EXPECT_FALSE(t.after_overrun);
    EXPECT_NEAR(t.start_s, now + (i + 1) * 1e-3, 1e-9);
  }
  const LoopStats s = pacer.stats();
  EXPECT_EQ(s.ticks, 16);
  EXPECT_EQ(s.missed_deadlines, 0);
  EXPECT_EQ(s.skipped_slots, 0);
  EXPECT_LE(s.period_jitter.max_s, 1e-9);
  EXPECT_LE(s.wake_latency.max_s, 1e-9);
  // The tick before the hold keeps its own compute time, not the hold's.
  EXPECT_NEAR(s.compute.max_s, 0.2e-3, 1e-9);
}

// Sleeping without a spin wakes as late as the OS makes it; a spin longer
// than the oversleep absorbs it, to within one spin iteration.
TEST(Pacer, SpinAbsorbsOversleep) {
  for (double spin : {0.0, 100e-6}) {
    auto clock = std::make_shared<FakeClock>();
    clock->oversleep_s = {80e-6};
    Pacer pacer(settings(1000.0, spin), clock);
    pacer.start();
    for (int i = 0; i < 1000; ++i) {
      clock->work(0.3e-3);
      pacer.wait_next();
    }
    LoopStats s = pacer.stats();
    if (spin == 0.0) {
      // Every tick starts 80 us late; the periods are nominal except the first.
      expect_percentile(s.wake_latency.p50_s, 80e-6, "latency p50");
      EXPECT_NEAR(s.wake_latency.max_s, 80e-6, 1e-9);
      EXPECT_EQ(s.period_jitter.p50_s, 0.0);
      EXPECT_NEAR(s.period_jitter.max_s, 80e-6, 1e-9);
      EXPECT_EQ(clock->relaxes, 0);
    } else {
      // Woken 20 us early, the spin ends within a 1 us iteration of the deadline.
      EXPECT_LE(s.wake_latency.max_s, clock->relax_step_s + 1e-9);
      EXPECT_LE(s.period_jitter.max_s, clock->relax_step_s + 1e-9);
      EXPECT_GE(clock->relaxes, 1000 * 19);
    }
    EXPECT_EQ(s.missed_deadlines, 0);
  }
}

// One sleep in ten oversleeps by 200 us: that tick's period is 200 us long
// and the next one 200 us short, so 20 % of periods deviate by 200 us.
TEST(Pacer, JitterFromScriptedOversleeps) {
  auto clock = std::make_shared<FakeClock>();
  clock->oversleep_s = {0, 0, 0, 0, 0, 0, 0, 0, 0, 200e-6};
  Pacer pacer(settings(1000.0, 0.0), clock);
  pacer.start();
  for (int i = 0; i < 1000; ++i) {
    clock->work(0.25e-3);
    pacer.wait_next();
  }
  LoopStats s = pacer.stats();
  EXPECT_EQ(s.period_jitter.count, 1000);
  EXPECT_EQ(s.period_jitter.p50_s, 0.0);
  expect_percentile(s.period_jitter.p99_s, 200e-6, "jitter p99");
  EXPECT_NEAR(s.period_jitter.max_s, 200e-6, 1e-9);
  // 100 late ticks: the 90th percentile of latency is still 0, the 91st is not.
  EXPECT_EQ(s.wake_latency.p50_s, 0.0);
  expect_percentile(s.wake_latency.p99_s, 200e-6, "latency p99");
  EXPECT_EQ(s.missed_deadlines, 0);
}

// A tick whose work takes 2.5 periods misses its deadline: the next tick
// starts at once on the latest slot begun (one slot dropped), and the one
// after is back on the original grid.
TEST(Pacer, OverrunIsCountedAndTheGridKept) {
  auto clock = std::make_shared<FakeClock>();
  Pacer pacer(settings(1000.0, 0.0), clock);
  Tick t0 = pacer.start();
  std::vector<Tick> ticks;
  for (int i = 0; i < 20; ++i) {
    clock->work(i == 5 ? 2.5e-3 : 0.3e-3);
    ticks.push_back(pacer.wait_next());
  }
  // Tick 5 started at slot 5 and ended at 7.5 periods: tick 6 takes slot 7.
  const Tick& late = ticks[5];
  EXPECT_EQ(late.index, 6);
  EXPECT_TRUE(late.after_overrun);
  EXPECT_EQ(late.slot, 7);
  EXPECT_NEAR(late.start_s - t0.start_s, 7.5e-3, 1e-12);
  EXPECT_NEAR(late.start_s - late.deadline_s, 0.5e-3, 1e-12);
  const Tick& next = ticks[6];
  EXPECT_FALSE(next.after_overrun);
  EXPECT_EQ(next.slot, 8);
  EXPECT_EQ(next.start_s, t0.start_s + 8 * 1e-3);
  EXPECT_EQ(ticks.back().slot, 21);
  LoopStats s = pacer.stats();
  EXPECT_EQ(s.ticks, 20);
  EXPECT_EQ(s.missed_deadlines, 1);
  EXPECT_EQ(s.skipped_slots, 1);
  EXPECT_NEAR(s.compute.max_s, 2.5e-3, 1e-9);
  EXPECT_NEAR(s.wake_latency.max_s, 0.5e-3, 1e-9);
}

// A compute time given by the loop replaces the measured one for that tick only.
TEST(Pacer, RecordedComputeReplacesTheMeasuredOne) {
  auto clock = std::make_shared<FakeClock>();
  Pacer pacer(settings(500.0, 0.0), clock);
  pacer.start();
  for (int i = 0; i < 100; ++i) {
    clock->work(0.7e-3);
    if (i % 2 == 0) pacer.record_compute(0.1e-3);
    pacer.wait_next();
  }
  LoopStats s = pacer.stats();
  EXPECT_NEAR(s.compute.mean_s, 0.5 * (0.1e-3 + 0.7e-3), 1e-9);
  EXPECT_NEAR(s.compute.max_s, 0.7e-3, 1e-9);
  expect_percentile(s.compute.p50_s, 0.1e-3, "compute p50");
}

// wait_next before start starts the schedule; start again restarts it and
// clears the statistics.
TEST(Pacer, StartAndRestart) {
  auto clock = std::make_shared<FakeClock>();
  Pacer pacer(settings(1000.0, 0.0), clock);
  Tick first = pacer.wait_next();
  EXPECT_EQ(first.index, 0);
  clock->work(0.2e-3);
  pacer.wait_next();
  EXPECT_EQ(pacer.stats().ticks, 1);
  clock->work(5.0);
  Tick again = pacer.start();
  EXPECT_EQ(again.index, 0);
  EXPECT_EQ(again.start_s, clock->t);
  EXPECT_EQ(pacer.stats().ticks, 0);
  clock->work(0.2e-3);
  EXPECT_FALSE(pacer.wait_next().after_overrun);
}

// Bad settings are refused with the field's name.
TEST(Pacer, InvalidSettingsNameTheField) {
  auto message = [](PacerSettings s) -> std::string {
    try {
      Pacer pacer(s);
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(message(settings(0.0, 0.0)).find("pacer.rate_hz"), std::string::npos);
  EXPECT_NE(message(settings(NAN, 0.0)).find("pacer.rate_hz"), std::string::npos);
  EXPECT_NE(message(settings(2e6, 0.0)).find("pacer.rate_hz"), std::string::npos);
  EXPECT_NE(message(settings(1000.0, -1e-6)).find("pacer.spin_s"), std::string::npos);
  EXPECT_NE(message(settings(1000.0, 2e-3)).find("pacer.spin_s"), std::string::npos);
  EXPECT_EQ(message(settings(1000.0, 1e-3)), "");
  EXPECT_EQ(validate(PacerSettings{}), "");
}

// Percentiles from the histogram against exact ones on random durations
// spanning nanoseconds to seconds.
TEST(DurationHistogram, PercentilesWithinResolution) {
  std::mt19937 rng(64);
  std::uniform_real_distribution<double> exponent(-9.0, 0.5);
  DurationHistogram h;
  std::vector<double> ns;
  for (int i = 0; i < 20000; ++i) {
    double s = std::pow(10.0, exponent(rng));
    h.record(s);
    ns.push_back(std::floor(s * 1e9 + 0.5));
  }
  std::sort(ns.begin(), ns.end());
  for (double q : {0.001, 0.1, 0.5, 0.9, 0.99, 0.999, 1.0}) {
    size_t rank = size_t(std::ceil(q * double(ns.size())));
    double truth = ns[rank - 1] * 1e-9;
    double got = h.percentile_s(q);
    EXPECT_GE(got, truth) << "q=" << q;
    EXPECT_LE(got, truth * (1.0 + kResolution)) << "q=" << q;
  }
  EXPECT_EQ(h.max_s(), ns.back() * 1e-9);
  EXPECT_EQ(h.count(), 20000);
  h.clear();
  EXPECT_EQ(h.count(), 0);
  EXPECT_EQ(h.percentile_s(0.5), 0.0);
  // Small values are exact; negative and NaN count as zero.
  h.record(37e-9);
  h.record(-1.0);
  h.record(NAN);
  EXPECT_EQ(h.percentile_s(1.0), 37e-9);
  EXPECT_EQ(h.percentile_s(0.5), 0.0);
}

// Ticks allocate nothing: the histograms are fixed-size.
TEST(Pacer, TicksAllocateNothing) {
  auto clock = std::make_shared<FakeClock>();
  clock->oversleep_s = {0.0, 30e-6, 0.0, 2e-3};  // includes overruns
  Pacer pacer(settings(1000.0, 50e-6), clock);
  pacer.start();
  long before = g_allocations.load();
  for (int i = 0; i < 20000; ++i) {
    clock->work(i % 100 == 0 ? 1.7e-3 : 0.2e-3);
    if (i % 3 == 0) pacer.record_compute(0.1e-3);
    pacer.wait_next();
  }
  LoopStats s = pacer.stats();
  EXPECT_EQ(g_allocations.load() - before, 0);
  EXPECT_GT(s.missed_deadlines, 0);
}

// The real clock: a short run at 2 kHz. Only sanity is asserted (a busy
// machine may make any tick late): the schedule's invariants and ordered,
// non-negative figures.
TEST(Pacer, RealClockSanity) {
  Pacer pacer(settings(2000.0, 100e-6));
  Tick first = pacer.start();
  Tick previous = first;
  for (int i = 0; i < 40; ++i) {
    Tick t = pacer.wait_next();
    EXPECT_EQ(t.index, previous.index + 1);
    EXPECT_GT(t.slot, previous.slot);
    EXPECT_GE(t.start_s, t.deadline_s);
    EXPECT_GE(t.start_s, previous.start_s);
    EXPECT_NEAR(t.deadline_s, first.start_s + double(t.slot) * pacer.period_s(), 1e-9);
    previous = t;
  }
  LoopStats s = pacer.stats();
  EXPECT_EQ(s.ticks, 40);
  for (const TimeStats* t : {&s.compute, &s.period_jitter, &s.wake_latency}) {
    EXPECT_EQ(t->count, 40);
    EXPECT_GE(t->p50_s, 0.0);
    EXPECT_LE(t->p50_s, t->p99_s);
    EXPECT_LE(t->p99_s, t->max_s);
  }
  // The run took at least as long as its schedule says.
  EXPECT_GE(previous.start_s - first.start_s, double(previous.slot) * pacer.period_s() - 1e-9);
}

}  // namespace
}  // namespace terracut::haptics
