// The in-memory link (transport.hpp): each side's emulator stamps what it
// sends with its arrival time and puts it in the other side's inbox, which
// hands datagrams out in arrival order (ties in sending order).
#include "terracut/net/transport.hpp"

#include <algorithm>

namespace terracut::net {

class MemoryLink::Side final : public Endpoint {
 public:
  explicit Side(const LinkConditions& c) : emulator_(c) {}

  void send(Channel channel, const std::uint8_t* data, std::size_t size, double now_s) override {
    ++traffic_.sent;
    traffic_.sent_bytes += std::int64_t(size);
    const auto arrive = emulator_.schedule(now_s, channel == Channel::kReliable);
    if (!arrive) return;
    Pending p{*arrive, next_order_++, std::vector<std::uint8_t>(data, data + size)};
    // Keep the peer's inbox sorted by (arrival, order): insert after every
    // datagram that arrives no later.
    auto& box = peer_->inbox_;
    const auto at = std::upper_bound(box.begin(), box.end(), p, [](const Pending& x, const Pending& y) {
      return x.arrive_s < y.arrive_s || (x.arrive_s == y.arrive_s && x.order < y.order);
    });
    box.insert(at, std::move(p));
  }

  void receive(double now_s, std::vector<std::vector<std::uint8_t>>& out) override {
    while (!inbox_.empty() && inbox_.front().arrive_s <= now_s) {
      ++traffic_.received;
      traffic_.received_bytes += std::int64_t(inbox_.front().bytes.size());
      out.push_back(std::move(inbox_.front().bytes));
      inbox_.pop_front();
    }
  }

  const LinkEmulator& emulator() const override { return emulator_; }

  Side* peer_ = nullptr;

 private:
  struct Pending {
    double arrive_s;
    std::int64_t order;
    std::vector<std::uint8_t> bytes;
  };
  LinkEmulator emulator_;
  std::int64_t next_order_ = 0;
  std::deque<Pending> inbox_;
};

MemoryLink::MemoryLink(const LinkConditions& a_to_b, const LinkConditions& b_to_a)
    : a_(std::make_unique<Side>(a_to_b)), b_(std::make_unique<Side>(b_to_a)) {
  a_->peer_ = b_.get();
  b_->peer_ = a_.get();
}
MemoryLink::~MemoryLink() = default;
Endpoint& MemoryLink::a() { return *a_; }
Endpoint& MemoryLink::b() { return *b_; }

}  // namespace terracut::net
