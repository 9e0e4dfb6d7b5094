// Encoding, decoding and ordering of bridge datagrams (bridge_protocol.hpp).
// Every field is written and read byte by byte in little-endian order, so the
// code is independent of the host's endianness and alignment.
#include "terracut/haptics/bridge_protocol.hpp"

#include "terracut/core/wire.hpp"

namespace terracut::haptics {
namespace {

using wire::get_f64;
using wire::get_u16;
using wire::get_u32;
using wire::get_u64;
using wire::put_f64;
using wire::put_u16;
using wire::put_u32;
using wire::put_u64;

// Header and CRC around a payload already written at out + kBridgeHeaderSize.
std::size_t finish_packet(const PacketHeader& header, PacketType type, std::size_t payload_size,
                          std::uint8_t* out) {
  put_u32(out + 0, kBridgeMagic);
  put_u16(out + 4, kBridgeVersion);
  put_u16(out + 6, static_cast<std::uint16_t>(type));
  put_u32(out + 8, header.session);
  put_u32(out + 12, header.sequence);
  put_u64(out + 16, header.timestamp_ns);
  put_u32(out + 24, static_cast<std::uint32_t>(payload_size));
  put_u32(out + 28, 0);
  return wire::seal_frame(out, kBridgeHeaderSize + payload_size);
}

// The format checks shared by both packet types (see decode_pose's comment
// for the order). On kNone, header is filled.
Reject check_format(const std::uint8_t* data, std::size_t size, PacketType want,
                    std::size_t want_payload, PacketHeader& header) {
  std::size_t declared = 0;
  const wire::Frame frame = wire::check_frame(
      data, size, {kBridgeMagic, kBridgeVersion, kBridgeHeaderSize, 24}, declared);
  // wire::Frame's values are the first of Reject's, in the same order.
  if (frame != wire::Frame::kOk) return static_cast<Reject>(frame);
  if (get_u16(data + 6) != static_cast<std::uint16_t>(want)) return Reject::kBadType;
  if (declared != want_payload) return Reject::kBadLength;
  header.session = get_u32(data + 8);
  header.sequence = get_u32(data + 12);
  header.timestamp_ns = get_u64(data + 16);
  return Reject::kNone;
}

}  // namespace

std::uint32_t crc32(const std::uint8_t* data, std::size_t size) noexcept {
  return wire::crc32(data, size);
}

std::size_t encode_pose(const PacketHeader& header, const PosePayload& pose,
                        std::uint8_t* out) noexcept {
  std::uint8_t* p = out + kBridgeHeaderSize;
  wire::put_vec3(p, pose.position_m);
  wire::put_quat(p + 24, pose.orientation);
  put_u32(p + 56, pose.buttons);
  put_u32(p + 60, pose.flags);
  return finish_packet(header, PacketType::kPose, kPosePayloadSize, out);
}

std::size_t encode_force(const PacketHeader& header, const ForcePayload& force,
                         std::uint8_t* out) noexcept {
  std::uint8_t* p = out + kBridgeHeaderSize;
  wire::put_vec3(p, force.force_n);
  put_u32(p + 24, force.flags);
  put_u32(p + 28, force.pose_sequence);
  return finish_packet(header, PacketType::kForce, kForcePayloadSize, out);
}

Reject decode_pose(const std::uint8_t* data, std::size_t size, PacketHeader& header,
                   PosePayload& pose) noexcept {
  const Reject r = check_format(data, size, PacketType::kPose, kPosePayloadSize, header);
  if (r != Reject::kNone) return r;
  const std::uint8_t* p = data + kBridgeHeaderSize;
  pose.position_m = wire::get_vec3(p);
  pose.orientation = wire::get_quat(p + 24);
  pose.buttons = get_u32(p + 56);
  pose.flags = get_u32(p + 60);
  return Reject::kNone;
}

Reject decode_force(const std::uint8_t* data, std::size_t size, PacketHeader& header,
                    ForcePayload& force) noexcept {
  const Reject r = check_format(data, size, PacketType::kForce, kForcePayloadSize, header);
  if (r != Reject::kNone) return r;
  const std::uint8_t* p = data + kBridgeHeaderSize;
  force.force_n = wire::get_vec3(p);
  force.flags = get_u32(p + 24);
  force.pose_sequence = get_u32(p + 28);
  return Reject::kNone;
}

Reject SequenceFilter::check(const PacketHeader& header) noexcept {
  switch (order_.check(header.session, header.sequence, header.timestamp_ns)) {
    case wire::Order::kAccepted:
      return Reject::kNone;
    case wire::Order::kDuplicate:
      return Reject::kDuplicate;
    case wire::Order::kReordered:
      return Reject::kReordered;
    case wire::Order::kStale:
      return Reject::kStale;
  }
  return Reject::kStale;
}

}  // namespace terracut::haptics
