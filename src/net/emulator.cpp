// The link emulator (emulator.hpp).
#include "terracut/net/emulator.hpp"

#include <algorithm>
#include <cmath>

#include "terracut/core/error.hpp"
#include "terracut/core/format.hpp"

namespace terracut::net {
namespace {

constexpr Range kRanges[] = {
    {"delay_s", 0.0, 10.0, RangeEnds::kClosed},
    {"jitter_s", 0.0, 10.0, RangeEnds::kClosed},
    {"loss", 0.0, 1.0, RangeEnds::kOpenHigh},
    {"burst.p_good_to_bad", 0.0, 1.0, RangeEnds::kClosed},
    {"burst.p_bad_to_good", 0.0, 1.0, RangeEnds::kOpenLow},
    {"burst.loss_good", 0.0, 1.0, RangeEnds::kClosed},
    {"burst.loss_bad", 0.0, 1.0, RangeEnds::kClosed},
    {"reorder", 0.0, 1.0, RangeEnds::kClosed},
    {"reorder_delay_s", 0.0, 10.0, RangeEnds::kClosed},
    {"retransmit_s", 0.0, 60.0, RangeEnds::kOpenLow},
};

std::string check(std::string_view field, double value) {
  return terracut::check(find_range(kRanges, field), value);
}

}  // namespace

std::string validate(const LinkConditions& c) {
  std::string m;
  if (!(m = check("delay_s", c.delay_s)).empty()) return m;
  if (!(m = check("jitter_s", c.jitter_s)).empty()) return m;
  if (!(m = check("loss", c.loss)).empty()) return m;
  if (!(m = check("burst.p_good_to_bad", c.burst.p_good_to_bad)).empty()) return m;
  if (!(m = check("burst.p_bad_to_good", c.burst.p_bad_to_good)).empty()) return m;
  if (!(m = check("burst.loss_good", c.burst.loss_good)).empty()) return m;
  if (!(m = check("burst.loss_bad", c.burst.loss_bad)).empty()) return m;
  if (!(m = check("reorder", c.reorder)).empty()) return m;
  if (!(m = check("reorder_delay_s", c.reorder_delay_s)).empty()) return m;
  if (c.retransmit_s && !(m = check("retransmit_s", *c.retransmit_s)).empty()) return m;
  return {};
}

std::span<const Range> link_ranges() { return kRanges; }

double retransmit_timeout_s(const LinkConditions& c, double round_trip_s) {
  return c.retransmit_s.value_or(round_trip_s + kRetransmitMargin_s);
}

LinkEmulator::LinkEmulator(const LinkConditions& conditions)
    : c_(conditions), round_trip_s_(emulated_round_trip_s(conditions)), rng_(conditions.seed) {
  if (const std::string problem = validate(c_); !problem.empty()) throw InputError(problem);
}

void LinkEmulator::set_round_trip_s(double round_trip_s) noexcept {
  if (std::isfinite(round_trip_s) && round_trip_s >= 0.0) round_trip_s_ = round_trip_s;
}

double LinkEmulator::uniform() noexcept {
  // 53 random bits: the same doubles from the same seed on every platform.
  return double(rng_() >> 11) * 0x1.0p-53;
}

bool LinkEmulator::lose() noexcept {
  // The chain moves first, then this datagram's fate is drawn in its state.
  if (c_.burst.p_good_to_bad > 0.0) {
    const double u = uniform();
    bad_ = bad_ ? !(u < c_.burst.p_bad_to_good) : (u < c_.burst.p_good_to_bad);
  }
  const double burst_loss = bad_ ? c_.burst.loss_bad : c_.burst.loss_good;
  const bool burst_lost = c_.burst.p_good_to_bad > 0.0 && uniform() < burst_loss;
  const bool independent_lost = c_.loss > 0.0 && uniform() < c_.loss;
  return burst_lost || independent_lost;
}

std::optional<double> LinkEmulator::schedule(double now_s, bool reliable) noexcept {
  ++counters_.datagrams;
  double extra_s = 0.0;
  if (reliable) {
    // Each loss costs one retransmission timeout (at most 50 in a row).
    int tries = 0;
    for (; tries < 50 && lose(); ++tries) {
      ++counters_.retransmits;
      extra_s += retransmit_s();
    }
    counters_.max_retransmits = std::max(counters_.max_retransmits, tries);
  } else if (lose()) {
    ++counters_.lost;
    return std::nullopt;
  }
  double delay = c_.delay_s;
  if (c_.jitter_s > 0.0) delay = std::max(0.0, delay + c_.jitter_s * (2.0 * uniform() - 1.0));
  if (c_.reorder > 0.0 && uniform() < c_.reorder) {
    ++counters_.held_back;
    delay += c_.reorder_delay_s;
  }
  double arrive = now_s + delay + extra_s;
  if (reliable) {
    arrive = std::max(arrive, last_reliable_s_);  // in order, as a reliable channel delivers
    last_reliable_s_ = arrive;
  }
  return arrive;
}

}  // namespace terracut::net
