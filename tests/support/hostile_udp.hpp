// What an attacker on the same machine can send a station's UDP port
// (loopback only): a junk flood from another local port, and an intruder
// that is a real ENet client. Shared by the carrier's tests
// (tests/net/enet_transport_test.cpp) and terracut-netprobe (the two-process
// flood test and the soak, tests/soak).
#pragma once

#include <arpa/inet.h>
#include <enet/enet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <random>
#include <thread>
#include <vector>

#include "terracut/net/secure.hpp"

namespace terracut::test {

/// Junk datagrams to 127.0.0.1:port from a port of its own, at a rate,
/// of every kind a flood may hold: random bytes (1 to 1400), empty,
/// truncated ENet-looking headers, ENet connection requests with random
/// fields, ENet-looking packets of an assigned peer, and oversize ones
/// (5000 bytes, more than ENet reads).
class JunkFlood {
 public:
  struct Counts {
    std::int64_t sent = 0, random = 0, empty = 0, truncated = 0, connects = 0, enet_like = 0,
                 oversize = 0, failed = 0;
  };
  explicit JunkFlood(std::uint32_t seed = 1) : fd_(::socket(AF_INET, SOCK_DGRAM, 0)), rng_(seed) {
    int big = 4 << 20;
    ::setsockopt(fd_, SOL_SOCKET, SO_SNDBUF, &big, sizeof big);
    // Random bytes made once: a datagram's are a slice of them at a random
    // offset (drawing every byte cost the flooder more processor than the
    // sending, and took it from the stations on a 2-core machine).
    for (auto& b : noise_) b = std::uint8_t(rng_());
  }
  ~JunkFlood() {
    if (fd_ >= 0) ::close(fd_);
  }
  JunkFlood(const JunkFlood&) = delete;
  JunkFlood& operator=(const JunkFlood&) = delete;

  /// Sends one junk datagram of a random kind.
  void send_one(int port) {
    sockaddr_in to{};
    to.sin_family = AF_INET;
    to.sin_port = htons(std::uint16_t(port));
    to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    std::size_t n = 0;
    const int kind = int(rng_() % 16);
    auto fill = [&](std::size_t from, std::size_t to_size) {
      const std::size_t at = rng_() % (sizeof noise_ - sizeof buf_);
      std::memcpy(buf_ + from, noise_ + at, to_size - from);
    };
    std::int64_t* count = nullptr;
    if (kind < 6) {  // random bytes
      n = 1 + rng_() % 1400;
      fill(0, n);
      count = &counts_.random;
    } else if (kind < 8) {  // empty
      n = 0;
      count = &counts_.empty;
    } else if (kind < 10) {  // a truncated ENet header
      n = 1 + rng_() % 7;
      fill(0, n);
      count = &counts_.truncated;
    } else if (kind < 12) {  // a connection request, its fields random
      n = 4 + 48 + rng_() % 8;
      fill(0, n);
      const std::uint16_t first = std::uint16_t(0x8000u | 0x0FFFu);  // sent time, unassigned peer id
      buf_[0] = std::uint8_t(first >> 8);
      buf_[1] = std::uint8_t(first);
      buf_[4] = std::uint8_t(0x80 | 2);  // acknowledge | CONNECT
      count = &counts_.connects;
    } else if (kind < 15) {  // ENet-looking, an assigned peer id
      n = 8 + rng_() % 200;
      fill(0, n);
      buf_[0] &= 0x80;  // peer 0..255, sent time maybe
      count = &counts_.enet_like;
    } else {  // longer than ENet reads
      n = 5000;
      fill(0, n);
      count = &counts_.oversize;
    }
    if (::sendto(fd_, buf_, n, 0, reinterpret_cast<const sockaddr*>(&to), sizeof to) >= 0) {
      ++*count;
      ++counts_.sent;
    } else {
      ++counts_.failed;
    }
  }

  /// Floods at rate_hz datagrams per second (in bursts every millisecond)
  /// until stop is set or duration_s has passed.
  void run(int port, double rate_hz, double duration_s, const std::atomic<bool>& stop) {
    using Clock = std::chrono::steady_clock;
    const auto start = Clock::now();
    double owed = 0.0;
    for (std::int64_t ms = 1; !stop.load(); ++ms) {
      const double t = std::chrono::duration<double>(Clock::now() - start).count();
      if (t >= duration_s) break;
      owed += rate_hz * 1e-3;
      for (; owed >= 1.0; owed -= 1.0) send_one(port);
      std::this_thread::sleep_until(start + std::chrono::milliseconds(ms));
    }
  }

