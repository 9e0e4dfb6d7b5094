// The device bridge protocol: binary datagrams between a process that owns a
// haptic device (the bridge) and the haptic loop. Byte-level description:
// docs/bridge-protocol.md. All fields little-endian; doubles are IEEE-754
// binary64.
//
//   offset size type  field
//   0      4    u32   magic = 0x42484354 (the bytes "TCHB")
//   4      2    u16   version = 1
//   6      2    u16   type: 1 pose (bridge -> loop), 2 force (loop -> bridge)
//   8      4    u32   session: chosen by the sender at start (a new value = reconnection)
//   12     4    u32   sequence: +1 per packet of the session (wraps)
//   16     8    u64   timestamp_ns: sender's monotonic clock, nanoseconds
//   24     4    u32   payload_size: 64 (pose) or 32 (force)
//   28     4    u32   reserved, 0
//   32     N    ...   payload
//   32+N   4    u32   crc32 (IEEE 802.3 / zlib) of bytes [0, 32+N)
//
// Encoding and decoding work on caller buffers: nothing is allocated and
// nothing throws, whatever the bytes.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <iterator>
#include <span>
#include <string_view>

#include "terracut/core/enum_names.hpp"
#include "terracut/core/math.hpp"
#include "terracut/core/wire.hpp"

