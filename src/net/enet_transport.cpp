// The ENet carrier with authenticated sessions (enet_transport.hpp).
#include "terracut/net/enet_transport.hpp"

#include <enet/enet.h>
#include <linux/filter.h>
#include <linux/sock_diag.h>
#include <sys/socket.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include "terracut/core/error.hpp"

namespace terracut::net {
namespace {

// ENet's global initialisation, counted across endpoints.
std::mutex g_enet_mutex;
int g_enet_users = 0;

void enet_acquire() {
  std::lock_guard<std::mutex> lock(g_enet_mutex);
  if (g_enet_users == 0 && enet_initialize() != 0) throw InputError("ENet could not be initialised");
  ++g_enet_users;
}
void enet_release() {
  std::lock_guard<std::mutex> lock(g_enet_mutex);
  if (--g_enet_users == 0) enet_deinitialize();
}

ENetAddress make_address(const std::string& address, int port, const char* what) {
  if (port < 0 || port > 65535)
    throw InputError(std::string(what) + ": port must be in [0, 65535], got " +
                     std::to_string(port));
  ENetAddress a{};
  if (address.empty() || address == "0.0.0.0") {
    a.host = ENET_HOST_ANY;
  } else if (enet_address_set_host_ip(&a, address.c_str()) != 0) {
    throw InputError(std::string(what) + ": '" + address +
                     "' is not an IPv4 address (ENet 1.3 speaks IPv4 only)");
  }
  a.port = static_cast<enet_uint16>(port);
  return a;
}

constexpr std::size_t kChannels = 3;   // 0 unreliable, 1 reliable, 2 control (reliable)
constexpr std::uint8_t kControl = 2;
constexpr std::size_t kPeers = 16;     // remote: the session's peer and candidates
// The control channel's sealed messages (one byte).
constexpr std::uint8_t kControlConfirm = 1;  // operator: the handshake's keys work
constexpr std::uint8_t kControlEnd = 2;      // the session is over
// Reliable datagrams kept while no session is open; beyond, the oldest go.
constexpr std::size_t kPendingBound = 1024;
// ENet's largest datagram: the socket filter cuts longer ones to this.
constexpr std::size_t kLargestDatagram = ENET_PROTOCOL_MAXIMUM_MTU;
// How soon the operator connects again after losing its peer, s.
constexpr double kReconnectDelay_s = 0.25;

double wall_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// ENet's packet throttle drops unreliable packets itself while the round
// trip it measures varies more than usual, which the emulated jitter and a
// busy machine both cause: commands would be lost beyond the loss the link
// is set to. The throttle stays at its full scale (never decelerates), so
// the emulator alone decides what is lost. Set once connected.
void never_throttle(ENetPeer* peer) {
  enet_peer_throttle_configure(peer, ENET_PEER_PACKET_THROTTLE_INTERVAL,
                               ENET_PEER_PACKET_THROTTLE_SCALE, 0);
}

// An ENet connection request (the first datagram of a new peer): header with
// the unassigned peer id, then a CONNECT command.
bool connection_request(const std::uint8_t* data, std::size_t size) {
  if (size < 2) return false;
  const enet_uint16 first = ENET_NET_TO_HOST_16(*reinterpret_cast<const enet_uint16*>(data));
  if (first & ENET_PROTOCOL_HEADER_FLAG_COMPRESSED) return false;
  const std::size_t header = (first & ENET_PROTOCOL_HEADER_FLAG_SENT_TIME) ? sizeof(ENetProtocolHeader)
                                                                           : sizeof(enet_uint16);
  const enet_uint16 peer_id =
      first & ~(ENET_PROTOCOL_HEADER_FLAG_MASK | ENET_PROTOCOL_HEADER_SESSION_MASK);
  return peer_id == ENET_PROTOCOL_MAXIMUM_PEER_ID && size >= header + sizeof(ENetProtocolConnect) &&
         (data[header] & ENET_PROTOCOL_COMMAND_MASK) == ENET_PROTOCOL_COMMAND_CONNECT;
}

// The socket's receive buffer, and a filter that drops empty datagrams (at
// one, ENet's read loop stops as if the socket were empty) and cuts longer
// ones than ENet reads to its largest (ENet would report them as a receive
// error, to stderr). The filter sees the UDP header (8 bytes) and the payload.
int prepare_socket(ENetSocket fd, int buffer_bytes) {
  if (::setsockopt(fd, SOL_SOCKET, SO_RCVBUFFORCE, &buffer_bytes, sizeof buffer_bytes) != 0)
    (void)::setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &buffer_bytes, sizeof buffer_bytes);
  int got = 0;
  socklen_t len = sizeof got;
  (void)::getsockopt(fd, SOL_SOCKET, SO_RCVBUF, &got, &len);
  constexpr std::uint32_t kUdpHeader = 8;
  sock_filter code[] = {
      BPF_STMT(BPF_LD | BPF_W | BPF_LEN, 0),
      BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, kUdpHeader, 2, 0),                        // empty: drop
      BPF_JUMP(BPF_JMP | BPF_JGT | BPF_K, kUdpHeader + kLargestDatagram, 2, 0),     // too long: cut
      BPF_STMT(BPF_RET | BPF_K, 0xFFFFFFFFu),                                        // keep
      BPF_STMT(BPF_RET | BPF_K, 0),
      BPF_STMT(BPF_RET | BPF_K, kUdpHeader + kLargestDatagram),
  };
  sock_fprog program{static_cast<unsigned short>(sizeof code / sizeof code[0]), code};
  (void)::setsockopt(fd, SOL_SOCKET, SO_ATTACH_FILTER, &program, sizeof program);
  return got;
}

