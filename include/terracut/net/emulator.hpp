// The network emulator of the teleoperation link: one direction of a link,
// at the sender. Linux `tc netem` is not available on the machines terracut
// is developed on, so the conditions are made in-process, the same way for
// the in-memory link of a single-process run and for the UDP (ENet) link of
// a two-process run: the sender asks the emulator when (and whether) a
// datagram arrives, and holds it until then (net::EmulatedEndpoint,
// emulated_link.hpp: a decorator in front of any transport).
//
// Per datagram, in this order (one seeded std::mt19937_64, so a run is
// reproducible):
//   - loss: independent (probability `loss`) or bursty: a Gilbert-Elliott
//     chain of two states, good and bad, stepped once per datagram, losing
//     with probability loss_good / loss_bad in each state;
//   - delay: one-way delay + a jitter uniform in [-jitter, +jitter] (never
//     below zero), so datagrams closer together than the jitter reorder;
//   - reordering: with probability `reorder` a datagram is held back a
//     further reorder_delay_s, so later ones overtake it.
// A reliable datagram is never lost: each loss costs it one retransmission
// timeout (retransmit_s) instead, and reliable datagrams arrive in the order
// they were sent (as over ENet's reliable channel).
#pragma once

#include <cstdint>
#include <optional>
#include <random>
#include <span>
#include <string>

#include "terracut/core/ranges.hpp"

namespace terracut::net {

/// Gilbert-Elliott bursty loss. Defaults: off (never bad).
struct GilbertElliott {
  double p_good_to_bad = 0.0;  ///< per datagram, [0, 1]
  double p_bad_to_good = 1.0;  ///< per datagram, (0, 1]
  double loss_good = 0.0;      ///< loss probability in the good state, [0, 1]
  double loss_bad = 1.0;       ///< loss probability in the bad state, [0, 1]
};

/// The conditions of one direction of a link.
struct LinkConditions {
  double delay_s = 0.0;          ///< one-way delay, s, [0, 10]
  double jitter_s = 0.0;         ///< half-width of the uniform jitter, s, [0, 10]
  double loss = 0.0;             ///< independent loss probability, [0, 1)
  GilbertElliott burst{};        ///< bursty loss, combined with `loss`
  double reorder = 0.0;          ///< probability a datagram is held back, [0, 1]
  double reorder_delay_s = 0.005;  ///< how long it is held back, s, [0, 10]
  /// Retransmission timeout of a lost reliable datagram, s, (0, 60];
  /// nullopt: the round trip and kRetransmitMargin_s (retransmit_timeout_s).
  std::optional<double> retransmit_s;
  std::uint64_t seed = 1;  ///< RNG seed
};

/// What a retransmission costs beyond the round trip, s (ENet's own timeout
/// adds about as much to its round-trip estimate).
inline constexpr double kRetransmitMargin_s = 0.02;
/// The retransmission timeout of a lost reliable datagram: c.retransmit_s
/// when set, else round_trip_s + kRetransmitMargin_s. The one rule, for
/// the emulator and for the buffers sized from it.
double retransmit_timeout_s(const LinkConditions& c, double round_trip_s);
/// The round trip these conditions make when the way back is alike: 2 x
/// delay_s, s (what a station assumes until it has measured one).
inline double emulated_round_trip_s(const LinkConditions& c) { return 2.0 * c.delay_s; }

/// Empty when valid, else a message naming the field ("delay_s must be ...").
std::string validate(const LinkConditions& c);
/// The ranges of LinkConditions' numbers, which validate() checks (core/ranges.hpp).
std::span<const Range> link_ranges();

/// Counters of one direction.
struct EmulatorCounters {
  std::int64_t datagrams = 0;    ///< scheduled
  std::int64_t lost = 0;         ///< unreliable datagrams dropped
  std::int64_t retransmits = 0;  ///< losses of reliable datagrams (each cost a timeout)
  int max_retransmits = 0;       ///< the most one reliable datagram needed (its delay: that x the timeout)
  std::int64_t held_back = 0;    ///< datagrams held back for reordering
};

class LinkEmulator {
 public:
  /// Throws InputError naming the field when the conditions are invalid.
  explicit LinkEmulator(const LinkConditions& conditions);

  /// When a datagram sent at now_s arrives, s; nullopt when it is lost
  /// (unreliable only).
  std::optional<double> schedule(double now_s, bool reliable) noexcept;

  const LinkConditions& conditions() const { return c_; }
  const EmulatorCounters& counters() const { return counters_; }
  /// The retransmission timeout a lost reliable datagram costs, s: from the
  /// measured round trip once there is one (set_round_trip_s), before that
  /// from the configured delay (emulated_round_trip_s).
  double retransmit_s() const { return retransmit_timeout_s(c_, round_trip_s_); }
  /// The round trip the station measured, s (>= 0; a non-finite value is ignored).
  void set_round_trip_s(double round_trip_s) noexcept;

 private:
  bool lose() noexcept;   // one loss draw (steps the Gilbert-Elliott chain)
  double uniform() noexcept;  // [0, 1)

  LinkConditions c_;
  double round_trip_s_ = 0.0;
  std::mt19937_64 rng_;
  bool bad_ = false;
  double last_reliable_s_ = 0.0;
  EmulatorCounters counters_{};
};

}  // namespace terracut::net
