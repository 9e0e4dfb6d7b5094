// The transport between the two stations: an Endpoint sends datagrams on one
// of two channels and receives what has arrived. Two carriers, one emulator
// (emulator.hpp) at the sender of each:
//   - MemoryLink: two endpoints in one process, for a single-process run and
//     for tests; time is the stations' (simulated) time.
//   - EnetEndpoint (enet_transport.hpp): UDP through ENet, one port, a
//     reliable channel and an unreliable sequenced one; time is the wall clock.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <memory>
#include <vector>

#include "terracut/net/emulator.hpp"

namespace terracut::net {

enum class Channel : std::uint8_t {
  kUnreliable = 0,  ///< sequenced, may be lost: commands, measurements
  kReliable = 1,    ///< delivered once and in order: patches, estimates
};

/// Traffic counters of an endpoint (datagrams as handed to / by the carrier).
struct TrafficCounters {
  std::int64_t sent = 0;
  std::int64_t sent_bytes = 0;
  std::int64_t received = 0;
  std::int64_t received_bytes = 0;
};

class Endpoint {
 public:
  virtual ~Endpoint() = default;
  /// Sends a datagram at time now_s (s); the emulator decides when it arrives.
  virtual void send(Channel channel, const std::uint8_t* data, std::size_t size,
                    double now_s) = 0;
  /// Appends to out every datagram that has arrived by now_s, in arrival order.
  virtual void receive(double now_s, std::vector<std::vector<std::uint8_t>>& out) = 0;
  const TrafficCounters& traffic() const { return traffic_; }
  /// The emulator of this endpoint's sending direction.
  virtual const LinkEmulator& emulator() const = 0;

 protected:
  TrafficCounters traffic_{};
};

/// Two endpoints joined in memory. a_to_b: the conditions of what a sends.
class MemoryLink {
 public:
  /// Throws InputError naming the field of bad conditions.
  MemoryLink(const LinkConditions& a_to_b, const LinkConditions& b_to_a);
  ~MemoryLink();
  Endpoint& a();
  Endpoint& b();

 private:
  class Side;
  std::unique_ptr<Side> a_;
  std::unique_ptr<Side> b_;
};

}  // namespace terracut::net