// The kernel's count of datagrams it dropped for the socket (u32, wraps).
std::optional<std::uint32_t> kernel_drops(ENetSocket fd) {
  std::uint32_t info[SK_MEMINFO_VARS] = {};
  socklen_t len = sizeof info;
  if (::getsockopt(fd, SOL_SOCKET, SO_MEMINFO, info, &len) != 0 || len < sizeof info) return std::nullopt;
  return info[SK_MEMINFO_DROPS];
}

}  // namespace

std::string_view to_string(Refusal reason) {
  switch (reason) {
    case Refusal::kBadKey: return "bad_key";
    case Refusal::kInsecureMismatch: return "insecure_mismatch";
    case Refusal::kMalformed: return "malformed";
    case Refusal::kBusy: return "busy";
    case Refusal::kTimeout: return "timeout";
  }
  return "unknown";
}

std::int64_t EnetCounters::refused_total() const {
  std::int64_t n = 0;
  for (std::int64_t r : refused) n += r;
  return n;
}

// A peer's progress: connected, answered (the remote sent WELCOME, or the
// operator sent HELLO), and the session's once its keys are proven.
struct PeerState {
  enum class Stage { kFree, kPending, kAnswered, kSession };
  Stage stage = Stage::kFree;
  ENetPeer* peer = nullptr;
  double deadline_s = 0.0;  // wall clock: refused (remote) or dropped (operator) if not past the handshake
  std::uint32_t operator_id = 0;
  std::optional<SecureChannel> channel;
  std::optional<HandshakeInitiator> initiator;  // operator
  void clear() {
    stage = Stage::kFree;
    peer = nullptr;
    deadline_s = 0.0;
    operator_id = 0;
    channel.reset();
    initiator.reset();
  }
};

struct EnetEndpoint::State {
  ~State() {
    if (host) enet_host_destroy(host);
    enet_release();
  }
  EnetOptions o;
  bool listener = false;
  ENetHost* host = nullptr;
  std::array<PeerState, kPeers> peers;
  int session = -1;            // the session's peer slot, -1 while none is connected
  bool has_session = false;    // a session was opened: its operator is known
  std::uint32_t session_operator = 0;
  std::uint32_t peer_id = 0;
  double last_heard_s = 0.0;   // wall clock, the session's last opened datagram
  bool peer_ended = false;      // the peer ended the session
  bool ended = false;           // this side ended it: no reconnection
  std::optional<Refusal> refused_by_peer;
  ENetAddress remote{};        // operator: where to connect
  double reconnect_at_s = -1.0;
  std::int64_t intercepted = 0;  // datagrams the intercept saw
  std::optional<std::uint32_t> drops_base, drops_last;
  std::int64_t drops_wrapped = 0;
  EnetCounters counters{};
  HeldQueue pending;  // reliable datagrams waiting for a session; tag: the Channel
  std::vector<std::uint8_t> sealed, opened;
  Inbox* out = nullptr;  // where receive() hands datagrams

