// Byte-level helpers shared by every wire format of terracut (the device
// bridge, haptics/bridge_protocol.hpp; the teleoperation link,
// net/messages.hpp): little-endian fields written and read byte by byte (so
// the code is independent of the host's endianness and alignment), the
// CRC-32 that checks a datagram, and the ordering rule that rejects
// duplicated, reordered and stale datagrams of a session. Nothing here
// allocates or throws.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>

#include "terracut/core/math.hpp"

namespace terracut::wire {

inline void put_u16(std::uint8_t* p, std::uint16_t v) {
  p[0] = static_cast<std::uint8_t>(v);
  p[1] = static_cast<std::uint8_t>(v >> 8);
}
inline void put_u32(std::uint8_t* p, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}
inline void put_u64(std::uint8_t* p, std::uint64_t v) {
  for (int i = 0; i < 8; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}
inline void put_f64(std::uint8_t* p, double v) {
  std::uint64_t bits = 0;
  std::memcpy(&bits, &v, sizeof bits);
  put_u64(p, bits);
}
inline void put_f32(std::uint8_t* p, float v) {
  std::uint32_t bits = 0;
  std::memcpy(&bits, &v, sizeof bits);
  put_u32(p, bits);
}
inline std::uint16_t get_u16(const std::uint8_t* p) {
  return static_cast<std::uint16_t>(p[0] | (p[1] << 8));
}
inline std::uint32_t get_u32(const std::uint8_t* p) {
  std::uint32_t v = 0;
  for (int i = 3; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}
inline std::uint64_t get_u64(const std::uint8_t* p) {
  std::uint64_t v = 0;
  for (int i = 7; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}
inline double get_f64(const std::uint8_t* p) {
  const std::uint64_t bits = get_u64(p);
  double v = 0.0;
  std::memcpy(&v, &bits, sizeof v);
  return v;
}
inline float get_f32(const std::uint8_t* p) {
  const std::uint32_t bits = get_u32(p);
  float v = 0.0f;
  std::memcpy(&v, &bits, sizeof v);
  return v;
}

/// A vector as three doubles (x, y, z) and a rotation as four (w, x, y, z).
inline void put_vec3(std::uint8_t* p, Vec3 v) {
  put_f64(p + 0, v.x);
  put_f64(p + 8, v.y);
  put_f64(p + 16, v.z);
}
inline void put_quat(std::uint8_t* p, Quat q) {
  put_f64(p + 0, q.w);
  put_f64(p + 8, q.x);
  put_f64(p + 16, q.y);
  put_f64(p + 24, q.z);
}
inline Vec3 get_vec3(const std::uint8_t* p) { return {get_f64(p), get_f64(p + 8), get_f64(p + 16)}; }
inline Quat get_quat(const std::uint8_t* p) {
  return {get_f64(p), get_f64(p + 8), get_f64(p + 16), get_f64(p + 24)};
}

/// CRC-32 (IEEE 802.3, reflected, polynomial 0xEDB88320, init and final xor
/// 0xFFFFFFFF: zlib's crc32 and Python's zlib.crc32).
std::uint32_t crc32(const std::uint8_t* data, std::size_t size) noexcept;

/// Where a datagram's framing is: its magic and version, its header size
/// and where the header says how long the payload is (u32). A frame is
/// header, payload, CRC-32 of both (u32) -- the bridge's and the link's.
struct FrameLayout {
  std::uint32_t magic = 0;       ///< at offset 0
  std::uint16_t version = 0;     ///< at offset 4
  std::size_t header_size = 0;   ///< bytes before the payload
  std::size_t size_offset = 0;   ///< offset of the payload size field
};

/// What the framing check says of a datagram (same order as the first
/// rejection reasons of both protocols).
enum class Frame : std::uint8_t {
  kOk = 0,
  kTruncated,    ///< shorter than its header, or than the size it declares
  kBadLength,    ///< longer than declared
  kBadMagic,
  kBadVersion,
  kBadChecksum,
};

/// Checks length, magic, version, declared size and CRC, in that order:
/// length >= 4, magic, length >= header + CRC, version, declared size, CRC.
/// On kOk, payload_size is the declared payload size.
Frame check_frame(const std::uint8_t* data, std::size_t size, const FrameLayout& layout,
                  std::size_t& payload_size) noexcept;

/// Writes the CRC-32 of the body bytes [0, body) after them; returns the
/// frame's size (body + 4).
inline std::size_t seal_frame(std::uint8_t* out, std::size_t body) noexcept {
  put_u32(out + body, crc32(out, body));
  return body + 4;
}

/// What the ordering rule says of a datagram.
enum class Order : std::uint8_t {
  kAccepted,   ///< newer than the last accepted one, or the first of a new session
  kDuplicate,  ///< same session and sequence as the last accepted one
  kReordered,  ///< an older sequence number than the last accepted one
  kStale,      ///< a newer sequence but an older timestamp
};

/// Accepts only datagrams newer than the last accepted one of the same
/// session. A datagram of another session starts a new session (the sender
/// restarted): its sequence and time are taken as they come. Sequence
/// numbers compare in serial-number arithmetic, so they may wrap around 2^32.
class SequenceFilter {
 public:
  Order check(std::uint32_t session, std::uint32_t sequence, std::uint64_t timestamp_ns) noexcept;

  /// True when the last accepted datagram started a new session (the first one included).
  bool new_session() const { return new_session_; }
  /// Sessions seen (1 after the first accepted datagram).
  std::int64_t sessions() const { return sessions_; }
  /// Datagrams skipped by gaps in the sequence numbers (lost or never sent).
  std::int64_t lost() const { return lost_; }
  std::uint32_t last_sequence() const { return last_sequence_; }
  std::uint32_t session() const { return session_; }

 private:
  bool has_session_ = false;
  bool new_session_ = false;
  std::uint32_t session_ = 0;
  std::uint32_t last_sequence_ = 0;
  std::uint64_t last_timestamp_ns_ = 0;
  std::int64_t sessions_ = 0;
  std::int64_t lost_ = 0;
};

}  // namespace terracut::wire
