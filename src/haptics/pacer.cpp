#include "terracut/haptics/pacer.hpp"

#include <algorithm>
#include <bit>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <thread>

#if defined(__unix__) || defined(__APPLE__)
#include <time.h>
#endif
#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

#include "terracut/core/error.hpp"
#include "terracut/core/format.hpp"
#include "terracut/core/ranges.hpp"

namespace terracut::haptics {

namespace {

/// The system's monotonic clock.
class SteadyPacerClock final : public PacerClock {
 public:
  double now_s() override {
#if defined(CLOCK_MONOTONIC) && !defined(__APPLE__)
    timespec ts{};
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return double(ts.tv_sec) + double(ts.tv_nsec) * 1e-9;
#else
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
#endif
  }

  void sleep_until(double t_s) override {
#if defined(CLOCK_MONOTONIC) && !defined(__APPLE__)
    // An absolute deadline on the same clock as now_s: no drift from the
    // time spent between reading the clock and going to sleep.
    double whole = std::floor(t_s);
    timespec ts{};
    ts.tv_sec = time_t(whole);
    ts.tv_nsec = std::clamp(long((t_s - whole) * 1e9), 0L, 999999999L);
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
    }
#else
    auto since_epoch = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
        std::chrono::duration<double>(t_s));
    std::this_thread::sleep_until(std::chrono::steady_clock::time_point(since_epoch));
#endif
  }

  void relax() override {
#if defined(__x86_64__) || defined(__i386__)
    _mm_pause();
#elif defined(__aarch64__)
    asm volatile("yield");
#endif
  }
};

}  // namespace

std::shared_ptr<PacerClock> steady_pacer_clock() {
  static const std::shared_ptr<PacerClock> clock = std::make_shared<SteadyPacerClock>();
  return clock;
}

std::string validate(const PacerSettings& settings) {
  if (std::string e = check(kRateRange, settings.rate_hz, "pacer.rate_hz"); !e.empty()) return e;
  if (!(std::isfinite(settings.spin_s) && settings.spin_s >= 0.0 &&
        settings.spin_s <= 1.0 / settings.rate_hz))
    return must_be("pacer.spin_s",
                   "in [0, 1 / rate_hz] = [0, " + format_number(1.0 / settings.rate_hz) +
                       "] seconds",
                   settings.spin_s);
  return {};
}

// ---------------------------------------------------------------------------
// DurationHistogram: bins 0..127 hold 0..127 ns exactly; above, the power of
// two [2^m, 2^(m+1)) (m = 7 .. 39) is split into 64 equal bins.

int DurationHistogram::bin_of(std::uint64_t ns) {
  if (ns < 128) return int(ns);
  int m = int(std::bit_width(ns)) - 1;
  if (m > 39) return kBins - 1;
  int shift = m - 6;
  int sub = int(ns >> shift) - 64;
  return 128 + (m - 7) * 64 + sub;
}

std::uint64_t DurationHistogram::upper_edge_ns(int bin) {
  if (bin < 128) return std::uint64_t(bin);
  int k = bin - 128;
  int m = 7 + k / 64, sub = k % 64;
  int shift = m - 6;
  return (std::uint64_t(64 + sub + 1) << shift) - 1;
}

void DurationHistogram::record(double duration_s) {
  // Nanoseconds, rounded; negative and NaN count as 0, huge values saturate.
  double ns_d = duration_s * 1e9 + 0.5;
  std::uint64_t ns = ns_d >= 1.0 ? (ns_d < 4e18 ? std::uint64_t(ns_d) : std::uint64_t(4e18)) : 0;
  ++bins_[size_t(bin_of(ns))];
  ++count_;
  max_ns_ = std::max(max_ns_, ns);
  sum_ns_ += double(ns);
}

void DurationHistogram::clear() {
  bins_.fill(0);
  count_ = 0;
  max_ns_ = 0;
  sum_ns_ = 0.0;
}

double DurationHistogram::percentile_s(double q) const {
  if (count_ == 0) return 0.0;
  std::int64_t rank = std::clamp<std::int64_t>(std::int64_t(std::ceil(q * double(count_))), 1, count_);
  std::int64_t seen = 0;
  for (int b = 0; b < kBins; ++b) {
    seen += std::int64_t(bins_[size_t(b)]);
    if (seen >= rank) return double(std::min(upper_edge_ns(b), max_ns_)) * 1e-9;
  }
  return max_s();
}

