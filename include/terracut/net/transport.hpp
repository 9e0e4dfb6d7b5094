// The transport between the two stations: an Endpoint sends datagrams on one
// of two channels and receives what has arrived. Two carriers:
//   - MemoryLink: two endpoints in one process, for a single-process run and
//     for tests; time is the stations' (simulated) time.
//   - EnetEndpoint (enet_transport.hpp): UDP through ENet, one port, a
//     reliable channel and an unreliable sequenced one, authenticated and
//     encrypted (secure.hpp); time is the wall clock.
// The link emulator (emulated_link.hpp) is a decorator in front of either:
// an Endpoint that wraps an Endpoint.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

namespace terracut::net {

enum class Channel : std::uint8_t {
  kUnreliable = 0,  ///< sequenced, may be lost: commands, measurements
  kReliable = 1,    ///< delivered once and in order: patches, estimates
};

/// The datagrams one Endpoint::receive handed over, in arrival order. Its
/// buffers are kept by clear() and reused, so a steady stream allocates
/// nothing once each slot has held its largest datagram.
class Inbox {
 public:
  /// Room for `slots` datagrams of `bytes` each, made now.
  explicit Inbox(std::size_t slots = 0, std::size_t bytes = 0);
  void clear() noexcept { count_ = 0; }
  /// Appends a copy of data[0, size).
  void push(const std::uint8_t* data, std::size_t size);
  std::size_t size() const noexcept { return count_; }
  bool empty() const noexcept { return count_ == 0; }
  const std::vector<std::uint8_t>& operator[](std::size_t i) const { return slots_[i]; }
  auto begin() const { return slots_.begin(); }
  auto end() const { return slots_.begin() + std::ptrdiff_t(count_); }

 private:
  std::vector<std::vector<std::uint8_t>> slots_;
  std::size_t count_ = 0;
};

/// Datagrams held until a time (an emulated arrival or release), handed out
/// in time order, ties in the order they were held. The storage is pooled:
/// once the queue has held its working number of datagrams of their working
/// sizes, holding and popping allocate nothing.
class HeldQueue {
 public:
  /// Room for `slots` datagrams of `bytes` each, made now.
  explicit HeldQueue(std::size_t slots = 0, std::size_t bytes = 0);
  /// Adds room for `slots` more datagrams of `bytes` each, made now.
  void reserve(std::size_t slots, std::size_t bytes);
  /// Holds a copy of data[0, size) until at_s, with the caller's tag.
  void hold(double at_s, std::uint8_t tag, const std::uint8_t* data, std::size_t size);
  bool empty() const noexcept { return queue_.empty(); }
  std::size_t size() const noexcept { return queue_.size(); }
  /// The earliest datagram (not empty()).
  double front_s() const { return slots_[queue_.front()].at_s; }
  std::uint8_t front_tag() const { return slots_[queue_.front()].tag; }
  const std::vector<std::uint8_t>& front_bytes() const { return slots_[queue_.front()].bytes; }
  void pop();

 private:
  struct Slot {
    double at_s = 0.0;
    std::int64_t order = 0;
    std::uint8_t tag = 0;
    std::vector<std::uint8_t> bytes;
  };
  std::size_t take(std::size_t size);  // a free slot, best by capacity
  std::vector<Slot> slots_;
  std::vector<std::uint32_t> free_;   // slots not held
  std::vector<std::uint32_t> queue_;  // held slots, sorted by (at_s, order)
  std::int64_t next_order_ = 0;
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
  /// Appends to out every datagram that has arrived by now_s, in arrival
  /// order (reusing out's buffers: the loop's way).
  virtual void receive(double now_s, Inbox& out) = 0;
  /// The same into plain vectors (allocates; for tests and tools).
  void receive(double now_s, std::vector<std::vector<std::uint8_t>>& out);
  const TrafficCounters& traffic() const { return traffic_; }
  /// Makes room now for `datagrams` more datagrams of up to `bytes` each
  /// held in flight in this endpoint's sending direction (a station calls
  /// it for its working traffic, so that sending allocates nothing).
  /// The default does nothing (a carrier without a pool).
  virtual void reserve_in_flight(std::size_t /*datagrams*/, std::size_t /*bytes*/) {}
  /// The round trip the station measured, s: what a layer that needs the
  /// delay uses instead of a configured one (the emulator's retransmission
  /// timeout). The default does nothing.
  virtual void note_round_trip_s(double /*round_trip_s*/) noexcept {}

 protected:
  TrafficCounters traffic_{};
};

/// Two endpoints joined in memory: what one sends, the other receives at its
/// next receive(), in sending order (no delay, no loss: wrap each side in an
/// EmulatedEndpoint for those).
class MemoryLink {
 public:
  MemoryLink();
  ~MemoryLink();
  Endpoint& a();
  Endpoint& b();

 private:
  class Side;
  std::unique_ptr<Side> a_;
  std::unique_ptr<Side> b_;
};

}  // namespace terracut::net
