// The UDP carrier of the teleoperation link, over ENet (Debian libenet-dev,
// 1.3: IPv4): one UDP port, channel 0 unreliable sequenced (commands,
// measurements), channel 1 reliable (patches, estimates), channel 2
// reliable (the handshake and the end of a session). The remote station
// listens; the operator station connects. No emulation here: the link
// emulator is a decorator in front of it (emulated_link.hpp).
//
// Sessions are authenticated (secure.hpp): after ENet's connection the
// operator sends HELLO, the remote answers WELCOME, and every datagram after
// that is sealed (ChaCha20-Poly1305, a replay window). The remote serves one
// operator per session:
//  - a peer that fails the handshake (another key, forged bytes, the other
//    mode, nothing in handshake_timeout_s) is refused, counted by reason and
//    disconnected at once; it never changes the session;
//  - a peer becomes the session's only after its first sealed datagram
//    opened (it holds the keys, not just a recorded HELLO);
//  - the same operator (its id, authenticated in the HELLO) connecting again
//    after a drop resumes the session;
//  - another operator is refused ("busy") while the session's operator is
//    connected and was heard within takeover_silence_s.
// The operator reconnects by itself when ENet declares its peer lost.
//
// Floods: a socket filter drops empty datagrams (at one, ENet stops reading
// the socket) and cuts oversize ones to ENet's largest (which ENet would
// report as a receive error); every datagram ENet reads passes terracut's
// intercept first, which drops and counts what comes from no peer and asks
// for no connection. The kernel's drops for the socket (receive buffer full;
// the filtered empty datagrams) are read back (SO_MEMINFO: the counter
// SO_RXQ_OVFL reports). A receive() drains the socket in passes of up to 256
// datagrams until it is empty or its time budget is spent, so the station's
// tick stays bounded under a flood and the rest waits in a receive buffer
// sized for it.
//
// Held datagrams live in pooled queues; ENet itself allocates each packet it
// sends and receives (enet_packet_create, through its malloc), which this
// side cannot avoid.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "terracut/net/secure.hpp"
#include "terracut/net/transport.hpp"