  PeerState* slot_of(ENetPeer* p) { return static_cast<PeerState*>(p->data); }
  PeerState* take_slot(ENetPeer* p, double now) {
    for (PeerState& s : peers)
      if (s.stage == PeerState::Stage::kFree) {
        s.clear();
        s.stage = PeerState::Stage::kPending;
        s.peer = p;
        s.deadline_s = now + o.handshake_timeout_s;
        p->data = &s;
        return &s;
      }
    return nullptr;
  }
  void free_slot(PeerState& s) {
    if (s.peer) s.peer->data = nullptr;
    if (session >= 0 && &peers[std::size_t(session)] == &s) session = -1;
    s.clear();
  }
  void refuse(PeerState& s, Refusal why) {
    ++counters.refused[std::size_t(why)];
    ENetPeer* p = s.peer;
    free_slot(s);
    enet_peer_disconnect_now(p, enet_uint32(why));  // no event follows
  }
  void transmit(PeerState& s, std::uint8_t channel, const std::uint8_t* data, std::size_t size) {
    if (sealed.size() < size + kSealOverhead) sealed.resize(size + kSealOverhead);
    const std::size_t n = s.channel->seal(channel, data, size, sealed.data());
    const enet_uint32 flags = channel == std::uint8_t(Channel::kUnreliable) ? 0 : ENET_PACKET_FLAG_RELIABLE;
    ENetPacket* packet = enet_packet_create(sealed.data(), n, flags);
    if (packet && enet_peer_send(s.peer, channel, packet) != 0) enet_packet_destroy(packet);
  }
  PeerState* session_slot() {
    return session >= 0 ? &peers[std::size_t(session)] : nullptr;
  }
  void flush_pending() {
    PeerState* s = session_slot();
    while (s && !pending.empty()) {
      transmit(*s, pending.front_tag(), pending.front_bytes().data(), pending.front_bytes().size());
      pending.pop();
    }
  }
  // Another operator may not open a session while this one's is live.
  bool busy(std::uint32_t operator_id, double now) const {
    return has_session && operator_id != session_operator && session >= 0 &&
           now - last_heard_s <= o.takeover_silence_s;
  }
  // The peer proved its keys: it is the session's (the one before, if any, is dropped).
  void open_session(PeerState& s, double now) {
    const int index = int(&s - peers.data());
    if (session >= 0 && session != index) {
      PeerState& old = peers[std::size_t(session)];
      ENetPeer* p = old.peer;
      free_slot(old);
      enet_peer_reset(p);
    }
    if (has_session && s.operator_id == session_operator)
      ++counters.resumed;
    else
      ++counters.sessions;
    has_session = true;
    session_operator = s.operator_id;
    session = index;
    s.stage = PeerState::Stage::kSession;
    last_heard_s = now;
    flush_pending();
  }
  // A sealed datagram of the session: to the inbox, or the control channel's.
  void deliver(std::uint8_t channel, const std::uint8_t* data, std::size_t size) {
    if (channel == kControl) {
      if (size == 1 && data[0] == kControlEnd) peer_ended = true;
      return;
    }
    out->push(data, size);
  }
  void on_connect(ENetPeer* p, double now);
  void on_receive(ENetPeer* p, std::uint8_t channel, const std::uint8_t* data, std::size_t size,
                  double now);
  void on_disconnect(ENetPeer* p, enet_uint32 data, double now);
  void start_connect(double now);
  void check_deadlines(double now);
  int service(ENetEvent& event);
  void read_kernel_drops();
};