namespace terracut::haptics {

inline constexpr std::uint32_t kBridgeMagic = 0x42484354u;  // "TCHB" in memory order
inline constexpr std::uint16_t kBridgeVersion = 1;
inline constexpr std::size_t kBridgeHeaderSize = 32;
inline constexpr std::size_t kBridgeCrcSize = 4;
inline constexpr std::size_t kPosePayloadSize = 64;
inline constexpr std::size_t kForcePayloadSize = 32;
inline constexpr std::size_t kPosePacketSize =
    kBridgeHeaderSize + kPosePayloadSize + kBridgeCrcSize;  // 100
inline constexpr std::size_t kForcePacketSize =
    kBridgeHeaderSize + kForcePayloadSize + kBridgeCrcSize;  // 68
inline constexpr std::size_t kMaxBridgePacketSize = kPosePacketSize;

/// Packet types.
enum class PacketType : std::uint16_t {
  kPose = 1,   ///< device pose, bridge -> loop
  kForce = 2,  ///< force command, loop -> bridge
};

/// Pose payload flag bits.
inline constexpr std::uint32_t kPoseHasOrientation = 1u;  ///< the orientation field is valid

/// The header fields a sender chooses (magic, version, sizes and CRC are implied).
struct PacketHeader {
  std::uint32_t session = 0;       ///< sender's session id
  std::uint32_t sequence = 0;      ///< packet number in the session
  std::uint64_t timestamp_ns = 0;  ///< sender's monotonic clock, ns
};

/// Pose payload (64 bytes): position f64[3] at 32, orientation f64[4] (w, x,
/// y, z) at 56, buttons u32 at 88, flags u32 at 92.
struct PosePayload {
  Vec3 position_m{};          ///< device frame, metres
  Quat orientation{};         ///< device frame, valid when flags has kPoseHasOrientation
  std::uint32_t buttons = 0;  ///< bit i = button i
  std::uint32_t flags = 0;    ///< kPoseHasOrientation; other bits 0 (ignored on receipt)
};

/// Force payload (32 bytes): force f64[3] at 32, flags u32 at 56,
/// pose_sequence u32 at 60.
struct ForcePayload {
  Vec3 force_n{};                   ///< device frame, newtons, |force| <= the safety maximum
  std::uint32_t flags = 0;          ///< the loop's flags of the tick (LoopRecord flags)
  std::uint32_t pose_sequence = 0;  ///< sequence of the newest pose accepted (for round trips)
};

/// CRC-32 (IEEE 802.3, reflected, polynomial 0xEDB88320, init and final xor
/// 0xFFFFFFFF: zlib's crc32 and Python's zlib.crc32).
std::uint32_t crc32(const std::uint8_t* data, std::size_t size) noexcept;

/// Writes a pose packet into out (at least kPosePacketSize bytes); returns its size.
std::size_t encode_pose(const PacketHeader& header, const PosePayload& pose,
                        std::uint8_t* out) noexcept;
/// Writes a force packet into out (at least kForcePacketSize bytes); returns its size.
std::size_t encode_force(const PacketHeader& header, const ForcePayload& force,
                         std::uint8_t* out) noexcept;

/// Why a datagram was rejected. Format reasons come from decode_*; the
/// order reasons from SequenceFilter.
enum class Reject : std::uint8_t {
  kNone = 0,     ///< accepted
  kTruncated,    ///< shorter than its header, or than the size its header declares
  kBadLength,    ///< longer than declared, or a payload size wrong for its type
  kBadMagic,     ///< the first four bytes are not "TCHB"
  kBadVersion,   ///< a protocol version this build does not speak
  kBadChecksum,  ///< CRC-32 mismatch: corrupted in transit
  kBadType,      ///< unknown type, or the other direction's type
  kDuplicate,    ///< same session and sequence as the last accepted packet
  kReordered,    ///< a sequence number older than the last accepted one
  kStale,        ///< a newer sequence but a timestamp older than the last accepted one
};
static_assert(int(Reject::kBadChecksum) == int(wire::Frame::kBadChecksum) &&
                  int(Reject::kTruncated) == int(wire::Frame::kTruncated),
              "the framing reasons are wire::Frame's, in its order");
/// Its names (core/enum_names.hpp: to_string, parse_enum), in the enum's
/// order: summary.json's rejected-packet counts are keyed by them.
inline constexpr EnumName<Reject> kRejectNames[] = {
    {Reject::kNone, "none"},
    {Reject::kTruncated, "truncated"},
    {Reject::kBadLength, "bad_length"},
    {Reject::kBadMagic, "bad_magic"},
    {Reject::kBadVersion, "bad_version"},
    {Reject::kBadChecksum, "bad_checksum"},
    {Reject::kBadType, "bad_type"},
    {Reject::kDuplicate, "duplicate"},
    {Reject::kReordered, "reordered"},
    {Reject::kStale, "stale"},
};
constexpr std::span<const EnumName<Reject>> enum_names(Reject) { return kRejectNames; }
using terracut::to_string;
inline constexpr std::size_t kRejectReasonCount = std::size(kRejectNames);  // including kNone
static_assert(std::size_t(kRejectNames[kRejectReasonCount - 1].value) + 1 == kRejectReasonCount,
              "one name per reason, in the enum's order (RejectCounts is indexed by the value)");

/// Checks a datagram's format (length, magic, version, CRC, type, payload
/// size) and decodes it. Order of checks: length >= 4, magic, length >=
/// header + CRC, version, declared size (truncated / bad_length), CRC, type.
/// On kNone the outputs are filled; otherwise they are unspecified.
Reject decode_pose(const std::uint8_t* data, std::size_t size, PacketHeader& header,
                   PosePayload& pose) noexcept;
Reject decode_force(const std::uint8_t* data, std::size_t size, PacketHeader& header,
                    ForcePayload& force) noexcept;

/// Counts of rejected datagrams by reason (index = Reject value; [0] unused).
struct RejectCounts {
  std::array<std::int64_t, kRejectReasonCount> by_reason{};
  void add(Reject reason) noexcept { ++by_reason[static_cast<std::size_t>(reason)]; }
  std::int64_t operator[](Reject reason) const {
    return by_reason[static_cast<std::size_t>(reason)];
  }
  std::int64_t total() const {
    std::int64_t sum = 0;
    for (std::size_t i = 1; i < kRejectReasonCount; ++i) sum += by_reason[i];
    return sum;
  }
};

/// Accepts only packets newer than the last accepted one of the same
/// session. A packet of another session starts a new session (a device
/// process restarted): its sequence and time are taken as they come.
class SequenceFilter {
 public:
  /// kNone (accepted; the filter moves on), kDuplicate, kReordered or kStale.
  Reject check(const PacketHeader& header) noexcept;

  /// True when the last accepted packet started a new session (the first one included).
  bool new_session() const { return order_.new_session(); }
  /// Sessions seen (1 after the first accepted packet).
  std::int64_t sessions() const { return order_.sessions(); }
  /// Packets skipped by gaps in the sequence numbers (lost or never sent).
  std::int64_t lost() const { return order_.lost(); }
  std::uint32_t last_sequence() const { return order_.last_sequence(); }

 private:
  wire::SequenceFilter order_;  // the rule shared with the teleoperation link (core/wire.hpp)
};

}  // namespace terracut::haptics
