// Encoding, decoding and ordering of bridge datagrams (bridge_protocol.hpp).
// Every field is written and read byte by byte in little-endian order, so the
// code is independent of the host's endianness and alignment.
#include "terracut/haptics/bridge_protocol.hpp"

#include <cstring>

namespace terracut::haptics {
namespace {

// CRC-32 table (reflected polynomial 0xEDB88320), built at compile time.
constexpr std::array<std::uint32_t, 256> make_crc_table() {
  std::array<std::uint32_t, 256> table{};
  for (std::uint32_t i = 0; i < 256; ++i) {
    std::uint32_t c = i;
    for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    table[i] = c;
  }
  return table;
}
constexpr std::array<std::uint32_t, 256> kCrcTable = make_crc_table();

void put_u16(std::uint8_t* p, std::uint16_t v) {
  p[0] = static_cast<std::uint8_t>(v);
  p[1] = static_cast<std::uint8_t>(v >> 8);
}
void put_u32(std::uint8_t* p, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}
void put_u64(std::uint8_t* p, std::uint64_t v) {
  for (int i = 0; i < 8; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}
void put_f64(std::uint8_t* p, double v) {
  std::uint64_t bits = 0;
  std::memcpy(&bits, &v, sizeof bits);
  put_u64(p, bits);
}
std::uint16_t get_u16(const std::uint8_t* p) {
  return static_cast<std::uint16_t>(p[0] | (p[1] << 8));
}
std::uint32_t get_u32(const std::uint8_t* p) {
  std::uint32_t v = 0;
  for (int i = 3; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}
std::uint64_t get_u64(const std::uint8_t* p) {
  std::uint64_t v = 0;
  for (int i = 7; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}
double get_f64(const std::uint8_t* p) {
  const std::uint64_t bits = get_u64(p);
  double v = 0.0;
  std::memcpy(&v, &bits, sizeof v);
  return v;
}

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
  const std::size_t body = kBridgeHeaderSize + payload_size;
  put_u32(out + body, crc32(out, body));
  return body + kBridgeCrcSize;
}

// The format checks shared by both packet types (see decode_pose's comment
// for the order). On kNone, header is filled.
Reject check_format(const std::uint8_t* data, std::size_t size, PacketType want,
                    std::size_t want_payload, PacketHeader& header) {
  if (size < 4) return Reject::kTruncated;
  if (get_u32(data) != kBridgeMagic) return Reject::kBadMagic;
  if (size < kBridgeHeaderSize + kBridgeCrcSize) return Reject::kTruncated;
  if (get_u16(data + 4) != kBridgeVersion) return Reject::kBadVersion;
  const std::uint64_t declared = get_u32(data + 24);
  const std::uint64_t expected = kBridgeHeaderSize + declared + kBridgeCrcSize;
  if (size < expected) return Reject::kTruncated;
  if (size > expected) return Reject::kBadLength;
  const std::size_t body = kBridgeHeaderSize + static_cast<std::size_t>(declared);
  if (crc32(data, body) != get_u32(data + body)) return Reject::kBadChecksum;
  if (get_u16(data + 6) != static_cast<std::uint16_t>(want)) return Reject::kBadType;
  if (declared != want_payload) return Reject::kBadLength;
  header.session = get_u32(data + 8);
  header.sequence = get_u32(data + 12);
  header.timestamp_ns = get_u64(data + 16);
  return Reject::kNone;
}

}  // namespace

std::uint32_t crc32(const std::uint8_t* data, std::size_t size) noexcept {
  std::uint32_t c = 0xFFFFFFFFu;
  for (std::size_t i = 0; i < size; ++i) c = kCrcTable[(c ^ data[i]) & 0xFFu] ^ (c >> 8);
  return c ^ 0xFFFFFFFFu;
}

std::size_t encode_pose(const PacketHeader& header, const PosePayload& pose,
                        std::uint8_t* out) noexcept {
  std::uint8_t* p = out + kBridgeHeaderSize;
  put_f64(p + 0, pose.position_m.x);
  put_f64(p + 8, pose.position_m.y);
  put_f64(p + 16, pose.position_m.z);
  put_f64(p + 24, pose.orientation.w);
  put_f64(p + 32, pose.orientation.x);
  put_f64(p + 40, pose.orientation.y);
  put_f64(p + 48, pose.orientation.z);
  put_u32(p + 56, pose.buttons);
  put_u32(p + 60, pose.flags);
  return finish_packet(header, PacketType::kPose, kPosePayloadSize, out);
}

std::size_t encode_force(const PacketHeader& header, const ForcePayload& force,
                         std::uint8_t* out) noexcept {
  std::uint8_t* p = out + kBridgeHeaderSize;
  put_f64(p + 0, force.force_n.x);
  put_f64(p + 8, force.force_n.y);
  put_f64(p + 16, force.force_n.z);
  put_u32(p + 24, force.flags);
  put_u32(p + 28, force.pose_sequence);
  return finish_packet(header, PacketType::kForce, kForcePayloadSize, out);
}

std::string_view to_string(Reject reason) {
  switch (reason) {
    case Reject::kNone:
      return "none";
    case Reject::kTruncated:
      return "truncated";
    case Reject::kBadLength:
      return "bad_length";
    case Reject::kBadMagic:
      return "bad_magic";
    case Reject::kBadVersion:
      return "bad_version";
    case Reject::kBadChecksum:
      return "bad_checksum";
    case Reject::kBadType:
      return "bad_type";
    case Reject::kDuplicate:
      return "duplicate";
    case Reject::kReordered:
      return "reordered";
    case Reject::kStale:
      return "stale";
  }
  return "unknown";
}

Reject decode_pose(const std::uint8_t* data, std::size_t size, PacketHeader& header,
                   PosePayload& pose) noexcept {
  const Reject r = check_format(data, size, PacketType::kPose, kPosePayloadSize, header);
  if (r != Reject::kNone) return r;
  const std::uint8_t* p = data + kBridgeHeaderSize;
  pose.position_m = {get_f64(p + 0), get_f64(p + 8), get_f64(p + 16)};
  pose.orientation = {get_f64(p + 24), get_f64(p + 32), get_f64(p + 40), get_f64(p + 48)};
  pose.buttons = get_u32(p + 56);
  pose.flags = get_u32(p + 60);
  return Reject::kNone;
}

Reject decode_force(const std::uint8_t* data, std::size_t size, PacketHeader& header,
                    ForcePayload& force) noexcept {
  const Reject r = check_format(data, size, PacketType::kForce, kForcePayloadSize, header);
  if (r != Reject::kNone) return r;
  const std::uint8_t* p = data + kBridgeHeaderSize;
  force.force_n = {get_f64(p + 0), get_f64(p + 8), get_f64(p + 16)};
  force.flags = get_u32(p + 24);
  force.pose_sequence = get_u32(p + 28);
  return Reject::kNone;
}

Reject SequenceFilter::check(const PacketHeader& header) noexcept {
  // Another session (or the first packet): a device process (re)started.
  if (!has_session_ || header.session != session_) {
    has_session_ = true;
    new_session_ = true;
    session_ = header.session;
    last_sequence_ = header.sequence;
    last_timestamp_ns_ = header.timestamp_ns;
    ++sessions_;
    return Reject::kNone;
  }
  // Serial-number arithmetic, so the sequence may wrap around 2^32.
  const std::int32_t ahead = static_cast<std::int32_t>(header.sequence - last_sequence_);
  if (ahead == 0) return Reject::kDuplicate;
  if (ahead < 0) return Reject::kReordered;
  if (header.timestamp_ns < last_timestamp_ns_) return Reject::kStale;
  new_session_ = false;
  lost_ += ahead - 1;
  last_sequence_ = header.sequence;
  last_timestamp_ns_ = header.timestamp_ns;
  return Reject::kNone;
}

}  // namespace terracut::haptics
