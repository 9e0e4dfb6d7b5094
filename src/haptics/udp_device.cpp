// The UDP bridge over asio (standalone): non-blocking sockets, preallocated
// buffers, error codes instead of exceptions on the per-tick paths.
#include "terracut/haptics/udp_device.hpp"

#include <array>
#include <asio.hpp>
#include <chrono>
#include <cmath>

#include "terracut/core/error.hpp"
#include "terracut/core/format.hpp"

namespace terracut::haptics {
namespace {

// Large enough for any UDP datagram, so an oversized one is seen whole (and
// rejected as bad_length) instead of cut to the buffer's size.
constexpr std::size_t kReceiveBufferSize = 65536;

asio::ip::address parse_address(const std::string& address, const char* field) {
  asio::error_code ec;
  asio::ip::address a = asio::ip::make_address(address, ec);
  if (ec)
    throw InputError(std::string(field) + ": '" + address +
                     "' is not an IP address (use a numeric IPv4 or IPv6 address, e.g. 127.0.0.1)");
  return a;
}

std::uint64_t loop_time_ns(double t_s) {
  return t_s > 0.0 && std::isfinite(t_s) ? static_cast<std::uint64_t>(std::llround(t_s * 1e9)) : 0;
}

// Reads the datagrams waiting on the socket (at most kMaxDatagramsPerPoll),
// decodes each with decode(data, size, header, payload), checks it with the
// sequence filter and books it in stats; calls accept(header, payload) for
// each packet that passes. Both ends of the bridge read this way.
template <class Payload, class Impl, class Decode, class Accept>
void drain_datagrams(Impl& impl, BridgeStats& stats, SequenceFilter& filter, Decode&& decode,
                     Accept&& accept) noexcept {
  for (int i = 0; i < kMaxDatagramsPerPoll; ++i) {
    asio::error_code ec;
    const std::size_t n = impl.socket.receive_from(asio::buffer(impl.rx), impl.sender, 0, ec);
    if (ec == asio::error::would_block || ec == asio::error::try_again) break;
    if (ec) {
      // ICMP "port unreachable" from an earlier send shows up here on Linux;
      // nothing was received, go on.
      ++stats.receive_errors;
      if (ec == asio::error::connection_refused) continue;
      break;
    }
    ++stats.datagrams_received;
    PacketHeader header;
    Payload payload;
    Reject r = decode(impl.rx.data(), n, header, payload);
    if (r == Reject::kNone) r = filter.check(header);
    if (r != Reject::kNone) {
      stats.rejected.add(r);
      continue;
    }
    ++stats.accepted;
    accept(header, payload);
  }
  stats.lost = filter.lost();
  stats.sessions = filter.sessions();
}

}  // namespace

// ---------------------------------------------------------------------------
// UdpDevice
// ---------------------------------------------------------------------------

struct UdpDevice::Impl {
  asio::io_context io;
  asio::ip::udp::socket socket{io};
  asio::ip::udp::endpoint sender;
  asio::ip::udp::endpoint peer;
  bool has_peer = false;
  std::array<std::uint8_t, kReceiveBufferSize> rx{};
  std::array<std::uint8_t, kMaxBridgePacketSize> tx{};
  PosePayload newest{};
  std::uint32_t newest_sequence = 0;
  std::uint64_t newest_timestamp_ns = 0;
};

UdpDevice::UdpDevice(const std::string& address, int port) : impl_(std::make_unique<Impl>()) {
  if (port < 0 || port > 65535)
    throw InputError(must_be("udp.port", "in [0, 65535]", port));
  const asio::ip::address ip = parse_address(address, "udp.address");
  const asio::ip::udp::endpoint local(ip, static_cast<unsigned short>(port));
  asio::error_code ec;
  impl_->socket.open(local.protocol(), ec);
  if (!ec) impl_->socket.bind(local, ec);
  if (!ec) impl_->socket.non_blocking(true, ec);
  if (ec)
    throw InputError("udp: cannot bind " + address + ":" + std::to_string(port) + ": " +
                     ec.message() + " (is another session using the port? pick another with " +
                     "--device udp:ADDR:PORT or haptics.udp.port)");
  port_ = impl_->socket.local_endpoint(ec).port();
  // A session id of our own for the force packets (distinct per process run).
  session_ = static_cast<std::uint32_t>(
      std::chrono::steady_clock::now().time_since_epoch().count() ^ 0x5bd1e995u);
}

UdpDevice::~UdpDevice() = default;

int UdpDevice::port() const { return port_; }

bool UdpDevice::read(double t_s, DeviceSample& out) noexcept {
  (void)t_s;
  bool got = false;
  reconnected_ = false;
  drain_datagrams<PosePayload>(
      *impl_, stats_, filter_,
      [](const std::uint8_t* data, std::size_t n, PacketHeader& h, PosePayload& p) {
        return decode_pose(data, n, h, p);
      },
      [&](const PacketHeader& header, const PosePayload& pose) {
        if (filter_.new_session() && filter_.sessions() > 1) reconnected_ = true;
        impl_->newest = pose;
        impl_->newest_sequence = header.sequence;
        impl_->newest_timestamp_ns = header.timestamp_ns;
        impl_->peer = impl_->sender;
        impl_->has_peer = true;
        got = true;
      });
  if (!got) return false;
  const PosePayload& p = impl_->newest;
  out.position_m = p.position_m;
  out.has_orientation = (p.flags & kPoseHasOrientation) != 0;
  out.orientation = out.has_orientation ? p.orientation : Quat{};
  out.buttons = p.buttons;
  out.reconnected = reconnected_;
  // The sender's clock (nanoseconds, any origin): kept to microseconds in a
  // double for about 285 years of uptime.
  out.device_time_s = double(impl_->newest_timestamp_ns) * 1e-9;
  return true;
}

void UdpDevice::write(const DeviceCommand& command) noexcept {
  if (!impl_->has_peer) return;
  PacketHeader header;
  header.session = session_;
  header.sequence = sequence_++;
  header.timestamp_ns = loop_time_ns(command.t_s);
  ForcePayload force;
  force.force_n = command.force_n;
  force.flags = command.flags;
  force.pose_sequence = impl_->newest_sequence;
  const std::size_t n = encode_force(header, force, impl_->tx.data());
  asio::error_code ec;
  impl_->socket.send_to(asio::buffer(impl_->tx.data(), n), impl_->peer, 0, ec);
  if (ec)
    ++stats_.send_errors;
  else
    ++stats_.sent;
}

void UdpDevice::stop() noexcept {
  asio::error_code ec;
  impl_->socket.close(ec);
}

std::vector<DeviceStat> UdpDevice::stats() const {
  std::vector<DeviceStat> out = {{"datagrams_received", double(stats_.datagrams_received)},
                                 {"poses_accepted", double(stats_.accepted)},
                                 {"poses_lost", double(stats_.lost)},
                                 {"sessions", double(stats_.sessions)},
                                 {"forces_sent", double(stats_.sent)},
                                 {"send_errors", double(stats_.send_errors)},
                                 {"receive_errors", double(stats_.receive_errors)}};
  return out;
}

// ---------------------------------------------------------------------------
// BridgeClient
// ---------------------------------------------------------------------------

struct BridgeClient::Impl {
  asio::io_context io;
  asio::ip::udp::socket socket{io};
  asio::ip::udp::endpoint server;
  asio::ip::udp::endpoint sender;
  std::array<std::uint8_t, kReceiveBufferSize> rx{};
  std::array<std::uint8_t, kMaxBridgePacketSize> tx{};
};

BridgeClient::BridgeClient(const std::string& address, int port, std::uint32_t session)
    : impl_(std::make_unique<Impl>()), session_(session) {
  if (port < 1 || port > 65535)
    throw InputError(must_be("port", "in [1, 65535]", port));
  const asio::ip::address ip = parse_address(address, "address");
  impl_->server = asio::ip::udp::endpoint(ip, static_cast<unsigned short>(port));
  asio::error_code ec;
  impl_->socket.open(impl_->server.protocol(), ec);
  if (!ec) impl_->socket.non_blocking(true, ec);
  if (ec) throw InputError("cannot open a UDP socket: " + ec.message());
}

BridgeClient::~BridgeClient() = default;

std::uint32_t BridgeClient::send_pose(const PosePayload& pose,
                                      std::uint64_t timestamp_ns) noexcept {
  PacketHeader header;
  header.session = session_;
  header.sequence = sequence_++;
  header.timestamp_ns = timestamp_ns;
  const std::size_t n = encode_pose(header, pose, impl_->tx.data());
  send_raw(impl_->tx.data(), n);
  return header.sequence;
}

void BridgeClient::send_raw(const std::uint8_t* data, std::size_t size) noexcept {
  asio::error_code ec;
  impl_->socket.send_to(asio::buffer(data, size), impl_->server, 0, ec);
  if (ec)
    ++stats_.send_errors;
  else
    ++stats_.sent;
}

bool BridgeClient::poll_force(ForcePayload& out, PacketHeader& header) noexcept {
  bool got = false;
  drain_datagrams<ForcePayload>(
      *impl_, stats_, filter_,
      [](const std::uint8_t* data, std::size_t n, PacketHeader& h, ForcePayload& f) {
        return decode_force(data, n, h, f);
      },
      [&](const PacketHeader& h, const ForcePayload& f) {
        out = f;
        header = h;
        got = true;
      });
  return got;
}

}  // namespace terracut::haptics
