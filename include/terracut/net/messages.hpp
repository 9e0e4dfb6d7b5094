// The teleoperation link's messages: binary datagrams between the operator
// station (the haptic loop on the local model) and the remote station (the
// "real" world). Byte-level description: docs/teleoperation.md. All fields
// little-endian (core/wire.hpp); doubles are IEEE-754 binary64, heights
// binary32.
//
//   offset size type  field
//   0      4    u32   magic = 0x4D4D4354 (the bytes "TCMM")
//   4      2    u16   version = 2
//   6      2    u16   type (MessageType)
//   8      4    u32   link: chosen for the pair of stations (a packet of another link is "foreign")
//   12     4    u32   session: chosen by the sender at start (a new value = the station restarted)
//   16     4    u32   sequence: +1 per message of this type in the session (wraps)
//   20     4    u32   reserved, 0
//   24     8    u64   timestamp_ns: sender's station clock, nanoseconds
//   32     4    u32   payload_size
//   36     4    u32   reserved, 0
//   40     N    ...   payload (per type, below)
//   40+N   4    u32   crc32 (IEEE 802.3 / zlib) of bytes [0, 40+N)
//
// The codec works on caller buffers; the patch codec (PatchCodec) keeps its
// zstd contexts and scratch, so that once reserved it allocates nothing (the
// free encode_patch / decode_patch make fresh ones per call); it never
// throws, whatever the bytes.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <iterator>
#include <memory>
#include <span>
#include <string_view>
#include <vector>

#include "terracut/core/blade.hpp"
#include "terracut/core/enum_names.hpp"
#include "terracut/core/grid.hpp"
#include "terracut/core/math.hpp"
#include "terracut/core/wire.hpp"

