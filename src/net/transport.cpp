// The in-memory link (transport.hpp): what a side sends waits in the other
// side's queue, in sending order, until that side receives. Also the pooled
// buffers the carriers and the emulator use (Inbox, HeldQueue).
#include "terracut/net/transport.hpp"

#include <algorithm>

namespace terracut::net {

Inbox::Inbox(std::size_t slots, std::size_t bytes) : slots_(slots) {
  for (auto& s : slots_) s.reserve(bytes);
}

void Inbox::push(const std::uint8_t* data, std::size_t size) {
  if (count_ == slots_.size()) slots_.emplace_back();
  slots_[count_++].assign(data, data + size);
}

HeldQueue::HeldQueue(std::size_t slots, std::size_t bytes) { reserve(slots, bytes); }

void HeldQueue::reserve(std::size_t slots, std::size_t bytes) {
  const std::size_t first = slots_.size();
  slots_.resize(first + slots);
  free_.reserve(slots_.size());
  queue_.reserve(slots_.size());
  for (std::size_t i = first; i < slots_.size(); ++i) {
    slots_[i].bytes.reserve(bytes);
    free_.push_back(std::uint32_t(i));
  }
}

// A free slot for a datagram of `size` bytes: the smallest one that holds it
// without growing, else the largest (it grows), else a new one.
std::size_t HeldQueue::take(std::size_t size) {
  std::size_t best = free_.size();
  for (std::size_t k = 0; k < free_.size(); ++k) {
    const std::size_t cap = slots_[free_[k]].bytes.capacity();
    if (best == free_.size()) {
      best = k;
      continue;
    }
    const std::size_t best_cap = slots_[free_[best]].bytes.capacity();
    const bool fits = cap >= size, best_fits = best_cap >= size;
    if ((fits && (!best_fits || cap < best_cap)) || (!fits && !best_fits && cap > best_cap))
      best = k;
  }
  if (best < free_.size()) {
    const std::size_t slot = free_[best];
    free_[best] = free_.back();
    free_.pop_back();
    return slot;
  }
  slots_.emplace_back();
  free_.reserve(slots_.size());
  queue_.reserve(slots_.size());
  return slots_.size() - 1;
}

void HeldQueue::hold(double at_s, std::uint8_t tag, const std::uint8_t* data, std::size_t size) {
  const std::size_t i = take(size);
  Slot& s = slots_[i];
  s.at_s = at_s;
  s.order = next_order_++;
  s.tag = tag;
  s.bytes.assign(data, data + size);
  // Insert after every datagram due no later.
  const auto at = std::upper_bound(queue_.begin(), queue_.end(), i, [this](std::size_t x, std::uint32_t y) {
    const Slot& a = slots_[x];
    const Slot& b = slots_[y];
    return a.at_s < b.at_s || (a.at_s == b.at_s && a.order < b.order);
  });
  queue_.insert(at, std::uint32_t(i));
}

void HeldQueue::pop() {
  free_.push_back(queue_.front());
  queue_.erase(queue_.begin());
}

void Endpoint::receive(double now_s, std::vector<std::vector<std::uint8_t>>& out) {
  Inbox in;
  receive(now_s, in);
  for (const auto& d : in) out.push_back(d);
}

class MemoryLink::Side final : public Endpoint {
 public:
  void send(Channel, const std::uint8_t* data, std::size_t size, double) override {
    ++traffic_.sent;
    traffic_.sent_bytes += std::int64_t(size);
    // One time for all: the queue keeps sending order (ties in holding order).
    peer_->inbox_.hold(0.0, 0, data, size);
  }

  void receive(double, Inbox& out) override {
    while (!inbox_.empty()) {
      ++traffic_.received;
      traffic_.received_bytes += std::int64_t(inbox_.front_bytes().size());
      out.push(inbox_.front_bytes().data(), inbox_.front_bytes().size());
      inbox_.pop();
    }
  }
  using Endpoint::receive;

  // What this side sends waits in its peer's queue.
  void reserve_in_flight(std::size_t datagrams, std::size_t bytes) override {
    peer_->inbox_.reserve(datagrams, bytes);
  }

  Side* peer_ = nullptr;

 private:
  HeldQueue inbox_;
};

MemoryLink::MemoryLink() : a_(std::make_unique<Side>()), b_(std::make_unique<Side>()) {
  a_->peer_ = b_.get();
  b_->peer_ = a_.get();
}
MemoryLink::~MemoryLink() = default;
Endpoint& MemoryLink::a() { return *a_; }
Endpoint& MemoryLink::b() { return *b_; }

}  // namespace terracut::net
