// Fuzz target: the device bridge protocol (haptics/bridge_protocol.hpp) --
// the datagram decoders and the ordering logic (SequenceFilter) over a
// stream of datagrams.
//
// The input is a list of datagrams, each introduced by two bytes: a length
// (0-255, so short, exact and overlong datagrams all occur) and a control
// byte. With the control byte's bit 0 set the datagram is a well-formed pose
// packet made from the following bytes (session 0-3, sequence and timestamp
// stepped by small signed amounts, so duplicates, reordering, stale
// timestamps, gaps, wraps and new sessions all occur); otherwise its bytes
// go to the decoders as they are (bit 1: with the CRC repaired).
//
// Checked: decoding never reads outside the datagram (the sanitizers);
// a datagram both decoders accept does not exist; an accepted datagram
// re-encodes to the same bytes (but the reserved field); every datagram is
// classified once; the filter's accepted packets of a session have strictly
// increasing sequence numbers (serial arithmetic) and non-decreasing
// timestamps, its count of sessions and lost packets match the stream.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "fuzz_file.hpp"
#include "terracut/haptics/bridge_protocol.hpp"

namespace {

using namespace terracut::haptics;
using terracut::fuzz::check;

void put32(std::uint8_t* p, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = std::uint8_t(v >> (8 * i));
}

// Whether a and b are the same datagram, the reserved field (bytes 28-31,
// not checked on receipt) and so the CRC aside.
bool same_but_reserved(const std::uint8_t* a, const std::uint8_t* b, std::size_t size) {
  return std::memcmp(a, b, 28) == 0 && std::memcmp(a + 32, b + 32, size - 32 - kBridgeCrcSize) == 0;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  SequenceFilter filter;
  RejectCounts counts;
  std::int64_t datagrams = 0, accepted = 0, expected_lost = 0, expected_sessions = 0;
  bool have = false;
  PacketHeader last{};
  PacketHeader next{};  // the generator's state for well-formed packets
  std::size_t at = 0;
  std::uint8_t buffer[256 + kMaxBridgePacketSize];
  while (at + 2 <= size) {
    const std::size_t length = data[at];
    const std::uint8_t control = data[at + 1];
    at += 2;
    const std::size_t take = std::min(length, size - at);
    std::vector<std::uint8_t> datagram(data + at, data + at + take);  // its own allocation: ASan sees overreads
    at += take;
    if (control & 1u) {
      // A well-formed pose: the header from the generator, the payload from the bytes.
      std::uint8_t d[8] = {};
      if (!datagram.empty()) std::memcpy(d, datagram.data(), std::min<std::size_t>(8, datagram.size()));
      next.session = d[0] % 4 == 0 ? next.session + 1u : next.session;
      next.sequence += std::uint32_t(std::int32_t(std::int8_t(d[1])));
      if (d[2] == 0xFF) next.sequence += 0x80000000u;  // a jump of half the sequence space
      next.timestamp_ns += std::uint64_t(std::int64_t(std::int8_t(d[3])) * 1000);
      PosePayload pose;
      std::uint64_t bits = 0;
      std::memcpy(&bits, d, 8);
      std::memcpy(&pose.position_m.x, &bits, 8);  // any bit pattern: NaN, inf, subnormal
      pose.flags = d[4];
      datagram.assign(kPosePacketSize, 0);
      encode_pose(next, pose, datagram.data());
    } else if ((control & 2u) && datagram.size() >= kBridgeHeaderSize + kBridgeCrcSize) {
      const std::size_t body = datagram.size() - kBridgeCrcSize;
      put32(datagram.data() + body, crc32(datagram.data(), body));
    }
    ++datagrams;

    PacketHeader header;
    PosePayload pose;
    ForcePayload force;
    const Reject as_pose = decode_pose(datagram.data(), datagram.size(), header, pose);
    PacketHeader force_header;
    const Reject as_force = decode_force(datagram.data(), datagram.size(), force_header, force);
    check(as_pose != Reject::kNone || as_force != Reject::kNone, "fuzz_bridge", "a datagram is a pose or a force, not both");
    check(as_pose <= Reject::kBadType && as_force <= Reject::kBadType, "fuzz_bridge", "format reasons only");
    if (as_force == Reject::kNone) {
      check(encode_force(force_header, force, buffer) == datagram.size(), "fuzz_bridge", "force size");
      check(same_but_reserved(buffer, datagram.data(), datagram.size()), "fuzz_bridge", "force round trip");
    }
    if (as_pose != Reject::kNone) {
      counts.add(as_pose);
      continue;
    }
    check(encode_pose(header, pose, buffer) == datagram.size(), "fuzz_bridge", "pose size");
    check(same_but_reserved(buffer, datagram.data(), datagram.size()), "fuzz_bridge", "pose round trip");

    const Reject order = filter.check(header);
    if (order != Reject::kNone) {
      check(order == Reject::kDuplicate || order == Reject::kReordered || order == Reject::kStale, "fuzz_bridge",
            "order reasons only");
      check(have && header.session == last.session, "fuzz_bridge", "another session is never refused");
      counts.add(order);
      continue;
    }
    ++accepted;
    if (!have || header.session != last.session) {
      ++expected_sessions;
      check(filter.new_session(), "fuzz_bridge", "a new session is reported");
    } else {
      const std::int32_t ahead = std::int32_t(header.sequence - last.sequence);
      check(ahead > 0, "fuzz_bridge", "sequence numbers increase within a session");
      check(header.timestamp_ns >= last.timestamp_ns, "fuzz_bridge", "timestamps never go back within a session");
      check(!filter.new_session(), "fuzz_bridge", "the same session is not new");
      expected_lost += ahead - 1;
    }
    have = true;
    last = header;
    check(filter.last_sequence() == header.sequence, "fuzz_bridge", "the filter moves on");
  }
  check(counts.total() + accepted == datagrams, "fuzz_bridge", "every datagram counted once");
  check(filter.sessions() == expected_sessions, "fuzz_bridge", "sessions counted");
  check(filter.lost() == expected_lost, "fuzz_bridge", "lost packets counted");
  return 0;
}
