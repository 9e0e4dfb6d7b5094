// The in-memory transport delivers in sending order, and with the emulator
// in front of it (a decorator) by emulated arrival time; the pooled queues.
// The ENet carrier's tests: enet_transport_test.cpp.
#include "terracut/net/transport.hpp"

#include <gtest/gtest.h>

#include "terracut/net/emulated_link.hpp"

namespace terracut::net {
namespace {

std::vector<std::uint8_t> bytes(std::uint8_t tag, std::size_t n = 16) {
  return std::vector<std::uint8_t>(n, tag);
}

TEST(HeldQueue, HandsOutInTimeOrderTiesInHoldingOrderAlsoAfterPopping) {
  HeldQueue q(2, 8);
  const auto a = bytes(1, 4), b = bytes(2, 100), c = bytes(3, 4), d = bytes(4, 4);
  q.hold(0.3, 10, a.data(), a.size());
  q.hold(0.1, 11, b.data(), b.size());
  q.hold(0.3, 12, c.data(), c.size());  // a tie with a: after it
  q.hold(0.2, 13, d.data(), d.size());
  ASSERT_EQ(q.size(), 4u);
  const double times[] = {0.1, 0.2, 0.3, 0.3};
  const std::uint8_t tags[] = {11, 13, 10, 12};
  const std::vector<std::uint8_t>* contents[] = {&b, &d, &a, &c};
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(q.front_s(), times[i]);
    EXPECT_EQ(q.front_tag(), tags[i]);
    EXPECT_EQ(q.front_bytes(), *contents[i]);
    q.pop();
  }
  EXPECT_TRUE(q.empty());
  // Again, in the popped slots: the order holds and the contents are whole.
  q.hold(0.5, 20, b.data(), b.size());
  q.hold(0.4, 21, a.data(), a.size());
  EXPECT_EQ(q.front_tag(), 21);
  q.pop();
  EXPECT_EQ(q.front_bytes(), b);
}

TEST(Inbox, KeepsItsBuffersAcrossClear) {
  Inbox in(1, 4);
  const auto a = bytes(1, 3), b = bytes(2, 40);
  in.push(a.data(), a.size());
  in.push(b.data(), b.size());
  ASSERT_EQ(in.size(), 2u);
  EXPECT_EQ(in[0], a);
  EXPECT_EQ(in[1], b);
  const std::uint8_t* kept = in[1].data();
  in.clear();
  EXPECT_TRUE(in.empty());
  in.push(a.data(), a.size());
  in.push(b.data(), b.size());
  EXPECT_EQ(in[1].data(), kept);  // the same buffer, not a new one
  std::size_t n = 0;
  for (const auto& d : in) n += d.size();
  EXPECT_EQ(n, a.size() + b.size());
}

TEST(MemoryLink, DeliversAtOnceInSendingOrder) {
  MemoryLink link;
  for (int i = 0; i < 5; ++i) {
    const auto d = bytes(std::uint8_t(i), 3 + std::size_t(i));
    link.a().send(i % 2 ? Channel::kReliable : Channel::kUnreliable, d.data(), d.size(), 1.0 - i);
  }
  std::vector<std::vector<std::uint8_t>> got;
  link.b().receive(0.0, got);
  ASSERT_EQ(got.size(), 5u);
  for (int i = 0; i < 5; ++i) EXPECT_EQ(got[std::size_t(i)], bytes(std::uint8_t(i), 3 + std::size_t(i)));
  got.clear();
  link.a().receive(0.0, got);
  EXPECT_TRUE(got.empty());
}

TEST(EmulatedLink, DeliversAtTheArrivalTime) {
  LinkConditions ab;
  ab.delay_s = 0.05;
  LinkConditions ba;
  ba.delay_s = 0.1;
  EmulatedLink link(ab, ba);
  const auto d = bytes(1);
  link.a().send(Channel::kUnreliable, d.data(), d.size(), 0.0);
  link.b().send(Channel::kReliable, d.data(), d.size(), 0.0);
  std::vector<std::vector<std::uint8_t>> got;
  link.release(0.049);
  link.b().receive(0.049, got);
  EXPECT_TRUE(got.empty());
  link.release(0.05);
  link.b().receive(0.05, got);
  ASSERT_EQ(got.size(), 1u);
  got.clear();
  link.release(0.099);
  link.a().receive(0.099, got);
  EXPECT_TRUE(got.empty());
  link.release(0.1);
  link.a().receive(0.1, got);
  EXPECT_EQ(got.size(), 1u);
  EXPECT_EQ(link.a().traffic().sent, 1);
  EXPECT_EQ(link.a().traffic().sent_bytes, 16);
  EXPECT_EQ(link.b().traffic().received, 1);
}

TEST(EmulatedLink, JitterDeliversInArrivalOrder) {
  LinkConditions ab;
  ab.delay_s = 0.02;
  ab.jitter_s = 0.01;
  EmulatedLink link(ab, {});
  for (int i = 0; i < 200; ++i) {
    const auto d = bytes(std::uint8_t(i));
    link.a().send(Channel::kUnreliable, d.data(), d.size(), i * 0.001);
  }
  std::vector<std::vector<std::uint8_t>> got;
  link.release(1.0);
  link.b().receive(1.0, got);
  ASSERT_EQ(got.size(), 200u);
  int out_of_order = 0;
  for (std::size_t i = 1; i < got.size(); ++i) out_of_order += got[i][0] < got[i - 1][0];
  EXPECT_GT(out_of_order, 10);
}

}  // namespace
}  // namespace terracut::net
