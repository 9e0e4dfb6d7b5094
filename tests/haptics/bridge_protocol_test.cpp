// The bridge protocol: byte layout, round trips, every rejection reason, and
// a fixed-seed fuzz of 100 000 malformed datagrams.
#include "terracut/haptics/bridge_protocol.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

namespace terracut::haptics {
namespace {

using Bytes = std::vector<std::uint8_t>;

Bytes pose_packet(const PacketHeader& h, const PosePayload& p) {
  Bytes b(kPosePacketSize);
  EXPECT_EQ(encode_pose(h, p, b.data()), kPosePacketSize);
  return b;
}

Bytes force_packet(const PacketHeader& h, const ForcePayload& f) {
  Bytes b(kForcePacketSize);
  EXPECT_EQ(encode_force(h, f, b.data()), kForcePacketSize);
  return b;
}

Reject decode_as_pose(const Bytes& b) {
  PacketHeader h;
  PosePayload p;
  return decode_pose(b.data(), b.size(), h, p);
}

std::uint64_t bits_of(double v) {
  std::uint64_t u;
  std::memcpy(&u, &v, sizeof u);
  return u;
}

std::uint32_t le32(const Bytes& b, std::size_t at) {
  return std::uint32_t(b[at]) | std::uint32_t(b[at + 1]) << 8 | std::uint32_t(b[at + 2]) << 16 |
         std::uint32_t(b[at + 3]) << 24;
}

// Rewrites the CRC after an edit, so that only the edited field is wrong.
void reseal(Bytes& b) {
  const std::size_t body = b.size() - kBridgeCrcSize;
  const std::uint32_t c = crc32(b.data(), body);
  for (int i = 0; i < 4; ++i) b[body + i] = std::uint8_t(c >> (8 * i));
}

TEST(BridgeProtocol, Crc32MatchesTheStandardCheckValue) {
  // The CRC-32 (IEEE) check value of "123456789" (zlib.crc32 gives the same).
  const char* text = "123456789";
  EXPECT_EQ(crc32(reinterpret_cast<const std::uint8_t*>(text), 9), 0xCBF43926u);
  EXPECT_EQ(crc32(nullptr, 0), 0u);
}

TEST(BridgeProtocol, PoseLayoutIsTheDocumentedOne) {
  PacketHeader h{0x11223344u, 0x55667788u, 0x0102030405060708ull};
  PosePayload p;
  p.position_m = {1.0, -2.5, 0.125};
  p.orientation = {0.5, 0.5, -0.5, 0.5};
  p.buttons = 0xA5u;
  p.flags = kPoseHasOrientation;
  const Bytes b = pose_packet(h, p);
  // Magic as the bytes "TCHB", version 1, type 1, the header fields LE.
  EXPECT_EQ(std::string(b.begin(), b.begin() + 4), "TCHB");
  EXPECT_EQ(b[4], 1);
  EXPECT_EQ(b[5], 0);
  EXPECT_EQ(b[6], 1);
  EXPECT_EQ(b[7], 0);
  EXPECT_EQ(le32(b, 8), 0x11223344u);
  EXPECT_EQ(le32(b, 12), 0x55667788u);
  EXPECT_EQ(le32(b, 16), 0x05060708u);
  EXPECT_EQ(le32(b, 20), 0x01020304u);
  EXPECT_EQ(le32(b, 24), 64u);
  EXPECT_EQ(le32(b, 28), 0u);
  // Payload: doubles at 32.., buttons at 88, flags at 92; CRC at 96.
  std::uint64_t x = 0;
  for (int i = 7; i >= 0; --i) x = (x << 8) | b[32 + i];
  EXPECT_EQ(x, bits_of(1.0));
  std::uint64_t qz = 0;
  for (int i = 7; i >= 0; --i) qz = (qz << 8) | b[80 + i];
  EXPECT_EQ(qz, bits_of(0.5));
  EXPECT_EQ(le32(b, 88), 0xA5u);
  EXPECT_EQ(le32(b, 92), kPoseHasOrientation);
  EXPECT_EQ(le32(b, 96), crc32(b.data(), 96));
}

TEST(BridgeProtocol, ForceLayoutIsTheDocumentedOne) {
  ForcePayload f;
  f.force_n = {0.0, 7.5, -1.0};
  f.flags = 0x1Fu;
  f.pose_sequence = 4242;
  const Bytes b = force_packet({7, 9, 11}, f);
  EXPECT_EQ(b[6], 2);
  EXPECT_EQ(le32(b, 24), 32u);
  std::uint64_t fy = 0;
  for (int i = 7; i >= 0; --i) fy = (fy << 8) | b[40 + i];
  EXPECT_EQ(fy, bits_of(7.5));
  EXPECT_EQ(le32(b, 56), 0x1Fu);
  EXPECT_EQ(le32(b, 60), 4242u);
  EXPECT_EQ(le32(b, 64), crc32(b.data(), 64));
}

TEST(BridgeProtocol, RoundTripsKeepEveryBit) {
  const double specials[] = {0.0,
                             -0.0,
                             1e-300,
                             -1e300,
                             std::numeric_limits<double>::denorm_min(),
                             std::numeric_limits<double>::infinity(),
                             std::numeric_limits<double>::quiet_NaN(),
                             0.1};
  for (double v : specials) {
    PacketHeader h{3, 0xFFFFFFFFu, 0xFFFFFFFFFFFFFFFFull};
    PosePayload p;
    p.position_m = {v, -v, 0.3};
    p.orientation = {v, 1.0, 2.0, 3.0};
    p.buttons = 0xFFFFFFFFu;
    p.flags = 0;
    const Bytes b = pose_packet(h, p);
    PacketHeader h2;
    PosePayload p2;
    ASSERT_EQ(decode_pose(b.data(), b.size(), h2, p2), Reject::kNone);
    EXPECT_EQ(h2.session, h.session);
    EXPECT_EQ(h2.sequence, h.sequence);
    EXPECT_EQ(h2.timestamp_ns, h.timestamp_ns);
    EXPECT_EQ(bits_of(p2.position_m.x), bits_of(v));
    EXPECT_EQ(bits_of(p2.position_m.y), bits_of(-v));
    EXPECT_EQ(bits_of(p2.orientation.w), bits_of(v));
    EXPECT_EQ(p2.orientation.z, 3.0);
    EXPECT_EQ(p2.buttons, 0xFFFFFFFFu);

    ForcePayload f;
    f.force_n = {v, 2.0, -v};
    f.flags = 0x100u;
    f.pose_sequence = 17;
    const Bytes fb = force_packet(h, f);
    ForcePayload f2;
    ASSERT_EQ(decode_force(fb.data(), fb.size(), h2, f2), Reject::kNone);
    EXPECT_EQ(bits_of(f2.force_n.x), bits_of(v));
    EXPECT_EQ(bits_of(f2.force_n.z), bits_of(-v));
    EXPECT_EQ(f2.flags, 0x100u);
    EXPECT_EQ(f2.pose_sequence, 17u);
  }
}

TEST(BridgeProtocol, EveryTruncationIsRejectedAsTruncated) {
  const Bytes b = pose_packet({1, 2, 3}, {});
  for (std::size_t n = 0; n < b.size(); ++n) {
    const Bytes cut(b.begin(), b.begin() + std::ptrdiff_t(n));
    EXPECT_EQ(decode_as_pose(cut), Reject::kTruncated) << n << " bytes";
  }
}

TEST(BridgeProtocol, ExtraBytesAreABadLength) {
  Bytes b = pose_packet({1, 2, 3}, {});
  b.push_back(0);
  EXPECT_EQ(decode_as_pose(b), Reject::kBadLength);
}

TEST(BridgeProtocol, EverySingleBitFlipIsCaughtWithItsReason) {
  const Bytes good = pose_packet({5, 6, 7}, {});
  for (std::size_t byte = 0; byte < good.size(); ++byte) {
    for (int bit = 0; bit < 8; ++bit) {
      Bytes b = good;
      b[byte] ^= std::uint8_t(1u << bit);
      Reject want = Reject::kBadChecksum;
      if (byte < 4) {
        want = Reject::kBadMagic;
      } else if (byte < 6) {
        want = Reject::kBadVersion;
      } else if (byte >= 24 && byte < 28) {
        // The declared payload size: bigger -> the datagram is too short for
        // it; smaller -> too long.
        want = le32(b, 24) > 64 ? Reject::kTruncated : Reject::kBadLength;
      }
      EXPECT_EQ(decode_as_pose(b), want) << "byte " << byte << " bit " << bit;
    }
  }
}

TEST(BridgeProtocol, WrongVersionAndTypeWithAValidChecksum) {
  Bytes b = pose_packet({1, 1, 1}, {});
  b[4] = 2;
  reseal(b);
  EXPECT_EQ(decode_as_pose(b), Reject::kBadVersion);

  // A force packet where a pose is expected (and the other way round).
  const Bytes f = force_packet({1, 1, 1}, {});
  EXPECT_EQ(decode_as_pose(f), Reject::kBadType);
  const Bytes p = pose_packet({1, 1, 1}, {});
  PacketHeader h;
  ForcePayload fp;
  EXPECT_EQ(decode_force(p.data(), p.size(), h, fp), Reject::kBadType);

  // An unknown type.
  Bytes u = pose_packet({1, 1, 1}, {});
  u[6] = 9;
  reseal(u);
  EXPECT_EQ(decode_as_pose(u), Reject::kBadType);

  // A pose type with a force-sized payload: consistent sizes, wrong for the type.
  Bytes s = force_packet({1, 1, 1}, {});
  s[6] = 1;
  reseal(s);
  EXPECT_EQ(decode_as_pose(s), Reject::kBadLength);
}

TEST(SequenceFilter, AcceptsOnlyNewerPackets) {
  SequenceFilter f;
  EXPECT_EQ(f.check({1, 10, 1000}), Reject::kNone);
  EXPECT_TRUE(f.new_session());
  EXPECT_EQ(f.check({1, 11, 2000}), Reject::kNone);
  EXPECT_FALSE(f.new_session());
  EXPECT_EQ(f.check({1, 11, 2000}), Reject::kDuplicate);
  EXPECT_EQ(f.check({1, 9, 500}), Reject::kReordered);
  EXPECT_EQ(f.check({1, 10, 3000}), Reject::kReordered);
  EXPECT_EQ(f.check({1, 12, 1999}), Reject::kStale);
  // Equal timestamps are fine (a coarse clock).
  EXPECT_EQ(f.check({1, 12, 2000}), Reject::kNone);
  // A gap of 3 packets.
  EXPECT_EQ(f.check({1, 16, 2500}), Reject::kNone);
  EXPECT_EQ(f.lost(), 3);
  // A restarted sender: a new session starts whatever its numbers.
  EXPECT_EQ(f.check({2, 0, 0}), Reject::kNone);
  EXPECT_TRUE(f.new_session());
  EXPECT_EQ(f.sessions(), 2);
  EXPECT_EQ(f.check({2, 0, 0}), Reject::kDuplicate);
}

TEST(SequenceFilter, SequenceNumbersWrapAround) {
  SequenceFilter f;
  EXPECT_EQ(f.check({4, 0xFFFFFFFEu, 1}), Reject::kNone);
  EXPECT_EQ(f.check({4, 0xFFFFFFFFu, 2}), Reject::kNone);
  EXPECT_EQ(f.check({4, 0u, 3}), Reject::kNone);
  EXPECT_EQ(f.check({4, 1u, 4}), Reject::kNone);
  EXPECT_EQ(f.check({4, 0xFFFFFFFFu, 5}), Reject::kReordered);
  EXPECT_EQ(f.lost(), 0);
}

// 100 000 malformed datagrams of seven kinds, each with the reason the
// documented order of checks gives; none may be accepted or crash.
TEST(BridgeProtocol, FuzzedDatagramsAreRejectedWithTheRightReason) {
  std::mt19937 rng(20240611u);
  std::uniform_int_distribution<int> byte(0, 255);
  RejectCounts counts;
  const int kPackets = 100000;
  for (int i = 0; i < kPackets; ++i) {
    const int kind = i % 7;
    PacketHeader h{std::uint32_t(rng()), std::uint32_t(rng()),
                   (std::uint64_t(rng()) << 32) | rng()};
    PosePayload p;
    p.position_m = {double(rng()) * 1e-9, -double(rng()), 1.0};
    Bytes b = pose_packet(h, p);
    Reject want = Reject::kNone;
    switch (kind) {
      case 0: {  // 0 to 3 random bytes
        b.resize(std::size_t(rng() % 4));
        for (auto& x : b) x = std::uint8_t(byte(rng));
        want = Reject::kTruncated;
        break;
      }
      case 1: {  // random bytes of random length, not starting with the magic
        b.resize(4 + std::size_t(rng() % 300));
        for (auto& x : b) x = std::uint8_t(byte(rng));
        if (le32(b, 0) == kBridgeMagic) b[0] ^= 0xFF;
        want = Reject::kBadMagic;
        break;
      }
      case 2:  // a valid packet cut short (keeping the magic)
        b.resize(4 + std::size_t(rng() % (kPosePacketSize - 4)));
        want = Reject::kTruncated;
        break;
      case 3: {  // a valid packet with extra bytes
        const std::size_t extra = 1 + std::size_t(rng() % 64);
        for (std::size_t k = 0; k < extra; ++k) b.push_back(std::uint8_t(byte(rng)));
        want = Reject::kBadLength;
        break;
      }
      case 4: {  // 1 to 8 flipped bits after the version, outside the size field
        const int flips = 1 + int(rng() % 8);
        for (int k = 0; k < flips; ++k) {
          std::size_t at;
          do at = 6 + std::size_t(rng() % (kPosePacketSize - 6));
          while (at >= 24 && at < 28);
          b[at] ^= std::uint8_t(1u << (rng() % 8));
        }
        // An even number of flips on the same bit cancels out; skip those.
        if (decode_as_pose(b) == Reject::kNone) {
          bool same = b == pose_packet(h, p);
          ASSERT_TRUE(same) << "a corrupted packet was accepted at " << i;
          continue;
        }
        want = Reject::kBadChecksum;
        break;
      }
      case 5: {  // another version, correctly sealed
        std::uint16_t v;
        do v = std::uint16_t(rng());
        while (v == kBridgeVersion);
        b[4] = std::uint8_t(v);
        b[5] = std::uint8_t(v >> 8);
        reseal(b);
        want = Reject::kBadVersion;
        break;
      }
      case 6: {  // the other direction's packet
        b = force_packet(h, {});
        want = Reject::kBadType;
        break;
      }
    }
    const Reject got = decode_as_pose(b);
    ASSERT_EQ(got, want) << "datagram " << i << " kind " << kind << " size " << b.size();
    counts.add(got);
    // The force decoder must survive the same bytes (and never accept them:
    // only kind 6 is a valid force packet).
    PacketHeader fh;
    ForcePayload fp;
    const Reject as_force = decode_force(b.data(), b.size(), fh, fp);
    if (kind == 6)
      EXPECT_EQ(as_force, Reject::kNone);
    else
      EXPECT_NE(as_force, Reject::kNone);
  }
  EXPECT_EQ(counts[Reject::kNone], 0);
  EXPECT_GT(counts.total(), kPackets * 99 / 100);
  for (Reject r : {Reject::kTruncated, Reject::kBadLength, Reject::kBadMagic, Reject::kBadVersion,
                   Reject::kBadChecksum, Reject::kBadType})
    EXPECT_GT(counts[r], 0) << to_string(r);
}

}  // namespace
}  // namespace terracut::haptics
