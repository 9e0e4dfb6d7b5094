// The teleoperation codec: round trips, and every malformed datagram
// rejected with its reason, never a crash.
#include "terracut/net/messages.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "terracut/core/wire.hpp"

namespace terracut::net {
namespace {

constexpr std::uint32_t kLink = 0xC0FFEEu;

Header header(std::uint32_t seq) {
  Header h;
  h.link = kLink;
  h.session = 7;
  h.sequence = seq;
  h.timestamp_ns = 1000u * seq;
  return h;
}

std::vector<std::uint8_t> command_bytes() {
  Command c;
  c.t_s = 1.25;
  c.pose.position_m = {0.1, 0.2, -0.3};
  c.pose.orientation = {0.5, 0.5, 0.5, 0.5};
  c.flags = kCommandLifted;
  c.round_trip_us = 101234;
  std::vector<std::uint8_t> out(kHeaderSize + kCommandPayloadSize + kCrcSize);
  EXPECT_EQ(encode_command(header(3), c, out.data()), out.size());
  return out;
}

// Re-seals a datagram whose bytes were edited, so that only the edit is wrong.
void reseal(std::vector<std::uint8_t>& d) {
  const std::size_t body = d.size() - kCrcSize;
  wire::put_u32(d.data() + body, wire::crc32(d.data(), body));
}

TEST(Messages, CommandRoundTrip) {
  const auto d = command_bytes();
  Header h;
  ASSERT_EQ(decode_header(d.data(), d.size(), kLink, h), Reject::kNone);
  EXPECT_EQ(h.type, MessageType::kCommand);
  EXPECT_EQ(h.session, 7u);
  EXPECT_EQ(h.sequence, 3u);
  EXPECT_EQ(h.timestamp_ns, 3000u);
  Command c;
  ASSERT_EQ(decode_command(d.data(), d.size(), c), Reject::kNone);
  EXPECT_EQ(c.t_s, 1.25);
  EXPECT_EQ(c.pose.position_m.z, -0.3);
  EXPECT_EQ(c.pose.orientation.w, 0.5);
  EXPECT_EQ(c.flags, kCommandLifted);
  EXPECT_EQ(c.round_trip_us, 101234u);
}

TEST(Messages, MeasurementAndEstimateRoundTrip) {
  Measurement m;
  m.t_s = 2.0;
  m.command_sequence = 99;
  m.pose.position_m = {1, 2, 3};
  m.force_world_n = {-4, 5, -6};
  m.contact_length_m = 0.4;
  m.cut_depth_m = 0.08;
  m.commands_received = 4000000001u;
  std::vector<std::uint8_t> d(kHeaderSize + kMeasurementPayloadSize + kCrcSize);
  ASSERT_EQ(encode_measurement(header(1), m, d.data()), d.size());
  Header h;
  ASSERT_EQ(decode_header(d.data(), d.size(), kLink, h), Reject::kNone);
  EXPECT_EQ(h.type, MessageType::kMeasurement);
  Measurement back;
  ASSERT_EQ(decode_measurement(d.data(), d.size(), back), Reject::kNone);
  EXPECT_EQ(back.command_sequence, 99u);
  EXPECT_EQ(back.force_world_n.z, -6.0);
  EXPECT_EQ(back.cut_depth_m, 0.08);
  EXPECT_EQ(back.commands_received, 4000000001u);

  Estimate e;
  e.t_s = 3.0;
  e.force_scale = 2.5;
  e.variance = 0.01;
  e.samples = 400;
  std::vector<std::uint8_t> de(kHeaderSize + kEstimatePayloadSize + kCrcSize);
  ASSERT_EQ(encode_estimate(header(2), e, de.data()), de.size());
  Estimate eb;
  ASSERT_EQ(decode_header(de.data(), de.size(), kLink, h), Reject::kNone);
  ASSERT_EQ(decode_estimate(de.data(), de.size(), eb), Reject::kNone);
  EXPECT_EQ(eb.force_scale, 2.5);
  EXPECT_EQ(eb.samples, 400u);
}

TEST(Messages, PatchRoundTripIsExactAndCompressed) {
  Patch p;
  p.t_s = 0.5;
  p.rect = {10, 20, 50, 60};  // 40 x 40
  for (int r = 0; r < 40; ++r)
    for (int c = 0; c < 40; ++c) p.heights.push_back(c < 20 ? 0.3f : 0.22f);  // a trench edge
  std::vector<std::uint8_t> d;
  const std::size_t size = encode_patch(header(5), p, d);
  ASSERT_GT(size, 0u);
  // Smooth terrain compresses well below the raw 6400 bytes.
  EXPECT_LT(size, 1600u);
  Header h;
  ASSERT_EQ(decode_header(d.data(), d.size(), kLink, h), Reject::kNone);
  EXPECT_EQ(h.type, MessageType::kPatch);
  Patch back;
  ASSERT_EQ(decode_patch(d.data(), d.size(), back), Reject::kNone);
  EXPECT_EQ(back.rect, p.rect);
  EXPECT_EQ(back.heights, p.heights);
  EXPECT_EQ(back.t_s, 0.5);
}

TEST(Messages, FormatErrorsAreNamed) {
  const auto good = command_bytes();
  Header h;
  // Truncated at every length.
  for (std::size_t n = 0; n < good.size(); ++n) {
    EXPECT_EQ(decode_header(good.data(), n, kLink, h), Reject::kTruncated) << n;
  }
  auto longer = good;
  longer.push_back(0);
  EXPECT_EQ(decode_header(longer.data(), longer.size(), kLink, h), Reject::kBadLength);
  auto magic = good;
  magic[0] ^= 0xFF;
  EXPECT_EQ(decode_header(magic.data(), magic.size(), kLink, h), Reject::kBadMagic);
  auto version = good;
  version[4] = std::uint8_t(kVersion + 1);
  EXPECT_EQ(decode_header(version.data(), version.size(), kLink, h), Reject::kBadVersion);
  auto flipped = good;
  flipped[60] ^= 0x01;
  EXPECT_EQ(decode_header(flipped.data(), flipped.size(), kLink, h), Reject::kBadChecksum);
  auto type = good;
  type[6] = 9;
  reseal(type);
  EXPECT_EQ(decode_header(type.data(), type.size(), kLink, h), Reject::kBadType);
  EXPECT_EQ(decode_header(good.data(), good.size(), kLink + 1, h), Reject::kForeign);
  // A payload of the wrong size for its type.
  Measurement m;
  EXPECT_EQ(decode_measurement(good.data(), good.size(), m), Reject::kBadLength);
  // Non-finite values.
  auto nan = good;
  wire::put_f64(nan.data() + kHeaderSize + 8, std::numeric_limits<double>::quiet_NaN());
  reseal(nan);
  ASSERT_EQ(decode_header(nan.data(), nan.size(), kLink, h), Reject::kNone);
  Command c;
  EXPECT_EQ(decode_command(nan.data(), nan.size(), c), Reject::kBadPayload);
}

TEST(Messages, BadPatchesAreRefused) {
  Patch p;
  p.rect = {0, 0, 4, 4};
  p.heights.assign(16, 0.1f);
  std::vector<std::uint8_t> d;
  ASSERT_GT(encode_patch(header(1), p, d), 0u);
  Patch back;
  Header h;
  // A rectangle that claims more samples than the data holds.
  auto bigger = d;
  wire::put_u32(bigger.data() + kHeaderSize + 16, 5);
  reseal(bigger);
  ASSERT_EQ(decode_header(bigger.data(), bigger.size(), kLink, h), Reject::kNone);
  EXPECT_EQ(decode_patch(bigger.data(), bigger.size(), back), Reject::kBadPayload);
  // An absurd rectangle.
  auto huge = d;
  wire::put_u32(huge.data() + kHeaderSize + 16, 1u << 20);
  wire::put_u32(huge.data() + kHeaderSize + 20, 1u << 20);
  reseal(huge);
  EXPECT_EQ(decode_patch(huge.data(), huge.size(), back), Reject::kBadPayload);
  // Compressed bytes that are not zstd.
  auto junk = d;
  for (std::size_t i = kHeaderSize + kPatchFixedSize; i + kCrcSize < junk.size(); ++i) junk[i] = 0xAB;
  reseal(junk);
  EXPECT_EQ(decode_patch(junk.data(), junk.size(), back), Reject::kBadPayload);
  // A non-finite height.
  p.heights[5] = std::numeric_limits<float>::infinity();
  ASSERT_GT(encode_patch(header(2), p, d), 0u);
  EXPECT_EQ(decode_patch(d.data(), d.size(), back), Reject::kBadPayload);
  // Empty rectangles are not encoded.
  Patch empty;
  EXPECT_EQ(encode_patch(header(3), empty, d), 0u);
}

TEST(Messages, RandomBytesNeverCrash) {
  std::mt19937 rng(11);
  const auto good = command_bytes();
  std::vector<std::uint8_t> d;
  for (int i = 0; i < 20000; ++i) {
    d = good;
    // Random edits, random lengths.
    const int edits = 1 + int(rng() % 4);
    for (int k = 0; k < edits; ++k) d[rng() % d.size()] = std::uint8_t(rng());
    d.resize(rng() % (d.size() + 8));
    Header h;
    Command c;
    Patch p;
    if (decode_header(d.data(), d.size(), kLink, h) == Reject::kNone) {
      (void)decode_command(d.data(), d.size(), c);
      (void)decode_patch(d.data(), d.size(), p);
    }
  }
  SUCCEED();
}

TEST(Messages, ReasonsHaveNames) {
  EXPECT_EQ(to_string(Reject::kForeign), "foreign");
  EXPECT_EQ(to_string(Reject::kBadPayload), "bad_payload");
  RejectCounts counts;
  counts.add(Reject::kStale);
  counts.add(Reject::kStale);
  counts.add(Reject::kForeign);
  EXPECT_EQ(counts[Reject::kStale], 2);
  EXPECT_EQ(counts.total(), 3);
}

}  // namespace
}  // namespace terracut::net