namespace terracut::net {

inline constexpr std::uint32_t kMagic = 0x4D4D4354u;  // "TCMM" in memory order
/// 2: the command carries the operator's round trip, the measurement the
/// commands the remote received (2026-12: measured, not configured).
inline constexpr std::uint16_t kVersion = 2;
inline constexpr std::size_t kHeaderSize = 40;
inline constexpr std::size_t kCrcSize = 4;
inline constexpr std::size_t kCommandPayloadSize = 72;
inline constexpr std::size_t kMeasurementPayloadSize = 120;
inline constexpr std::size_t kPatchFixedSize = 32;  ///< before the compressed heights
inline constexpr std::size_t kEstimatePayloadSize = 32;
/// Largest patch, samples (2048 x 2048); a patch declaring more is refused.
inline constexpr std::int64_t kMaxPatchSamples = std::int64_t(1) << 22;

enum class MessageType : std::uint16_t {
  kCommand = 1,      ///< operator -> remote, unreliable sequenced, every tick
  kMeasurement = 2,  ///< remote -> operator, unreliable sequenced, every tick
  kPatch = 3,        ///< remote -> operator, reliable: heights of a rectangle
  kEstimate = 4,     ///< remote -> operator, reliable: the soil estimate
};
inline constexpr std::size_t kMessageTypeCount = 5;  // index = type value; [0] unused

/// The header fields a sender chooses (magic, version, sizes, CRC implied).
struct Header {
  MessageType type = MessageType::kCommand;
  std::uint32_t link = 0;
  std::uint32_t session = 0;
  std::uint32_t sequence = 0;
  std::uint64_t timestamp_ns = 0;
};

/// Command flag bits.
inline constexpr std::uint32_t kCommandLifted = 1u;  ///< the operator's tool was lifted (a jump, not a sweep)

/// Tool command (72 bytes): t_s f64 at 40, position f64[3] at 48,
/// orientation f64[4] (w, x, y, z) at 72, flags u32 at 104, round_trip_us
/// u32 at 108.
struct Command {
  double t_s = 0.0;  ///< operator loop time of the command, s
  BladePose pose{};  ///< commanded tool pose, world
  std::uint32_t flags = 0;
  /// The round trip the operator measured (its recent largest), us; 0:
  /// none yet. The remote's emulator and retransmissions use it.
  std::uint32_t round_trip_us = 0;
};

/// Measurement flag bits.
inline constexpr std::uint32_t kMeasurementHolding = 1u;  ///< link silent: the remote tool holds still

/// What the remote measured (120 bytes): t_s f64 at 40, command_sequence
/// u32 at 48, flags u32 at 52, position f64[3] at 56, orientation f64[4] at
/// 80, force f64[3] at 112, contact_length f64 at 136, cut_depth f64 at 144,
/// commands_received u32 at 152, reserved u32 at 156.
struct Measurement {
  double t_s = 0.0;                    ///< remote loop time, s
  std::uint32_t command_sequence = 0;  ///< the newest command it follows
  std::uint32_t flags = 0;
  BladePose pose{};             ///< measured tool pose, world
  Vec3 force_world_n{};         ///< measured force on the tool, world N
  double contact_length_m = 0;  ///< blade length in soil, m
  double cut_depth_m = 0;       ///< depth of cut, m
  /// Commands of this operator session that reached the remote so far
  /// (followed, or too old to follow): the operator's measure of its
  /// command loss.
  std::uint32_t commands_received = 0;
};

/// Heights of a rectangle (32 bytes + compressed data): t_s f64 at 40, c0,
/// r0, cols, rows i32 at 48..60, raw_size u32 at 64 (= cols x rows x 4),
/// compressed_size u32 at 68, then compressed_size bytes: the heights as
/// float32 little-endian, rows x cols row-major, compressed with zstd.
struct Patch {
  double t_s = 0.0;          ///< remote time of the measurement, s
  Rect rect{};               ///< samples [c0, c1) x [r0, r1) of the grid
  std::vector<float> heights;  ///< rect rows x cols, row-major, metres
};

/// The remote's estimate of the soil (32 bytes): t_s f64 at 40, force_scale
/// f64 at 48, variance f64 at 56, samples u32 at 64, flags u32 at 68.
struct Estimate {
  double t_s = 0.0;
  /// Measured force / the operator's model's force at the same cut: the
  /// factor the operator's cutting force should be multiplied by, > 0.
  double force_scale = 1.0;
  double variance = 0.0;       ///< RLS covariance of force_scale
  std::uint32_t samples = 0;   ///< samples the estimate has seen
  std::uint32_t flags = 0;
};

/// Why a datagram was rejected. Format reasons come from the decoders; the
/// order reasons from wire::SequenceFilter (core/wire.hpp), as in the device
/// bridge (haptics/bridge_protocol.hpp).
enum class Reject : std::uint8_t {
  kNone = 0,     ///< accepted
  kTruncated,    ///< shorter than its header, or than the size it declares
  kBadLength,    ///< longer than declared, or a payload size wrong for its type
  kBadMagic,     ///< the first four bytes are not "TCMM"
  kBadVersion,   ///< a protocol version this build does not speak
  kBadChecksum,  ///< CRC-32 mismatch
  kBadType,      ///< unknown type, or a type this station does not receive
  kForeign,      ///< well-formed, but of another link
  kBadPayload,   ///< non-finite values, a patch that does not decompress or lies outside the grid
  kDuplicate,    ///< same session and sequence as the last accepted one
  kReordered,    ///< older than the last accepted one
  kStale,        ///< newer sequence, older timestamp
};
/// Its names (core/enum_names.hpp: to_string, parse_enum), in the enum's
/// order: the link's rejected-datagram counts are keyed by them.
inline constexpr EnumName<Reject> kRejectNames[] = {
    {Reject::kNone, "none"},
    {Reject::kTruncated, "truncated"},
    {Reject::kBadLength, "bad_length"},
    {Reject::kBadMagic, "bad_magic"},
    {Reject::kBadVersion, "bad_version"},
    {Reject::kBadChecksum, "bad_checksum"},
    {Reject::kBadType, "bad_type"},
    {Reject::kForeign, "foreign"},
    {Reject::kBadPayload, "bad_payload"},
    {Reject::kDuplicate, "duplicate"},
    {Reject::kReordered, "reordered"},
    {Reject::kStale, "stale"},
};
constexpr std::span<const EnumName<Reject>> enum_names(Reject) { return kRejectNames; }
using terracut::to_string;
inline constexpr std::size_t kRejectReasonCount = std::size(kRejectNames);  // including kNone
static_assert(std::size_t(kRejectNames[kRejectReasonCount - 1].value) + 1 == kRejectReasonCount,
              "one name per reason, in the enum's order (RejectCounts is indexed by the value)");

static_assert(int(Reject::kBadChecksum) == int(wire::Frame::kBadChecksum) &&
                  int(Reject::kTruncated) == int(wire::Frame::kTruncated),
              "the framing reasons are wire::Frame's, in its order");

/// The reason for an ordering verdict (kNone when accepted).
Reject to_reject(wire::Order order);

/// Counts of rejected datagrams by reason (index = Reject value; [0] unused).
struct RejectCounts {
  std::array<std::int64_t, kRejectReasonCount> by_reason{};
  void add(Reject reason) noexcept { ++by_reason[static_cast<std::size_t>(reason)]; }
  std::int64_t operator[](Reject reason) const {
    return by_reason[static_cast<std::size_t>(reason)];
  }
  std::int64_t total() const;
};

/// Encoders: write the datagram into out and return its size. out must hold
/// kHeaderSize + payload + kCrcSize bytes (encode_patch: it resizes out).
/// header.type is set by each encoder.
std::size_t encode_command(Header header, const Command& command, std::uint8_t* out) noexcept;
std::size_t encode_measurement(Header header, const Measurement& m, std::uint8_t* out) noexcept;
std::size_t encode_estimate(Header header, const Estimate& e, std::uint8_t* out) noexcept;
/// patch.heights must hold rect.area() values. zstd level 1 (PatchCodec
/// below: the same without allocating per call). Returns 0 (and
/// leaves out empty) when the rectangle is empty or too large.
std::size_t encode_patch(Header header, const Patch& patch, std::vector<std::uint8_t>& out);

/// Checks the format (length, magic, version, declared size, CRC, link) and
/// fills header. Order of checks: length >= 4, magic, length >= header +
/// CRC, version, declared size (truncated / bad_length), CRC, type known,
/// link (foreign).
Reject decode_header(const std::uint8_t* data, std::size_t size, std::uint32_t link,
                     Header& header) noexcept;
/// Payload decoders, after decode_header accepted the datagram: kBadLength
/// for a wrong payload size, kBadPayload for non-finite values.
Reject decode_command(const std::uint8_t* data, std::size_t size, Command& out) noexcept;
Reject decode_measurement(const std::uint8_t* data, std::size_t size, Measurement& out) noexcept;
Reject decode_estimate(const std::uint8_t* data, std::size_t size, Estimate& out) noexcept;
/// kBadPayload also for a rectangle with no samples or above
/// kMaxPatchSamples, a raw size that does not match, data that does not
/// decompress to exactly raw_size bytes, or a non-finite height. out.heights
/// is resized (reused across calls).
Reject decode_patch(const std::uint8_t* data, std::size_t size, Patch& out);

/// Size of the largest patch datagram of `samples` heights, bytes (what an
/// encoder's buffer needs).
std::size_t patch_datagram_bound(std::size_t samples);

/// encode_patch and decode_patch with their zstd contexts and scratch kept
/// between calls (the free functions make fresh ones each call): a station
/// that reserved its working patch size encodes and decodes without
/// allocating. Same rules and results as the free functions.
class PatchCodec {
 public:
  PatchCodec();
  ~PatchCodec();
  PatchCodec(const PatchCodec&) = delete;
  PatchCodec& operator=(const PatchCodec&) = delete;
  /// Makes room now for patches of up to `samples` heights (the scratch and
  /// zstd's working memory for that size), samples <= kMaxPatchSamples.
  void reserve(std::size_t samples);
  std::size_t encode(Header header, const Patch& patch, std::vector<std::uint8_t>& out);
  Reject decode(const std::uint8_t* data, std::size_t size, Patch& out);

 private:
  struct Contexts;
  std::unique_ptr<Contexts> z_;
  std::vector<std::uint8_t> raw_;
};

}  // namespace terracut::net
