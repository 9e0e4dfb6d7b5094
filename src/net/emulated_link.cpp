// The link emulator as a decorator of any transport (emulated_link.hpp).
#include "terracut/net/emulated_link.hpp"

#include <chrono>

namespace terracut::net {

EmulatedEndpoint::EmulatedEndpoint(Endpoint& inner, const LinkConditions& sending,
                                   EmulatorClock clock)
    : inner_(inner), emulator_(sending), clock_(clock) {}

double EmulatedEndpoint::now(double now_s) const {
  if (clock_ == EmulatorClock::kCaller) return now_s;
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

void EmulatedEndpoint::send(Channel channel, const std::uint8_t* data, std::size_t size,
                            double now_s) {
  now_s = now(now_s);
  ++traffic_.sent;
  traffic_.sent_bytes += std::int64_t(size);
  const auto arrive = emulator_.schedule(now_s, channel == Channel::kReliable);
  if (!arrive) return;
  held_.hold(*arrive, static_cast<std::uint8_t>(channel), data, size);
  release(now_s);
}

void EmulatedEndpoint::release(double now_s) {
  now_s = now(now_s);
  while (!held_.empty() && held_.front_s() <= now_s) {
    const std::vector<std::uint8_t>& bytes = held_.front_bytes();
    inner_.send(static_cast<Channel>(held_.front_tag()), bytes.data(), bytes.size(), now_s);
    held_.pop();
  }
}

void EmulatedEndpoint::receive(double now_s, Inbox& out) {
  release(now_s);  // (release reads the wall clock itself when it is the emulator's)
  const std::size_t before = out.size();
  inner_.receive(now_s, out);
  for (std::size_t i = before; i < out.size(); ++i) {
    ++traffic_.received;
    traffic_.received_bytes += std::int64_t(out[i].size());
  }
}

void EmulatedEndpoint::reserve_in_flight(std::size_t datagrams, std::size_t bytes) {
  held_.reserve(datagrams, bytes);
  inner_.reserve_in_flight(datagrams, bytes);
}

void EmulatedEndpoint::note_round_trip_s(double round_trip_s) noexcept {
  emulator_.set_round_trip_s(round_trip_s);
  inner_.note_round_trip_s(round_trip_s);
}

EmulatedLink::EmulatedLink(const LinkConditions& a_to_b, const LinkConditions& b_to_a)
    : a_(memory_.a(), a_to_b), b_(memory_.b(), b_to_a) {}

void EmulatedLink::release(double now_s) {
  a_.release(now_s);
  b_.release(now_s);
}

}  // namespace terracut::net
