// CRC-32 and the ordering rule of datagrams (wire.hpp).
#include "terracut/core/wire.hpp"

#include <array>

namespace terracut::wire {
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

}  // namespace

std::uint32_t crc32(const std::uint8_t* data, std::size_t size) noexcept {
  std::uint32_t c = 0xFFFFFFFFu;
  for (std::size_t i = 0; i < size; ++i) c = kCrcTable[(c ^ data[i]) & 0xFFu] ^ (c >> 8);
  return c ^ 0xFFFFFFFFu;
}

Frame check_frame(const std::uint8_t* data, std::size_t size, const FrameLayout& layout,
                  std::size_t& payload_size) noexcept {
  if (size < 4) return Frame::kTruncated;
  if (get_u32(data) != layout.magic) return Frame::kBadMagic;
  if (size < layout.header_size + 4) return Frame::kTruncated;
  if (get_u16(data + 4) != layout.version) return Frame::kBadVersion;
  const std::uint64_t declared = get_u32(data + layout.size_offset);
  const std::uint64_t expected = layout.header_size + declared + 4;
  if (size < expected) return Frame::kTruncated;
  if (size > expected) return Frame::kBadLength;
  const std::size_t body = layout.header_size + static_cast<std::size_t>(declared);
  if (crc32(data, body) != get_u32(data + body)) return Frame::kBadChecksum;
  payload_size = static_cast<std::size_t>(declared);
  return Frame::kOk;
}

Order SequenceFilter::check(std::uint32_t session, std::uint32_t sequence,
                            std::uint64_t timestamp_ns) noexcept {
  // Another session (or the first datagram): the sender (re)started.
  if (!has_session_ || session != session_) {
    has_session_ = true;
    new_session_ = true;
    session_ = session;
    last_sequence_ = sequence;
    last_timestamp_ns_ = timestamp_ns;
    ++sessions_;
    return Order::kAccepted;
  }
  const std::int32_t ahead = static_cast<std::int32_t>(sequence - last_sequence_);
  if (ahead == 0) return Order::kDuplicate;
  if (ahead < 0) return Order::kReordered;
  if (timestamp_ns < last_timestamp_ns_) return Order::kStale;
  new_session_ = false;
  lost_ += ahead - 1;
  last_sequence_ = sequence;
  last_timestamp_ns_ = timestamp_ns;
  return Order::kAccepted;
}

}  // namespace terracut::wire