// ---------------------------------------------------------------------------
// Pacer

namespace {

const PacerSettings& checked(const PacerSettings& settings) {
  if (std::string error = validate(settings); !error.empty()) throw InputError(error);
  return settings;
}

TimeStats time_stats(const DurationHistogram& h) {
  TimeStats s;
  s.p50_s = h.percentile_s(0.50);
  s.p99_s = h.percentile_s(0.99);
  s.max_s = h.max_s();
  s.mean_s = h.mean_s();
  s.count = h.count();
  return s;
}

}  // namespace

Pacer::Pacer(const PacerSettings& settings, std::shared_ptr<PacerClock> clock)
    : settings_(checked(settings)),
      clock_(clock ? std::move(clock) : steady_pacer_clock()),
      period_s_(1.0 / settings.rate_hz) {}

Tick Pacer::start() {
  double now = clock_->now_s();
  origin_s_ = now;
  tick_ = Tick{0, 0, now, now, period_s_, false};
  started_ = true;
  recorded_compute_s_ = -1.0;
  reset_stats();
  return tick_;
}

void Pacer::record_compute(double compute_s) { recorded_compute_s_ = compute_s >= 0.0 ? compute_s : 0.0; }

double Pacer::end_tick() {
  const double end = clock_->now_s();
  compute_.record(recorded_compute_s_ >= 0.0 ? recorded_compute_s_ : end - tick_.start_s);
  recorded_compute_s_ = -1.0;
  ++ticks_;
  return end;
}

void Pacer::hold() {
  if (!started_ || held_) return;
  end_tick();
  held_ = true;
}

Tick Pacer::resume() {
  if (!started_) return start();
  if (!held_) end_tick();
  held_ = false;
  // The next slot starts now: the grid moves so that its deadline is the
  // present time (and the slots of the pause are neither run nor skipped).
  const double now = clock_->now_s();
  const std::int64_t slot = tick_.slot + 1;
  origin_s_ = now - double(slot) * period_s_;
  tick_ = Tick{tick_.index + 1, slot, now, now, period_s_, false};
  return tick_;
}

Tick Pacer::wait_next() {
  if (!started_) return start();
  // End the current tick.
  double end = end_tick();

  std::int64_t slot = tick_.slot + 1;
  double deadline = origin_s_ + double(slot) * period_s_;
  double start;
  bool overrun = end > deadline;
  if (overrun) {
    // The work ran past this deadline: start at once, on the latest slot
    // that has begun, and drop the slots that passed entirely.
    ++missed_;
    std::int64_t latest = std::int64_t(std::floor((end - origin_s_) / period_s_));
    latest = std::max(latest, slot);
    while (origin_s_ + double(latest) * period_s_ > end && latest > slot) --latest;  // rounding
    skipped_ += latest - slot;
    slot = latest;
    deadline = origin_s_ + double(slot) * period_s_;
    start = end;
  } else {
    // Sleep to a little before the deadline, then spin to it.
    double wake = deadline - settings_.spin_s;
    if (end < wake) clock_->sleep_until(wake);
    double now = clock_->now_s();
    while (now < deadline) {
      clock_->relax();
      now = clock_->now_s();
    }
    start = now;
  }

  Tick next{tick_.index + 1, slot, deadline, start, start - tick_.start_s, overrun};
  jitter_.record(std::abs(next.period_s - period_s_));
  latency_.record(start - deadline);
  tick_ = next;
  return tick_;
}

LoopStats Pacer::stats() const {
  LoopStats s;
  s.rate_hz = settings_.rate_hz;
  s.ticks = ticks_;
  s.missed_deadlines = missed_;
  s.skipped_slots = skipped_;
  s.compute = time_stats(compute_);
  s.period_jitter = time_stats(jitter_);
  s.wake_latency = time_stats(latency_);
  return s;
}

void Pacer::reset_stats() {
  ticks_ = 0;
  missed_ = 0;
  skipped_ = 0;
  compute_.clear();
  jitter_.clear();
  latency_.clear();
}

}  // namespace terracut::haptics