namespace {
// The endpoint whose host is being serviced on this thread (the intercept's).
thread_local EnetEndpoint::State* t_servicing = nullptr;

// Every datagram ENet reads comes here first: 1 drops it (counted), 0 lets
// ENet have it. ENet sees only datagrams from its peers' addresses and
// connection requests (to a listener).
int ENET_CALLBACK intercept(ENetHost* host, ENetEvent*) {
  EnetEndpoint::State* s = t_servicing;
  if (!s) return 0;
  ++s->intercepted;
  ++s->counters.datagrams;
  const std::size_t n = host->receivedDataLength;
  if (n >= kLargestDatagram) {  // cut to this by the socket filter: longer than any ENet datagram
    ++s->counters.dropped_oversize;
    return 1;
  }
  const ENetAddress& from = host->receivedAddress;
  for (std::size_t i = 0; i < host->peerCount; ++i) {
    const ENetPeer& p = host->peers[i];
    if (p.state != ENET_PEER_STATE_DISCONNECTED && p.address.host == from.host &&
        p.address.port == from.port) {
      const PeerState* slot = static_cast<const PeerState*>(p.data);
      if (!slot)
        ++s->counters.to_half_open;
      else if (slot->stage != PeerState::Stage::kSession)
        ++s->counters.to_unauthenticated;
      return 0;
    }
  }
  if (s->listener && connection_request(host->receivedData, n)) {
    ++s->counters.connection_requests;
    return 0;
  }
  ++s->counters.dropped_unknown_source;
  return 1;
}
}  // namespace

int EnetEndpoint::State::service(ENetEvent& event) {
  t_servicing = this;
  const int r = enet_host_service(host, &event, 0);
  t_servicing = nullptr;
  return r;
}

void EnetEndpoint::State::read_kernel_drops() {
  const auto now = kernel_drops(host->socket);
  if (!now) return;
  if (!drops_base) drops_base = drops_last = now;
  if (*now < *drops_last) drops_wrapped += std::int64_t(1) << 32;
  drops_last = now;
  counters.kernel_dropped = drops_wrapped + std::int64_t(*now) - std::int64_t(*drops_base);
}

void EnetEndpoint::State::start_connect(double now) {
  ENetPeer* p = enet_host_connect(host, &remote, kChannels, 0);
  reconnect_at_s = -1.0;
  if (!p) {
    reconnect_at_s = now + kReconnectDelay_s;
    return;
  }
  PeerState* s = take_slot(p, now);
  // The connection itself may wait for a late remote: ENet retries it until
  // its peer timeout, then a new connection starts.
  s->deadline_s = 1e300;
  const enet_uint32 timeout_ms = enet_uint32(std::lround(o.peer_timeout_s * 1000.0));
  enet_peer_timeout(p, 0, std::min<enet_uint32>(1000, timeout_ms), timeout_ms);
}

void EnetEndpoint::State::on_connect(ENetPeer* p, double now) {
  ++counters.connections;
  never_throttle(p);
  const enet_uint32 timeout_ms = enet_uint32(std::lround(o.peer_timeout_s * 1000.0));
  enet_peer_timeout(p, 0, std::min<enet_uint32>(1000, timeout_ms), timeout_ms);
  if (listener) {
    if (!take_slot(p, now)) enet_peer_disconnect_now(p, enet_uint32(Refusal::kBusy));
    return;
  }
  // Operator: our connection is up; say HELLO.
  PeerState* s = slot_of(p);
  if (!s) return;
  s->initiator.emplace(o.key, o.station_id);
  s->stage = PeerState::Stage::kAnswered;
  s->deadline_s = now + o.handshake_timeout_s;
  ENetPacket* packet = enet_packet_create(s->initiator->hello().data(), kHelloSize, ENET_PACKET_FLAG_RELIABLE);
  if (packet && enet_peer_send(p, kControl, packet) != 0) enet_packet_destroy(packet);
}

