// The UDP device bridge (protocol: bridge_protocol.hpp, docs/bridge-protocol.md).
//
// UdpDevice is the loop's side: it binds an address (127.0.0.1 by default),
// takes pose packets from whichever process sends them and answers each tick
// with a force packet to the sender of the newest accepted pose. BridgeClient
// is the other side, what a device process does: send poses, receive forces;
// terracut-device and the tests use it.
//
// Both sides use non-blocking sockets and preallocated buffers: read() and
// write() never block, never throw and allocate nothing. A flood is drained
// at most kMaxDatagramsPerPoll datagrams per call.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "terracut/haptics/bridge_protocol.hpp"
#include "terracut/haptics/device.hpp"

namespace terracut::haptics {

/// Most datagrams one read()/poll_force() takes from the socket.
inline constexpr int kMaxDatagramsPerPoll = 256;

/// Traffic counters of one side of the bridge.
struct BridgeStats {
  std::int64_t datagrams_received = 0;  ///< datagrams read from the socket
  std::int64_t accepted = 0;            ///< packets that passed every check
  RejectCounts rejected{};              ///< the others, by reason
  std::int64_t lost = 0;                ///< gaps in accepted sequence numbers
  std::int64_t sessions = 0;            ///< sender sessions seen (reconnections + 1)
  std::int64_t sent = 0;                ///< packets sent
  std::int64_t send_errors = 0;         ///< sends the socket refused (would block, no route)
  std::int64_t receive_errors = 0;      ///< socket errors on receive (other than "nothing there")
};

/// The `udp` device: the loop side of the bridge.
class UdpDevice final : public Device {
 public:
  /// Binds a UDP socket to address:port (port 0: a free port, see port()).
  /// Throws InputError naming udp.address / udp.port when the address is not
  /// an IP address or cannot be bound (for example the port is in use).
  UdpDevice(const std::string& address, int port);
  ~UdpDevice() override;
  UdpDevice(const UdpDevice&) = delete;
  UdpDevice& operator=(const UdpDevice&) = delete;

  std::string_view kind() const override { return "udp"; }
  /// Drains the socket; the newest accepted pose is the sample. Sets
  /// `reconnected` (see DeviceSample) when it starts a new sender session.
  bool read(double t_s, DeviceSample& out) noexcept override;
  /// Sends a force packet to the sender of the newest accepted pose (none
  /// before the first pose).
  void write(const DeviceCommand& command) noexcept override;
  void stop() noexcept override;
  std::vector<DeviceStat> stats() const override;

  /// The bound port (also after stop()).
  int port() const;
  const BridgeStats& bridge_stats() const { return stats_; }
  /// True when the newest accepted pose started a new session after the first.
  bool reconnected() const { return reconnected_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  BridgeStats stats_{};
  SequenceFilter filter_{};
  bool reconnected_ = false;
  int port_ = 0;                // the bound port
  std::uint32_t session_ = 0;   // our own session id for force packets
  std::uint32_t sequence_ = 0;  // our next force sequence number
};

/// The device process's side of the bridge.
class BridgeClient {
 public:
  /// Opens a socket on an ephemeral local port and sends to address:port.
  /// session: this process's session id (e.g. random or time-based).
  /// Throws InputError when the address is not an IP address.
  BridgeClient(const std::string& address, int port, std::uint32_t session);
  ~BridgeClient();
  BridgeClient(const BridgeClient&) = delete;
  BridgeClient& operator=(const BridgeClient&) = delete;

  /// Sends one pose (sequence numbers are assigned here, from 0). Returns the
  /// sequence number used.
  std::uint32_t send_pose(const PosePayload& pose, std::uint64_t timestamp_ns) noexcept;
  /// Sends raw bytes (tests: malformed packets) to the loop.
  void send_raw(const std::uint8_t* data, std::size_t size) noexcept;
  /// Drains the socket; true when a new force was accepted (the newest in `out`,
  /// its header in `header`).
  bool poll_force(ForcePayload& out, PacketHeader& header) noexcept;

  const BridgeStats& stats() const { return stats_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  BridgeStats stats_{};
  SequenceFilter filter_{};
  std::uint32_t session_ = 0;
  std::uint32_t sequence_ = 0;
};

}  // namespace terracut::haptics
