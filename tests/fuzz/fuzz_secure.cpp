// Fuzz target: the authenticated sessions of the UDP link (net/secure.hpp) --
// the remote's answer to a HELLO, the operator's check of a WELCOME, and the
// opening of a sealed datagram, whatever the bytes.
//
// The first byte chooses what the rest becomes:
//  0: a HELLO to answer (the remote's key is fixed);
//  1: a WELCOME to check against a HELLO of the fixed key;
//  2: a sealed datagram to open in a fixed session;
//  3: a message sealed in that session, then (first byte >> 2) of its bytes
//     flipped at positions the following bytes give, then opened twice.
//
// Checked: nothing reads outside the input (the sanitizers); no random HELLO
// or WELCOME is accepted (a tag of 32 bytes, forged by chance: never); an
// opened datagram's plaintext is its size less the overhead; an unflipped
// sealed message opens to exactly its bytes on its channel, a flipped one
// never opens, and a second opening of the same bytes is refused as a replay.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <vector>

#include "fuzz_file.hpp"
#include "terracut/net/secure.hpp"

namespace {

using namespace terracut::net;
using terracut::fuzz::check;
constexpr const char* kTarget = "fuzz_secure";

LinkKey fixed_key(std::uint8_t seed) {
  LinkKey k;
  for (std::size_t i = 0; i < k.bytes.size(); ++i) k.bytes[i] = std::uint8_t(seed + 13 * i);
  return k;
}

// Both sides of one session made by a handshake between holders of the key.
struct Session {
  Session() {
    HandshakeInitiator init(fixed_key(1), 5u);
    std::array<std::uint8_t, kWelcomeSize> welcome{};
    SessionKeys remote_keys, op_keys;
    std::uint32_t id = 0, remote_id = 0;
    check(answer_hello(fixed_key(1), 9u, init.hello().data(), kHelloSize, id, welcome, remote_keys) ==
              AuthReject::kNone,
          kTarget, "the fixed handshake failed");
    check(init.accept(welcome.data(), welcome.size(), op_keys, remote_id) == AuthReject::kNone, kTarget,
          "the fixed handshake's WELCOME failed");
    op = std::make_unique<SecureChannel>(op_keys);
    remote = std::make_unique<SecureChannel>(remote_keys);
  }
  std::unique_ptr<SecureChannel> op, remote;
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const std::uint8_t control = data[0];
  const std::uint8_t* bytes = data + 1;
  const std::size_t n = size - 1;
  switch (control & 3) {
    case 0: {
      std::array<std::uint8_t, kWelcomeSize> welcome{};
      SessionKeys keys;
      std::uint32_t id = 0;
      const AuthReject r = answer_hello(fixed_key(1), 9u, bytes, n, id, welcome, keys);
      check(r != AuthReject::kNone, kTarget, "a HELLO forged by chance was accepted");
      break;
    }
    case 1: {
      const HandshakeInitiator init(fixed_key(1), 5u);
      SessionKeys keys;
      std::uint32_t remote_id = 0;
      check(init.accept(bytes, n, keys, remote_id) != AuthReject::kNone, kTarget,
            "a WELCOME forged by chance was accepted");
      break;
    }
    case 2: {
      Session s;
      std::vector<std::uint8_t> out(n + 1);
      std::size_t opened = 0;
      std::uint8_t channel = 0;
      if (s.remote->open(bytes, n, out.data(), opened, channel) == AuthReject::kNone)
        check(opened + kSealOverhead == n && channel < kSealedChannels, kTarget, "a sealed datagram of the wrong size opened");
      break;
    }
    case 3: {
      Session s;
      const std::size_t flips = control >> 2;
      const std::size_t message = n > 2 * flips ? n - 2 * flips : 0;
      const std::uint8_t channel = message > 0 ? bytes[0] % kSealedChannels : 0;
      std::vector<std::uint8_t> sealed(message + kSealOverhead);
      sealed.resize(s.op->seal(channel, bytes, message, sealed.data()));
      bool changed = false;
      for (std::size_t i = 0; i < flips && message + 2 * i + 1 < n; ++i) {
        const std::size_t at = bytes[message + 2 * i] % sealed.size();
        const std::uint8_t mask = bytes[message + 2 * i + 1];
        sealed[at] ^= mask;
        changed = changed || mask != 0;
      }
      std::vector<std::uint8_t> out(sealed.size());
      std::size_t opened = 0;
      std::uint8_t got_channel = 0;
      const AuthReject r = s.remote->open(sealed.data(), sealed.size(), out.data(), opened, got_channel);
      if (!changed) {
        check(r == AuthReject::kNone && opened == message && got_channel == channel &&
                  (message == 0 || std::memcmp(out.data(), bytes, message) == 0),
              kTarget, "an untouched sealed message did not open to its bytes");
        check(s.remote->open(sealed.data(), sealed.size(), out.data(), opened, got_channel) == AuthReject::kReplayed,
              kTarget, "a sealed message opened twice");
      } else {
        // Flips may cancel out (the same byte twice): then it is the original.
        if (r == AuthReject::kNone)
          check(opened == message && (message == 0 || std::memcmp(out.data(), bytes, message) == 0),
                kTarget, "a flipped sealed message opened to other bytes");
      }
      break;
    }
  }
  return 0;
}