void EnetEndpoint::State::on_receive(ENetPeer* p, std::uint8_t channel, const std::uint8_t* data,
                                     std::size_t size, double now) {
  PeerState* s = slot_of(p);
  if (!s) return;
  if (opened.size() < size) opened.resize(size);
  std::size_t n = 0;
  std::uint8_t sealed_channel = 0;
  switch (s->stage) {
    case PeerState::Stage::kFree:
      return;
    case PeerState::Stage::kPending: {  // remote: only a HELLO may come now
      ++counters.unauthenticated_packets;
      if (!listener) return;
      if (channel != kControl || !is_handshake(data, size)) return refuse(*s, Refusal::kMalformed);
      std::array<std::uint8_t, kWelcomeSize> welcome{};
      SessionKeys keys;
      std::uint32_t id = 0;
      const AuthReject r = answer_hello(o.key, o.station_id, data, size, id, welcome, keys);
      if (r == AuthReject::kInsecure) return refuse(*s, Refusal::kInsecureMismatch);
      if (r == AuthReject::kBadMac) return refuse(*s, Refusal::kBadKey);
      if (r != AuthReject::kNone) return refuse(*s, Refusal::kMalformed);
      if (busy(id, now)) return refuse(*s, Refusal::kBusy);
      s->operator_id = id;
      s->channel.emplace(keys);
      s->stage = PeerState::Stage::kAnswered;
      ENetPacket* packet = enet_packet_create(welcome.data(), welcome.size(), ENET_PACKET_FLAG_RELIABLE);
      if (packet && enet_peer_send(p, kControl, packet) != 0) enet_packet_destroy(packet);
      return;
    }
    case PeerState::Stage::kAnswered:
      ++counters.unauthenticated_packets;
      if (!listener) {  // operator: the WELCOME
        if (channel != kControl || !is_handshake(data, size)) return;  // stale data of a dropped session
        SessionKeys keys;
        std::uint32_t remote_id = 0;
        const AuthReject r = s->initiator->accept(data, size, keys, remote_id);
        if (r != AuthReject::kNone) {
          // Not our remote (another key, or forged): drop it and try again.
          ++counters.refused[std::size_t(r == AuthReject::kInsecure ? Refusal::kInsecureMismatch
                                                                    : Refusal::kBadKey)];
          free_slot(*s);
          enet_peer_disconnect_now(p, 0);
          reconnect_at_s = now + kReconnectDelay_s;
          return;
        }
        s->initiator.reset();
        s->channel.emplace(keys);
        s->operator_id = o.station_id;
        peer_id = remote_id;
        open_session(*s, now);
        const std::uint8_t confirm = kControlConfirm;
        transmit(*s, kControl, &confirm, 1);
        return;
      }
      // Remote: the first sealed datagram proves the peer holds the keys.
      if (s->channel->open(data, size, opened.data(), n, sealed_channel) != AuthReject::kNone)
        return refuse(*s, Refusal::kBadKey);
      if (busy(s->operator_id, now)) return refuse(*s, Refusal::kBusy);
      open_session(*s, now);
      peer_id = s->operator_id;
      return deliver(sealed_channel, opened.data(), n);
    case PeerState::Stage::kSession: {
      const AuthReject r = s->channel->open(data, size, opened.data(), n, sealed_channel);
      if (r != AuthReject::kNone) {
        ++counters.rejected[std::size_t(r)];
        return;
      }
      last_heard_s = now;
      return deliver(sealed_channel, opened.data(), n);
    }
  }
}

void EnetEndpoint::State::on_disconnect(ENetPeer* p, enet_uint32 data, double now) {
  PeerState* s = slot_of(p);
  const bool was_session = s && s->stage == PeerState::Stage::kSession;
  if (s) free_slot(*s);
  if (listener) return;
  // Operator: refused by the remote (a reason in the disconnection), or lost.
  if (!was_session && data >= enet_uint32(Refusal::kBadKey) && data < kRefusalCount) {
    refused_by_peer = Refusal(data);
    return;
  }
  if (!peer_ended && !ended) reconnect_at_s = now + kReconnectDelay_s;
}

