// The transports: the in-memory link delivers in sending order, and with the
// emulator in front of it (a decorator) by emulated arrival time; the ENet
// link carries both channels over one loopback UDP port, the emulator in
// front of it loses at the sender, and junk sent to that port breaks nothing.
#include "terracut/net/transport.hpp"

#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <thread>

#include "terracut/core/error.hpp"
#include "terracut/net/emulated_link.hpp"
#include "terracut/net/enet_transport.hpp"

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

// Services both ENet endpoints until pred holds or 3 s of wall time pass.
template <class Pred>
bool pump(EnetEndpoint& a, EnetEndpoint& b, std::vector<std::vector<std::uint8_t>>& at_a,
          std::vector<std::vector<std::uint8_t>>& at_b, Pred pred) {
  const auto start = std::chrono::steady_clock::now();
  while (std::chrono::steady_clock::now() - start < std::chrono::seconds(3)) {
    const double now = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    a.receive(now, at_a);
    b.receive(now, at_b);
    if (pred()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return false;
}

TEST(EnetLink, BothChannelsOverOneLoopbackPort) {
  auto server = EnetEndpoint::listen("127.0.0.1", 0);
  ASSERT_GT(server->port(), 0);
  auto client = EnetEndpoint::connect("127.0.0.1", server->port());
  std::vector<std::vector<std::uint8_t>> at_server, at_client;
  ASSERT_TRUE(pump(*server, *client, at_server, at_client,
                   [&] { return server->connected() && client->connected(); }));
  // Reliable messages arrive all and in order; unreliable ones over loopback too.
  for (int i = 0; i < 50; ++i) {
    const auto d = bytes(std::uint8_t(i), 100 + i);
    client->send(Channel::kReliable, d.data(), d.size(), 0.0);
    server->send(Channel::kUnreliable, d.data(), d.size(), 0.0);
  }
  ASSERT_TRUE(pump(*server, *client, at_server, at_client,
                   [&] { return at_server.size() >= 50 && at_client.size() >= 45; }));
  ASSERT_EQ(at_server.size(), 50u);
  for (int i = 0; i < 50; ++i) {
    EXPECT_EQ(at_server[std::size_t(i)].size(), std::size_t(100 + i));
    EXPECT_EQ(at_server[std::size_t(i)][0], std::uint8_t(i));
  }
}

TEST(EnetLink, TheEmulatorInFrontLosesAtTheSender) {
  auto server = EnetEndpoint::listen("127.0.0.1", 0);
  LinkConditions lossy;
  lossy.loss = 0.5;
  lossy.seed = 3;
  auto client = EnetEndpoint::connect("127.0.0.1", server->port());
  EmulatedEndpoint emulated(*client, lossy);
  std::vector<std::vector<std::uint8_t>> at_server, at_client;
  ASSERT_TRUE(pump(*server, *client, at_server, at_client, [&] { return client->connected(); }));
  for (int i = 0; i < 400; ++i) {
    const auto d = bytes(1);
    emulated.send(Channel::kUnreliable, d.data(), d.size(), 0.0);
  }
  EXPECT_EQ(emulated.traffic().sent, 400);
  const std::int64_t expected = 400 - emulated.emulator().counters().lost;
  EXPECT_EQ(client->traffic().sent, expected);
  ASSERT_TRUE(pump(*server, *client, at_server, at_client,
                   [&] { return std::int64_t(at_server.size()) >= expected; }));
  // Half are lost (4 sigma of a binomial(400, 0.5) is 40).
  EXPECT_NEAR(double(at_server.size()), 200.0, 40.0);
}

TEST(EnetLink, JunkOnThePortBreaksNothing) {
  auto server = EnetEndpoint::listen("127.0.0.1", 0);
  // Raw UDP junk, not ENet: ENet's own checks drop it.
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  ASSERT_GE(fd, 0);
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(std::uint16_t(server->port()));
  to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  for (int i = 0; i < 200; ++i) {
    std::uint8_t junk[64];
    for (std::size_t k = 0; k < sizeof junk; ++k) junk[k] = std::uint8_t(i * 31 + k * 7);
    ::sendto(fd, junk, std::size_t(1 + i % 64), 0, reinterpret_cast<const sockaddr*>(&to), sizeof to);
  }
  ::close(fd);
  std::vector<std::vector<std::uint8_t>> at_server, at_client;
  auto client = EnetEndpoint::connect("127.0.0.1", server->port());
  ASSERT_TRUE(pump(*server, *client, at_server, at_client, [&] { return server->connected(); }));
  EXPECT_TRUE(at_server.empty());
  const auto d = bytes(9);
  client->send(Channel::kReliable, d.data(), d.size(), 0.0);
  ASSERT_TRUE(pump(*server, *client, at_server, at_client, [&] { return !at_server.empty(); }));
  EXPECT_EQ(at_server.front()[0], 9);
}

TEST(EnetLink, BadAddressesAreNamed) {
  EXPECT_THROW(EnetEndpoint::listen("not-an-ip", 0), InputError);
  EXPECT_THROW(EnetEndpoint::connect("127.0.0.1", 0), InputError);
  auto a = EnetEndpoint::listen("127.0.0.1", 0);
  EXPECT_THROW(EnetEndpoint::listen("127.0.0.1", a->port()), InputError);
}

}  // namespace
}  // namespace terracut::net