  const Counts& counts() const { return counts_; }

 private:
  int fd_;
  std::mt19937 rng_;
  std::uint8_t buf_[5000] = {};
  std::uint8_t noise_[1 << 16] = {};
  Counts counts_;
};

/// A real ENet client (Debian's libenet) trying to take a station's session
/// over: connects, then sends what an attacker without the key can (a HELLO
/// made with another key, one replayed from itself, random bytes on every
/// channel, or nothing at all), and connects again once refused.
class Intruder {
 public:
  struct Counts {
    std::int64_t attempts = 0, connected = 0, refused = 0, silent = 0;
    std::int64_t refusal_codes[8] = {};
  };
  explicit Intruder(std::uint32_t seed = 2) : rng_(seed) {
    enet_initialize();
    host_ = enet_host_create(nullptr, 1, 3, 0, 0);
  }
  ~Intruder() {
    if (host_) enet_host_destroy(host_);
    enet_deinitialize();
  }
  Intruder(const Intruder&) = delete;
  Intruder& operator=(const Intruder&) = delete;

  /// Attacks 127.0.0.1:port until stop is set or duration_s has passed.
  void run(int port, double duration_s, const std::atomic<bool>& stop) {
    using Clock = std::chrono::steady_clock;
    const auto start = Clock::now();
    ENetAddress a{};
    enet_address_set_host_ip(&a, "127.0.0.1");
    a.port = std::uint16_t(port);
    ENetPeer* peer = nullptr;
    while (!stop.load() && std::chrono::duration<double>(Clock::now() - start).count() < duration_s) {
      if (!peer) {
        peer = enet_host_connect(host_, &a, 3, 0);
        enet_peer_timeout(peer, 0, 500, 1000);
        ++counts_.attempts;
      }
      ENetEvent e;
      while (enet_host_service(host_, &e, 1) > 0) {
        if (e.type == ENET_EVENT_TYPE_CONNECT) {
          ++counts_.connected;
          attack(e.peer);
        } else if (e.type == ENET_EVENT_TYPE_RECEIVE) {
          enet_packet_destroy(e.packet);
        } else if (e.type == ENET_EVENT_TYPE_DISCONNECT) {
          if (e.data > 0) {
            ++counts_.refused;
            ++counts_.refusal_codes[std::min<std::uint32_t>(e.data, 7)];
          }
          peer = nullptr;
        }
      }
    }
    if (peer) enet_peer_reset(peer);
  }

  const Counts& counts() const { return counts_; }

 private:
  void send(ENetPeer* p, std::uint8_t channel, const std::uint8_t* data, std::size_t n) {
    ENetPacket* packet = enet_packet_create(data, n, ENET_PACKET_FLAG_RELIABLE);
    if (enet_peer_send(p, channel, packet) != 0) enet_packet_destroy(packet);
  }
  void attack(ENetPeer* p) {
    const int how = int(rng_() % 4);
    if (how == 0) {  // a HELLO of another key
      net::LinkKey other;
      for (auto& b : other.bytes) b = std::uint8_t(rng_());
      net::HandshakeInitiator hello(other, rng_());
      send(p, 2, hello.hello().data(), hello.hello().size());
    } else if (how == 1) {  // random bytes on each channel
      std::uint8_t junk[200];
      for (auto& b : junk) b = std::uint8_t(rng_());
      for (std::uint8_t ch = 0; ch < 3; ++ch) send(p, ch, junk, 1 + rng_() % sizeof junk);
    } else if (how == 2) {  // a sealed-looking datagram (kind 3) with no key behind it
      std::uint8_t sealed[60] = {3, 0, 0, 0};
      for (std::size_t i = 4; i < sizeof sealed; ++i) sealed[i] = std::uint8_t(rng_());
      send(p, 0, sealed, sizeof sealed);
    } else {  // nothing: the station must not wait for it forever
      ++counts_.silent;
    }
    enet_host_flush(host_);
  }

  ENetHost* host_ = nullptr;
  std::mt19937 rng_;
  Counts counts_;
};

}  // namespace terracut::test