void EnetEndpoint::State::check_deadlines(double now) {
  for (PeerState& s : peers) {
    if ((s.stage != PeerState::Stage::kPending && s.stage != PeerState::Stage::kAnswered) ||
        now <= s.deadline_s)
      continue;
    if (listener) {
      refuse(s, Refusal::kTimeout);
    } else {  // no WELCOME in time: connect again
      ENetPeer* p = s.peer;
      free_slot(s);
      enet_peer_reset(p);
      reconnect_at_s = now + kReconnectDelay_s;
    }
  }
  if (!listener && reconnect_at_s >= 0.0 && now >= reconnect_at_s && !refused_by_peer && !peer_ended &&
      !ended)
    start_connect(now);
}

EnetEndpoint::EnetEndpoint(std::unique_ptr<State> state) : s_(std::move(state)) {}

EnetEndpoint::~EnetEndpoint() {
  for (PeerState& s : s_->peers)
    if (s.peer && s.peer->state == ENET_PEER_STATE_CONNECTED) enet_peer_disconnect_now(s.peer, 0);
  if (s_->host) enet_host_flush(s_->host);
}

namespace {
std::unique_ptr<EnetEndpoint::State> make_state(const EnetOptions& o, bool listener) {
  if (!(o.handshake_timeout_s > 0.0 && o.handshake_timeout_s <= 60.0))
    throw InputError("handshake_timeout_s must be in (0, 60]");
  if (!(o.peer_timeout_s >= 1.0 && o.peer_timeout_s <= 60.0))
    throw InputError("peer_timeout_s must be in [1, 60]");
  if (!(o.receive_budget_s >= 0.0) || !(o.takeover_silence_s >= 0.0))
    throw InputError("receive_budget_s and takeover_silence_s must be >= 0");
  // A key left at its default (zeros) is no key: say so rather than run
  // "authenticated" with the key everyone knows.
  if (!o.key.insecure &&
      std::all_of(o.key.bytes.begin(), o.key.bytes.end(), [](std::uint8_t b) { return b == 0; }))
    throw InputError("the link's key is all zeros (none was given): give the stations a key, or "
                     "insecure_key() for a demo on loopback");
  enet_acquire();
  auto state = std::make_unique<EnetEndpoint::State>();
  state->o = o;
  state->listener = listener;
  return state;
}
}  // namespace

std::unique_ptr<EnetEndpoint> EnetEndpoint::listen(const std::string& address, int port,
                                                   const EnetOptions& options) {
  auto state = make_state(options, true);
  const ENetAddress a = make_address(address, port, "--listen");
  state->host = enet_host_create(&a, kPeers, kChannels, 0, 0);
  if (!state->host)
    throw InputError("cannot bind UDP " + address + ":" + std::to_string(port) +
                     " (in use, or not an address of this machine)");
  state->host->intercept = intercept;
  state->counters.receive_buffer_bytes = prepare_socket(state->host->socket, options.receive_buffer_bytes);
  state->read_kernel_drops();
  return std::unique_ptr<EnetEndpoint>(new EnetEndpoint(std::move(state)));
}

std::unique_ptr<EnetEndpoint> EnetEndpoint::connect(const std::string& address, int port,
                                                    const EnetOptions& options) {
  auto state = make_state(options, false);
  if (port < 1) throw InputError("--connect: port must be in [1, 65535], got " + std::to_string(port));
  state->remote = make_address(address, port, "--connect");
  state->host = enet_host_create(nullptr, 1, kChannels, 0, 0);
  if (!state->host) throw InputError("cannot create a UDP socket");
  state->host->intercept = intercept;
  state->counters.receive_buffer_bytes = prepare_socket(state->host->socket, options.receive_buffer_bytes);
  state->read_kernel_drops();
  state->start_connect(wall_s());
  if (state->session < 0 && state->peers[0].stage == PeerState::Stage::kFree)
    throw InputError("cannot connect to " + address + ":" + std::to_string(port));
  return std::unique_ptr<EnetEndpoint>(new EnetEndpoint(std::move(state)));
}

