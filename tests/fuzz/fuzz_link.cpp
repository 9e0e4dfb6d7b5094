// Fuzz target: the teleoperation link's messages (net/messages.hpp) -- the
// header and payload decoders of every message type, the zstd patch
// included.
//
// The input is a list of records, each a control byte, a length (two bytes,
// little-endian) and that many bytes (fewer at the end of the input). The
// control byte's low two bits choose what the bytes become:
//  0: a datagram as it is (the decoders' framing checks see raw bytes);
//  1: a datagram whose framing is repaired (magic, version, this link, the
//     type from the control byte, the declared size, the CRC), so the
//     payload decoders see arbitrary payloads of every type;
//  2: a patch built from the bytes (a rectangle of up to 16 x 16 samples and
//     their heights) and encoded, then (control >> 2) of its bytes flipped
//     at positions the following bytes give, and its CRC repaired, so the
//     zstd decoder sees nearly valid frames;
//  3: as 2 with no flips.
//
// Checked: decoding never reads outside the datagram (the sanitizers); an
// accepted message holds finite values (a patch: rect.area() finite heights
// inside the declared rectangle); decoding what an accepted message encodes
// to gives it back bit for bit; an unflipped patch (mode 3) is accepted and
// gives back the heights it was built from.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "fuzz_file.hpp"
#include "terracut/core/wire.hpp"
#include "terracut/net/messages.hpp"

namespace {

using namespace terracut;
using namespace terracut::net;
using terracut::fuzz::check;

constexpr std::uint32_t kLink = 7;
constexpr const char* kTarget = "fuzz_link";

bool finite(const BladePose& p) { return is_finite(p.position_m) && is_finite(p.orientation); }

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }
bool same_bits(const Vec3& a, const Vec3& b) { return same_bits(a.x, b.x) && same_bits(a.y, b.y) && same_bits(a.z, b.z); }
bool same_bits(const BladePose& a, const BladePose& b) {
  return same_bits(a.position_m, b.position_m) && same_bits(a.orientation.w, b.orientation.w) &&
         same_bits(a.orientation.x, b.orientation.x) && same_bits(a.orientation.y, b.orientation.y) &&
         same_bits(a.orientation.z, b.orientation.z);
}