namespace terracut::net {

/// Why a peer was refused (the remote's counts; the operator hears the
/// reason in ENet's disconnection).
enum class Refusal : std::uint8_t {
  kBadKey = 1,        ///< the handshake or its first sealed datagram did not verify: another key, or forged
  kInsecureMismatch,  ///< one side runs --insecure-loopback, the other has a key
  kMalformed,         ///< not this protocol's handshake
  kBusy,              ///< another operator's session is live
  kTimeout,           ///< no handshake within handshake_timeout_s
};
inline constexpr std::size_t kRefusalCount = 6;  // index = value; [0] unused
/// "bad_key", "insecure_mismatch", "malformed", "busy", "timeout".
std::string_view to_string(Refusal reason);

struct EnetOptions {
  /// The pre-shared key (or insecure_key() for --insecure-loopback); one
  /// left at zeros is refused.
  LinkKey key;
  /// This station's id: the operator's identifies it across reconnections.
  std::uint32_t station_id = 0;
  /// Remote: a peer that has not authenticated this long after connecting
  /// is refused. Operator: how long it waits for the WELCOME before it
  /// connects again, s, (0, 60].
  double handshake_timeout_s = 2.0;
  /// ENet declares a peer lost after this long unheard, s, [1, 60].
  double peer_timeout_s = 3.0;
  /// Remote: another operator may open a session once the session's
  /// operator has been unheard this long (or disconnected), s.
  double takeover_silence_s = 3.0;
  /// The socket's receive buffer asked for, bytes (the kernel may give less).
  int receive_buffer_bytes = 8 << 20;
  /// Time a receive() may spend draining the socket past its first pass, s.
  double receive_budget_s = 0.0004;
};

/// What the carrier counted. Datagrams: UDP datagrams at the socket.
struct EnetCounters {
  std::int64_t datagrams = 0;               ///< read from the socket (ENet read them)
  std::int64_t dropped_unknown_source = 0;  ///< from no peer and no connection request: dropped before ENet
  std::int64_t dropped_oversize = 0;        ///< longer than ENet's largest: dropped before ENet
  /// Connection requests from new addresses, passed to ENet: those ENet did
  /// not accept (malformed) are connection_requests - connections.
  std::int64_t connection_requests = 0;
  /// Passed to ENet from the address of a connection ENet has not finished
  /// (no CONNECT event yet: a request ENet answered and waits on; a flood's
  /// random request may open one, and its junk then comes from a "peer"),
  /// and from peers connected but not authenticated (refused soon): what
  /// ENet does with them is its own, the count is terracut's.
  std::int64_t to_half_open = 0;
  std::int64_t to_unauthenticated = 0;
  /// The kernel's drops for the socket since it opened: receive buffer full,
  /// or an empty datagram (the socket filter drops those).
  std::int64_t kernel_dropped = 0;
  std::int64_t receive_errors = 0;  ///< enet_host_service errors
  std::int64_t budget_stops = 0;    ///< receive() calls that left datagrams for the next (budget spent)
  std::int64_t connections = 0;     ///< ENet connections accepted or made
  std::array<std::int64_t, kRefusalCount> refused{};  ///< peers refused, by Refusal
  std::int64_t sessions = 0;        ///< sessions opened (a new operator)
  std::int64_t resumed = 0;         ///< the session's operator authenticated again after a drop
  /// Sealed datagrams of the session refused, by AuthReject (bad_mac, replayed, ...).
  std::array<std::int64_t, kAuthRejectCount> rejected{};
  std::int64_t unauthenticated_packets = 0;  ///< ENet packets of peers not (yet) authenticated
  std::int64_t dropped_unconnected = 0;  ///< sent while no session: unreliable dropped, reliable past the queue's bound
  int receive_buffer_bytes = 0;     ///< the socket's receive buffer as the kernel set it
  std::int64_t refused_total() const;
};

class EnetEndpoint final : public Endpoint {
 public:
  /// The remote side: binds address:port (IPv4 text, port 0 = any free port).
  /// Throws InputError naming the address when it cannot be bound.
  static std::unique_ptr<EnetEndpoint> listen(const std::string& address, int port,
                                              const EnetOptions& options);
  /// The operator side: connects to address:port and authenticates (both
  /// complete while receive() is called). Throws InputError naming a bad address.
  static std::unique_ptr<EnetEndpoint> connect(const std::string& address, int port,
                                               const EnetOptions& options);
  ~EnetEndpoint() override;

  /// Seals and sends (a session is open), else: an unreliable datagram is
  /// dropped (counted), a reliable one waits for the session (up to a bound).
  void send(Channel channel, const std::uint8_t* data, std::size_t size, double now_s) override;
  /// Drains the socket (within the budget), handles connections and
  /// handshakes, hands over the session's opened datagrams, and sends what
  /// waits.
  void receive(double now_s, Inbox& out) override;
  using Endpoint::receive;
  void reserve_in_flight(std::size_t datagrams, std::size_t bytes) override;

  /// Tells the peer the session is over (sealed, reliable) and services the
  /// link up to wait_s for it to be delivered. Nothing when no session.
  void end_session(double wait_s);

  /// The bound UDP port (the operator's too: a free one the kernel chose).
  int port() const;
  /// True while an authenticated session's peer is connected.
  bool connected() const;
  /// True once the session's peer said the session is over.
  bool peer_ended() const;
  /// Operator: why the remote refused this station, if it did (then it
  /// does not connect again).
  std::optional<Refusal> refused_by_peer() const;
  /// The session's operator id (remote), or the remote's id (operator); 0 before one.
  std::uint32_t peer_id() const;
  const EnetCounters& counters() const;

  struct State;  // enet_transport.cpp

 private:
  explicit EnetEndpoint(std::unique_ptr<State> state);
  std::unique_ptr<State> s_;
};

}  // namespace terracut::net