void EnetEndpoint::send(Channel channel, const std::uint8_t* data, std::size_t size, double) {
  ++traffic_.sent;
  traffic_.sent_bytes += std::int64_t(size);
  if (PeerState* s = s_->session_slot()) {
    s_->transmit(*s, static_cast<std::uint8_t>(channel), data, size);
    return;
  }
  if (channel != Channel::kReliable) {
    ++s_->counters.dropped_unconnected;
    return;
  }
  if (s_->pending.size() >= kPendingBound) {
    s_->pending.pop();
    ++s_->counters.dropped_unconnected;
  }
  s_->pending.hold(0.0, static_cast<std::uint8_t>(channel), data, size);
}

void EnetEndpoint::receive(double, Inbox& out) {
  State& s = *s_;
  s.out = &out;
  const std::size_t before_out = out.size();
  const double start = wall_s();
  ENetEvent event;
  // Passes of up to 256 datagrams (ENet's) until the socket is empty or the
  // budget is spent; the first always runs.
  for (;;) {
    const std::int64_t before = s.intercepted;
    const int r = s.service(event);
    const double now = wall_s();
    if (r > 0) {
      switch (event.type) {
        case ENET_EVENT_TYPE_CONNECT:
          s.on_connect(event.peer, now);
          break;
        case ENET_EVENT_TYPE_DISCONNECT:
          s.on_disconnect(event.peer, event.data, now);
          break;
        case ENET_EVENT_TYPE_RECEIVE:
          s.on_receive(event.peer, event.channelID, event.packet->data, event.packet->dataLength, now);
          enet_packet_destroy(event.packet);
          break;
        case ENET_EVENT_TYPE_NONE:
          break;
      }
    } else {
      if (r < 0) ++s.counters.receive_errors;
      if (s.intercepted - before < 256) break;  // the socket is empty
    }
    if (now - start > s.o.receive_budget_s) {
      ++s.counters.budget_stops;
      break;
    }
  }
  s.out = nullptr;
  for (std::size_t i = before_out; i < out.size(); ++i) {
    ++traffic_.received;
    traffic_.received_bytes += std::int64_t(out[i].size());
  }
  s.check_deadlines(wall_s());
  s.read_kernel_drops();
  enet_host_flush(s.host);
}

void EnetEndpoint::end_session(double wait_s) {
  State& s = *s_;
  PeerState* p = s.session_slot();
  if (!p) return;
  const std::uint8_t end = kControlEnd;
  s.transmit(*p, kControl, &end, 1);
  ENetPeer* peer = p->peer;
  enet_peer_disconnect_later(peer, 0);
  s.ended = true;
  const double start = wall_s();
  ENetEvent event;
  Inbox ignored;
  s.out = &ignored;
  while (wall_s() - start < wait_s) {
    const int r = s.service(event);
    if (r > 0 && event.type == ENET_EVENT_TYPE_RECEIVE) enet_packet_destroy(event.packet);
    if (r > 0 && event.type == ENET_EVENT_TYPE_DISCONNECT && event.peer == peer) {
      s.on_disconnect(peer, event.data, wall_s());
      break;
    }
    if (r <= 0) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  s.out = nullptr;
}

void EnetEndpoint::reserve_in_flight(std::size_t datagrams, std::size_t bytes) {
  s_->pending.reserve(std::min(datagrams, kPendingBound), bytes);
  if (s_->sealed.size() < bytes + kSealOverhead) s_->sealed.resize(bytes + kSealOverhead);
  if (s_->opened.size() < bytes + kSealOverhead) s_->opened.resize(bytes + kSealOverhead);
}

int EnetEndpoint::port() const {
  // The socket's own port: an operator's host binds any free one (its
  // ENetHost::address says 0).
  ENetAddress a{};
  if (!s_->host || enet_socket_get_address(s_->host->socket, &a) != 0) return -1;
  return int(a.port);
}
bool EnetEndpoint::connected() const { return s_->session >= 0; }
bool EnetEndpoint::peer_ended() const { return s_->peer_ended; }
std::optional<Refusal> EnetEndpoint::refused_by_peer() const { return s_->refused_by_peer; }
std::uint32_t EnetEndpoint::peer_id() const { return s_->peer_id; }
const EnetCounters& EnetEndpoint::counters() const { return s_->counters; }

}  // namespace terracut::net