// Decodes a datagram; for an accepted one checks its values and that it
// survives a re-encoding. Returns the verdict.
Reject decode_and_check(const std::uint8_t* data, std::size_t size, Patch& patch) {
  Header h;
  const Reject header = decode_header(data, size, kLink, h);
  if (header != Reject::kNone) return header;
  std::uint8_t again[kHeaderSize + kMeasurementPayloadSize + kCrcSize];
  switch (h.type) {
    case MessageType::kCommand: {
      Command c;
      const Reject r = decode_command(data, size, c);
      if (r != Reject::kNone) return r;
      check(std::isfinite(c.t_s) && finite(c.pose), kTarget, "an accepted command holds a non-finite value");
      const std::size_t n = encode_command(h, c, again);
      Header h2;
      Command c2;
      check(decode_header(again, n, kLink, h2) == Reject::kNone && decode_command(again, n, c2) == Reject::kNone,
            kTarget, "a re-encoded command is refused");
      check(same_bits(c.t_s, c2.t_s) && same_bits(c.pose, c2.pose) && c.flags == c2.flags && c.round_trip_us == c2.round_trip_us, kTarget,
            "a command does not survive re-encoding");
      return r;
    }
    case MessageType::kMeasurement: {
      Measurement m;
      const Reject r = decode_measurement(data, size, m);
      if (r != Reject::kNone) return r;
      check(std::isfinite(m.t_s) && finite(m.pose) && is_finite(m.force_world_n) &&
                std::isfinite(m.contact_length_m) && std::isfinite(m.cut_depth_m),
            kTarget, "an accepted measurement holds a non-finite value");
      const std::size_t n = encode_measurement(h, m, again);
      Header h2;
      Measurement m2;
      check(decode_header(again, n, kLink, h2) == Reject::kNone &&
                decode_measurement(again, n, m2) == Reject::kNone,
            kTarget, "a re-encoded measurement is refused");
      check(same_bits(m.t_s, m2.t_s) && same_bits(m.pose, m2.pose) && same_bits(m.force_world_n, m2.force_world_n) &&
                m.command_sequence == m2.command_sequence && m.flags == m2.flags &&
                m.commands_received == m2.commands_received,
            kTarget, "a measurement does not survive re-encoding");
      return r;
    }
    case MessageType::kEstimate: {
      Estimate e;
      const Reject r = decode_estimate(data, size, e);
      if (r != Reject::kNone) return r;
      check(std::isfinite(e.t_s) && std::isfinite(e.force_scale) && std::isfinite(e.variance), kTarget,
            "an accepted estimate holds a non-finite value");
      const std::size_t n = encode_estimate(h, e, again);
      Header h2;
      Estimate e2;
      check(decode_header(again, n, kLink, h2) == Reject::kNone && decode_estimate(again, n, e2) == Reject::kNone,
            kTarget, "a re-encoded estimate is refused");
      check(same_bits(e.force_scale, e2.force_scale) && same_bits(e.variance, e2.variance) &&
                e.samples == e2.samples,
            kTarget, "an estimate does not survive re-encoding");
      return r;
    }
    case MessageType::kPatch: {
      const Reject r = decode_patch(data, size, patch);
      if (r != Reject::kNone) return r;
      check(!patch.rect.empty() && std::int64_t(patch.heights.size()) == patch.rect.area(), kTarget,
            "an accepted patch does not hold its rectangle's heights");
      for (float v : patch.heights) check(std::isfinite(v), kTarget, "an accepted patch holds a non-finite height");
      std::vector<std::uint8_t> encoded;
      const std::size_t n = encode_patch(h, patch, encoded);
      check(n > 0, kTarget, "an accepted patch cannot be re-encoded");
      Header h2;
      Patch p2;
      check(decode_header(encoded.data(), n, kLink, h2) == Reject::kNone &&
                decode_patch(encoded.data(), n, p2) == Reject::kNone,
            kTarget, "a re-encoded patch is refused");
      check(p2.rect == patch.rect &&
                std::memcmp(p2.heights.data(), patch.heights.data(), patch.heights.size() * sizeof(float)) == 0,
            kTarget, "a patch does not survive re-encoding");
      return r;
    }
  }
  return Reject::kBadType;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Patch patch;  // reused, as the operator station reuses its own
  std::size_t at = 0;
  while (at + 3 <= size) {
    const std::uint8_t control = data[at];
    const std::size_t length = std::size_t(data[at + 1]) | (std::size_t(data[at + 2]) << 8);
    at += 3;
    const std::size_t take = std::min(length, size - at);
    const std::uint8_t* bytes = data + at;
    at += take;
    const int mode = control & 3;
    if (mode == 0) {
      std::vector<std::uint8_t> datagram(bytes, bytes + take);  // its own allocation: ASan sees overreads
      decode_and_check(datagram.data(), datagram.size(), patch);
    } else if (mode == 1) {
      std::vector<std::uint8_t> datagram(kHeaderSize + take + kCrcSize, 0);
      std::copy(bytes, bytes + take, datagram.begin() + kHeaderSize);
      wire::put_u32(datagram.data() + 0, kMagic);
      wire::put_u16(datagram.data() + 4, kVersion);
      wire::put_u16(datagram.data() + 6, std::uint16_t(1 + (control >> 2) % 4));
      wire::put_u32(datagram.data() + 8, kLink);
      wire::put_u32(datagram.data() + 32, std::uint32_t(take));
      wire::seal_frame(datagram.data(), kHeaderSize + take);
      decode_and_check(datagram.data(), datagram.size(), patch);
    } else {
      if (take < 4) continue;
      Patch built;
      const int cols = 1 + bytes[0] % 16, rows = 1 + bytes[1] % 16;
      built.rect = {bytes[2] % 64, bytes[3] % 64, 0, 0};
      built.rect.c1 = built.rect.c0 + cols;
      built.rect.r1 = built.rect.r0 + rows;
      built.heights.resize(std::size_t(cols * rows));
      const std::size_t extra = take - 4;
      for (std::size_t k = 0; k < built.heights.size(); ++k)
        built.heights[k] = float((extra > 0 ? bytes[4 + k % extra] : 1u) * (k + 1) % 997) * 1e-3f;
      Header h;
      h.type = MessageType::kPatch;
      h.link = kLink;
      std::vector<std::uint8_t> encoded;
      const std::size_t n = encode_patch(h, built, encoded);
      check(n > 0, kTarget, "a small patch cannot be encoded");
      encoded.resize(n);
      const int flips = mode == 3 ? 0 : control >> 2;
      for (int f = 0; f < flips && 4 + 2 * f + 1 < int(take); ++f) {
        const std::size_t pos = (std::size_t(bytes[4 + 2 * f]) * 251 + bytes[5 + 2 * f]) % (n - kCrcSize);
        encoded[pos] ^= std::uint8_t(1u << (bytes[5 + 2 * f] % 8));
      }
      wire::seal_frame(encoded.data(), n - kCrcSize);
      const Reject r = decode_and_check(encoded.data(), encoded.size(), patch);
      if (mode == 3) {
        check(r == Reject::kNone, kTarget, "an encoded patch is refused");
        check(patch.rect == built.rect &&
                  std::memcmp(patch.heights.data(), built.heights.data(), built.heights.size() * sizeof(float)) == 0,
              kTarget, "an encoded patch does not decode to its heights");
      }
    }
  }
  return 0;
}
