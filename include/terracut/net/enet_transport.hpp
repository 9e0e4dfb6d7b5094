// The UDP carrier of the teleoperation link, over ENet (Debian libenet-dev,
// 1.3: IPv4): one UDP port, channel 0 unreliable sequenced (commands,
// measurements), channel 1 reliable (patches, estimates). The remote
// station listens; the operator station connects. What is sent goes through
// the sender's LinkEmulator first: a datagram is held until its emulated
// arrival time (on the wall clock the caller passes as now_s) and then handed
// to ENet, so the conditions add to what the real network does. The remote
// side serves one operator at a time: a new connection (a restarted
// operator) replaces the old one. Held datagrams live in a pooled queue;
// ENet itself allocates each packet it sends and receives (enet_packet_create,
// through its malloc), which this side cannot avoid.
#pragma once

#include <memory>
#include <string>

#include "terracut/net/transport.hpp"

namespace terracut::net {

class EnetEndpoint final : public Endpoint {
 public:
  /// The remote side: binds address:port (IPv4 text, port 0 = any free port).
  /// Throws InputError naming the address when it cannot be bound.
  static std::unique_ptr<EnetEndpoint> listen(const std::string& address, int port);
  /// The operator side: connects to address:port (the connection completes
  /// while receive() is called). Throws InputError naming a bad address.
  static std::unique_ptr<EnetEndpoint> connect(const std::string& address, int port);
  ~EnetEndpoint() override;

  void send(Channel channel, const std::uint8_t* data, std::size_t size, double now_s) override;
  /// Services ENet (without waiting), hands over what arrived and sends what
  /// the emulator has released by now_s.
  void receive(double now_s, Inbox& out) override;
  using Endpoint::receive;
  void reserve_in_flight(std::size_t datagrams, std::size_t bytes) override;

  /// The bound UDP port.
  int port() const;
  /// True while a peer is connected.
  bool connected() const;
  /// Connections accepted or made (a restarted peer counts again).
  std::int64_t connections() const;
  /// Datagrams released while no peer was connected (unreliable: dropped).
  std::int64_t dropped_unconnected() const;

 private:
  struct State;
  explicit EnetEndpoint(std::unique_ptr<State> state);
  void release(double now_s);
  std::unique_ptr<State> s_;
};

}  // namespace terracut::net
