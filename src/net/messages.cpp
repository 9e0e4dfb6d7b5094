// Encoding and decoding of the teleoperation link's datagrams (messages.hpp).
#include "terracut/net/messages.hpp"

#include <zstd.h>

#include <algorithm>
#include <cmath>
#include <new>

#include "terracut/core/wire.hpp"

namespace terracut::net {
namespace {

using wire::get_f32;
using wire::get_f64;
using wire::get_u16;
using wire::get_u32;
using wire::get_u64;
using wire::put_f32;
using wire::put_f64;
using wire::put_u16;
using wire::put_u32;
using wire::put_u64;

// Header and CRC around a payload already written at out + kHeaderSize.
std::size_t finish(const Header& h, MessageType type, std::size_t payload, std::uint8_t* out) {
  put_u32(out + 0, kMagic);
  put_u16(out + 4, kVersion);
  put_u16(out + 6, static_cast<std::uint16_t>(type));
  put_u32(out + 8, h.link);
  put_u32(out + 12, h.session);
  put_u32(out + 16, h.sequence);
  put_u32(out + 20, 0);
  put_u64(out + 24, h.timestamp_ns);
  put_u32(out + 32, static_cast<std::uint32_t>(payload));
  put_u32(out + 36, 0);
  return wire::seal_frame(out, kHeaderSize + payload);
}

void put_pose(std::uint8_t* p, const BladePose& pose) {
  wire::put_vec3(p, pose.position_m);
  wire::put_quat(p + 24, pose.orientation);
}
BladePose get_pose(const std::uint8_t* p) {
  BladePose pose;
  pose.position_m = wire::get_vec3(p);
  pose.orientation = wire::get_quat(p + 24);
  return pose;
}
bool finite_pose(const BladePose& pose) {
  return is_finite(pose.position_m) && is_finite(pose.orientation);
}

// The payload of an accepted datagram, and its declared size.
const std::uint8_t* payload_of(const std::uint8_t* data) { return data + kHeaderSize; }
std::size_t payload_size(const std::uint8_t* data) { return get_u32(data + 32); }

}  // namespace

Reject to_reject(wire::Order order) {
  switch (order) {
    case wire::Order::kAccepted: return Reject::kNone;
    case wire::Order::kDuplicate: return Reject::kDuplicate;
    case wire::Order::kReordered: return Reject::kReordered;
    case wire::Order::kStale: return Reject::kStale;
  }
  return Reject::kStale;
}

std::int64_t RejectCounts::total() const {
  std::int64_t sum = 0;
  for (std::size_t i = 1; i < kRejectReasonCount; ++i) sum += by_reason[i];
  return sum;
}

std::size_t encode_command(Header header, const Command& c, std::uint8_t* out) noexcept {
  std::uint8_t* p = out + kHeaderSize;
  put_f64(p + 0, c.t_s);
  put_pose(p + 8, c.pose);
  put_u32(p + 64, c.flags);
  put_u32(p + 68, c.round_trip_us);
  return finish(header, MessageType::kCommand, kCommandPayloadSize, out);
}

std::size_t encode_measurement(Header header, const Measurement& m, std::uint8_t* out) noexcept {
  std::uint8_t* p = out + kHeaderSize;
  put_f64(p + 0, m.t_s);
  put_u32(p + 8, m.command_sequence);
  put_u32(p + 12, m.flags);
  put_pose(p + 16, m.pose);
  wire::put_vec3(p + 72, m.force_world_n);
  put_f64(p + 96, m.contact_length_m);
  put_f64(p + 104, m.cut_depth_m);
  put_u32(p + 112, m.commands_received);
  put_u32(p + 116, 0);
  return finish(header, MessageType::kMeasurement, kMeasurementPayloadSize, out);
}

std::size_t encode_estimate(Header header, const Estimate& e, std::uint8_t* out) noexcept {
  std::uint8_t* p = out + kHeaderSize;
  put_f64(p + 0, e.t_s);
  put_f64(p + 8, e.force_scale);
  put_f64(p + 16, e.variance);
  put_u32(p + 24, e.samples);
  put_u32(p + 28, e.flags);
  return finish(header, MessageType::kEstimate, kEstimatePayloadSize, out);
}

struct PatchCodec::Contexts {
  Contexts() : c(ZSTD_createCCtx()), d(ZSTD_createDCtx()) {
    if (!c || !d) {
      ZSTD_freeCCtx(c);
      ZSTD_freeDCtx(d);
      throw std::bad_alloc();
    }
  }
  ~Contexts() {
    ZSTD_freeCCtx(c);
    ZSTD_freeDCtx(d);
  }
  ZSTD_CCtx* c;
  ZSTD_DCtx* d;
};

PatchCodec::PatchCodec() : z_(std::make_unique<Contexts>()) {}
PatchCodec::~PatchCodec() = default;

std::size_t patch_datagram_bound(std::size_t samples) {
  return kHeaderSize + kPatchFixedSize + ZSTD_compressBound(samples * 4) + kCrcSize;
}

void PatchCodec::reserve(std::size_t samples) {
  samples = std::min<std::size_t>(std::max<std::size_t>(samples, 1), kMaxPatchSamples);
  raw_.assign(samples * 4, 0);
  // One compression of that size sizes zstd's working memory.
  std::vector<std::uint8_t> out(ZSTD_compressBound(raw_.size()));
  (void)ZSTD_compressCCtx(z_->c, out.data(), out.size(), raw_.data(), raw_.size(), 1);
}

std::size_t PatchCodec::encode(Header header, const Patch& patch, std::vector<std::uint8_t>& out) {
  out.clear();
  const std::int64_t n = patch.rect.area();
  if (n <= 0 || n > kMaxPatchSamples || patch.heights.size() != std::size_t(n)) return 0;
  // The heights as little-endian float32, then compressed.
  raw_.resize(std::size_t(n) * 4);
  for (std::int64_t i = 0; i < n; ++i) put_f32(raw_.data() + 4 * i, patch.heights[std::size_t(i)]);
  const std::size_t bound = ZSTD_compressBound(raw_.size());
  out.resize(patch_datagram_bound(std::size_t(n)));
  std::uint8_t* p = out.data() + kHeaderSize;
  const std::size_t packed =
      ZSTD_compressCCtx(z_->c, p + kPatchFixedSize, bound, raw_.data(), raw_.size(), 1);
  if (ZSTD_isError(packed)) {
    out.clear();
    return 0;
  }
  put_f64(p + 0, patch.t_s);
  put_u32(p + 8, static_cast<std::uint32_t>(patch.rect.c0));
  put_u32(p + 12, static_cast<std::uint32_t>(patch.rect.r0));
  put_u32(p + 16, static_cast<std::uint32_t>(patch.rect.c1 - patch.rect.c0));
  put_u32(p + 20, static_cast<std::uint32_t>(patch.rect.r1 - patch.rect.r0));
  put_u32(p + 24, static_cast<std::uint32_t>(raw_.size()));
  put_u32(p + 28, static_cast<std::uint32_t>(packed));
  const std::size_t size = finish(header, MessageType::kPatch, kPatchFixedSize + packed, out.data());
  out.resize(size);
  return size;
}

std::size_t encode_patch(Header header, const Patch& patch, std::vector<std::uint8_t>& out) {
  PatchCodec codec;
  return codec.encode(header, patch, out);
}

Reject decode_header(const std::uint8_t* data, std::size_t size, std::uint32_t link,
                     Header& header) noexcept {
  std::size_t declared = 0;
  const wire::Frame frame =
      wire::check_frame(data, size, {kMagic, kVersion, kHeaderSize, 32}, declared);
  // wire::Frame's values are the first of Reject's, in the same order.
  if (frame != wire::Frame::kOk) return static_cast<Reject>(frame);
  const std::uint16_t type = get_u16(data + 6);
  if (type == 0 || type >= kMessageTypeCount) return Reject::kBadType;
  if (get_u32(data + 8) != link) return Reject::kForeign;
  header.type = static_cast<MessageType>(type);
  header.link = link;
  header.session = get_u32(data + 12);
  header.sequence = get_u32(data + 16);
  header.timestamp_ns = get_u64(data + 24);
  return Reject::kNone;
}

Reject decode_command(const std::uint8_t* data, std::size_t, Command& out) noexcept {
  if (payload_size(data) != kCommandPayloadSize) return Reject::kBadLength;
  const std::uint8_t* p = payload_of(data);
  out.t_s = get_f64(p + 0);
  out.pose = get_pose(p + 8);
  out.flags = get_u32(p + 64);
  out.round_trip_us = get_u32(p + 68);
  if (!std::isfinite(out.t_s) || !finite_pose(out.pose)) return Reject::kBadPayload;
  return Reject::kNone;
}

Reject decode_measurement(const std::uint8_t* data, std::size_t, Measurement& out) noexcept {
  if (payload_size(data) != kMeasurementPayloadSize) return Reject::kBadLength;
  const std::uint8_t* p = payload_of(data);
  out.t_s = get_f64(p + 0);
  out.command_sequence = get_u32(p + 8);
  out.flags = get_u32(p + 12);
  out.pose = get_pose(p + 16);
  out.force_world_n = wire::get_vec3(p + 72);
  out.contact_length_m = get_f64(p + 96);
  out.cut_depth_m = get_f64(p + 104);
  out.commands_received = get_u32(p + 112);
  if (!std::isfinite(out.t_s) || !finite_pose(out.pose) || !is_finite(out.force_world_n) ||
      !std::isfinite(out.contact_length_m) || !std::isfinite(out.cut_depth_m))
    return Reject::kBadPayload;
  return Reject::kNone;
}

Reject decode_estimate(const std::uint8_t* data, std::size_t, Estimate& out) noexcept {
  if (payload_size(data) != kEstimatePayloadSize) return Reject::kBadLength;
  const std::uint8_t* p = payload_of(data);
  out.t_s = get_f64(p + 0);
  out.force_scale = get_f64(p + 8);
  out.variance = get_f64(p + 16);
  out.samples = get_u32(p + 24);
  out.flags = get_u32(p + 28);
  if (!std::isfinite(out.t_s) || !(out.force_scale > 0.0) || !std::isfinite(out.force_scale) ||
      !std::isfinite(out.variance) || out.variance < 0.0)
    return Reject::kBadPayload;
  return Reject::kNone;
}

Reject decode_patch(const std::uint8_t* data, std::size_t size, Patch& out) {
  PatchCodec codec;
  return codec.decode(data, size, out);
}

Reject PatchCodec::decode(const std::uint8_t* data, std::size_t, Patch& out) {
  const std::size_t payload = payload_size(data);
  if (payload < kPatchFixedSize) return Reject::kBadLength;
  const std::uint8_t* p = payload_of(data);
  const std::int64_t c0 = static_cast<std::int32_t>(get_u32(p + 8));
  const std::int64_t r0 = static_cast<std::int32_t>(get_u32(p + 12));
  const std::int64_t cols = static_cast<std::int32_t>(get_u32(p + 16));
  const std::int64_t rows = static_cast<std::int32_t>(get_u32(p + 20));
  const std::uint64_t raw_size = get_u32(p + 24);
  const std::uint64_t packed = get_u32(p + 28);
  if (packed != payload - kPatchFixedSize) return Reject::kBadLength;
  if (cols < 1 || rows < 1 || c0 < 0 || r0 < 0 || cols * rows > kMaxPatchSamples ||
      c0 + cols > (std::int64_t(1) << 30) || r0 + rows > (std::int64_t(1) << 30))
    return Reject::kBadPayload;
  const std::int64_t n = cols * rows;
  if (raw_size != std::uint64_t(n) * 4) return Reject::kBadPayload;
  // The frame must say exactly how much it holds, and hold exactly that.
  const unsigned long long content = ZSTD_getFrameContentSize(p + kPatchFixedSize, packed);
  if (content != raw_size) return Reject::kBadPayload;
  try {
    raw_.resize(raw_size);
    const std::size_t got =
        ZSTD_decompressDCtx(z_->d, raw_.data(), raw_.size(), p + kPatchFixedSize, packed);
    if (ZSTD_isError(got) || got != raw_size) return Reject::kBadPayload;
    out.heights.resize(std::size_t(n));
    for (std::int64_t i = 0; i < n; ++i) {
      const float h = get_f32(raw_.data() + 4 * i);
      if (!std::isfinite(h)) return Reject::kBadPayload;
      out.heights[std::size_t(i)] = h;
    }
  } catch (const std::bad_alloc&) {
    return Reject::kBadPayload;
  }
  out.t_s = get_f64(p + 0);
  if (!std::isfinite(out.t_s)) return Reject::kBadPayload;
  out.rect = {int(c0), int(r0), int(c0 + cols), int(r0 + rows)};
  return Reject::kNone;
}

}  // namespace terracut::net
