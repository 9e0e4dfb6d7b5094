// The link emulator in front of a transport: an Endpoint that wraps an
// Endpoint (a decorator), so the same emulated conditions apply to any
// carrier, the in-memory link of a single-process run and the UDP (ENet)
// link of a two-process run alike. What the station sends goes through the
// emulator (emulator.hpp: loss, delay, jitter, reordering, a reliable
// datagram's retransmissions) and waits in a pooled queue until its
// emulated arrival; then it is handed to the wrapped endpoint. What arrives
// passes through untouched.
#pragma once

#include <cstddef>
#include <cstdint>

#include "terracut/net/emulator.hpp"
#include "terracut/net/transport.hpp"

namespace terracut::net {

/// Whose time the emulator holds datagrams by.
enum class EmulatorClock {
  kCaller,  ///< the now_s the station passes (simulated time: the in-memory link)
  /// The wall clock (steady_clock), whatever now_s says: a real transport,
  /// where a station's tick times may lag the wall clock while it catches
  /// up, and a delay held in them would be shorter than the one emulated.
  kWall,
};

class EmulatedEndpoint final : public Endpoint {
 public:
  /// inner must outlive this endpoint. Throws InputError naming the field
  /// of bad conditions.
  EmulatedEndpoint(Endpoint& inner, const LinkConditions& sending,
                   EmulatorClock clock = EmulatorClock::kCaller);

  /// Asks the emulator when the datagram arrives (nothing more when it is
  /// lost), holds it until then, and hands the wrapped endpoint what is due.
  void send(Channel channel, const std::uint8_t* data, std::size_t size, double now_s) override;
  /// Hands on what is due by now_s, then receives from the wrapped endpoint.
  void receive(double now_s, Inbox& out) override;
  using Endpoint::receive;
  /// Hands the wrapped endpoint every held datagram due by now_s (the wall
  /// clock's now with EmulatorClock::kWall).
  void release(double now_s);
  /// Room in the held queue (and in the wrapped endpoint's).
  void reserve_in_flight(std::size_t datagrams, std::size_t bytes) override;
  /// The measured round trip sets the emulator's retransmission timeout
  /// (LinkEmulator::set_round_trip_s); passed on to the wrapped endpoint.
  void note_round_trip_s(double round_trip_s) noexcept override;

  const LinkEmulator& emulator() const { return emulator_; }
  Endpoint& inner() { return inner_; }
  const Endpoint& inner() const { return inner_; }

 private:
  double now(double now_s) const;
  Endpoint& inner_;
  LinkEmulator emulator_;
  EmulatorClock clock_;
  HeldQueue held_;  // tag: the Channel
};

/// Two endpoints in one process joined in memory (MemoryLink), each sending
/// through its emulator: the single-process run's link. Time is the
/// stations' (simulated) time.
class EmulatedLink {
 public:
  /// a_to_b: the conditions of what a sends. Throws InputError naming the
  /// field of bad conditions.
  EmulatedLink(const LinkConditions& a_to_b, const LinkConditions& b_to_a);
  EmulatedEndpoint& a() { return a_; }
  EmulatedEndpoint& b() { return b_; }
  /// Hands on what is due by now_s both ways: called before the stations'
  /// ticks of that time, so that a datagram arrives at its time whichever
  /// station ticks first.
  void release(double now_s);

 private:
  MemoryLink memory_;
  EmulatedEndpoint a_, b_;
};

}  // namespace terracut::net
