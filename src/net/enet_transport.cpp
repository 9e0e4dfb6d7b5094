// The ENet carrier (enet_transport.hpp).
#include "terracut/net/enet_transport.hpp"

#include <enet/enet.h>

#include <algorithm>
#include <mutex>

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

constexpr std::size_t kChannels = 2;

}  // namespace

struct EnetEndpoint::State {
  ~State() {
    if (host) enet_host_destroy(host);
    enet_release();
  }
  ENetHost* host = nullptr;
  ENetPeer* peer = nullptr;  // the connected peer, or null
  bool connected = false;
  std::int64_t connections = 0;
  std::int64_t dropped_unconnected = 0;
  HeldQueue held;  // waiting for a peer; tag: the Channel
};

EnetEndpoint::EnetEndpoint(std::unique_ptr<State> state) : s_(std::move(state)) {}

EnetEndpoint::~EnetEndpoint() {
  if (s_->peer && s_->connected) {
    enet_peer_disconnect_now(s_->peer, 0);
    enet_host_flush(s_->host);
  }
}

namespace {
// ENet drops unreliable packets itself ("packet throttling") while the round
// trip it measures varies more than usual, which the emulated jitter and a
// busy machine both cause: commands would be lost beyond the loss the link
// is set to. The throttle stays at its full scale (never decelerates), so
// the emulator alone decides what is lost. Set on both sides once connected
// (before, the command would break the handshake).
void never_throttle(ENetPeer* peer) {
  enet_peer_throttle_configure(peer, ENET_PEER_PACKET_THROTTLE_INTERVAL, ENET_PEER_PACKET_THROTTLE_SCALE, 0);
}
}  // namespace

std::unique_ptr<EnetEndpoint> EnetEndpoint::listen(const std::string& address, int port) {
  enet_acquire();
  auto state = std::make_unique<State>();
  const ENetAddress a = make_address(address, port, "--listen");
  state->host = enet_host_create(&a, 4, kChannels, 0, 0);
  if (!state->host)
    throw InputError("cannot bind UDP " + address + ":" + std::to_string(port) +
                     " (in use, or not an address of this machine)");
  return std::unique_ptr<EnetEndpoint>(new EnetEndpoint(std::move(state)));
}

std::unique_ptr<EnetEndpoint> EnetEndpoint::connect(const std::string& address, int port) {
  enet_acquire();
  auto state = std::make_unique<State>();
  if (port < 1) throw InputError("--connect: port must be in [1, 65535], got " + std::to_string(port));
  const ENetAddress remote = make_address(address, port, "--connect");
  state->host = enet_host_create(nullptr, 1, kChannels, 0, 0);
  if (!state->host) throw InputError("cannot create a UDP socket");
  state->peer = enet_host_connect(state->host, &remote, kChannels, 0);
  if (!state->peer) throw InputError("cannot connect to " + address + ":" + std::to_string(port));
  return std::unique_ptr<EnetEndpoint>(new EnetEndpoint(std::move(state)));
}

void EnetEndpoint::send(Channel channel, const std::uint8_t* data, std::size_t size, double now_s) {
  ++traffic_.sent;
  traffic_.sent_bytes += std::int64_t(size);
  s_->held.hold(now_s, static_cast<std::uint8_t>(channel), data, size);
  release(now_s);
}

void EnetEndpoint::release(double now_s) {
  HeldQueue& held = s_->held;
  while (!held.empty() && held.front_s() <= now_s) {
    const auto channel = static_cast<Channel>(held.front_tag());
    if (!s_->connected) {
      // Nobody to send to: an unreliable datagram is gone; a reliable one waits.
      if (channel == Channel::kReliable) break;
      ++s_->dropped_unconnected;
      held.pop();
      continue;
    }
    const enet_uint32 flags = channel == Channel::kReliable ? ENET_PACKET_FLAG_RELIABLE : 0;
    const std::vector<std::uint8_t>& bytes = held.front_bytes();
    ENetPacket* packet = enet_packet_create(bytes.data(), bytes.size(), flags);
    if (packet && enet_peer_send(s_->peer, static_cast<enet_uint8>(channel), packet) != 0)
      enet_packet_destroy(packet);
    held.pop();
  }
  enet_host_flush(s_->host);
}

void EnetEndpoint::receive(double now_s, Inbox& out) {
  ENetEvent event;
  while (enet_host_service(s_->host, &event, 0) > 0) {
    switch (event.type) {
      case ENET_EVENT_TYPE_CONNECT:
        // A new peer (or a restarted one) replaces the old.
        if (s_->peer && s_->peer != event.peer && s_->connected) enet_peer_reset(s_->peer);
        s_->peer = event.peer;
        s_->connected = true;
        never_throttle(event.peer);
        ++s_->connections;
        break;
      case ENET_EVENT_TYPE_DISCONNECT:
        if (event.peer == s_->peer) s_->connected = false;
        break;
      case ENET_EVENT_TYPE_RECEIVE:
        if (event.peer == s_->peer) {
          ++traffic_.received;
          traffic_.received_bytes += std::int64_t(event.packet->dataLength);
          out.push(event.packet->data, event.packet->dataLength);
        }
        enet_packet_destroy(event.packet);
        break;
      case ENET_EVENT_TYPE_NONE:
        break;
    }
  }
  release(now_s);
}

void EnetEndpoint::reserve_in_flight(std::size_t datagrams, std::size_t bytes) {
  s_->held.reserve(datagrams, bytes);
}
int EnetEndpoint::port() const { return s_->host ? int(s_->host->address.port) : -1; }
bool EnetEndpoint::connected() const { return s_->connected; }
std::int64_t EnetEndpoint::connections() const { return s_->connections; }
std::int64_t EnetEndpoint::dropped_unconnected() const { return s_->dropped_unconnected; }

}  // namespace terracut::net
