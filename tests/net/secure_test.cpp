// Authenticated sessions (secure.hpp): the handshake agrees on keys only
// between holders of the same pre-shared key; a sealed datagram opens once,
// on its own channel, and a forged tag, a replay, a truncated or a foreign
// datagram is refused by name; key files are refused when their permissions,
// size or contents are wrong.
#include "terracut/net/secure.hpp"

#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <random>

#include "terracut/core/error.hpp"

namespace terracut::net {
namespace {

namespace fs = std::filesystem;

LinkKey key_of(std::uint8_t seed) {
  LinkKey k;
  for (std::size_t i = 0; i < k.bytes.size(); ++i) k.bytes[i] = std::uint8_t(seed * 31 + i);
  return k;
}

// Runs the handshake; returns both sides' keys (empty optional: refused, reason in why).
struct Handshake {
  AuthReject remote = AuthReject::kNone, op = AuthReject::kNone;
  SessionKeys op_keys, remote_keys;
  std::uint32_t seen_operator = 0, seen_remote = 0;
};
Handshake handshake(const LinkKey& op_key, const LinkKey& remote_key) {
  Handshake h;
  HandshakeInitiator init(op_key, 0xABCD1234u);
  std::array<std::uint8_t, kWelcomeSize> welcome{};
  h.remote = answer_hello(remote_key, 77u, init.hello().data(), init.hello().size(), h.seen_operator,
                          welcome, h.remote_keys);
  if (h.remote == AuthReject::kNone)
    h.op = init.accept(welcome.data(), welcome.size(), h.op_keys, h.seen_remote);
  return h;
}

TEST(Handshake, TheSameKeyAgreesOnOneKeyPerDirection) {
  const Handshake h = handshake(key_of(1), key_of(1));
  ASSERT_EQ(h.remote, AuthReject::kNone);
  ASSERT_EQ(h.op, AuthReject::kNone);
  EXPECT_EQ(h.seen_operator, 0xABCD1234u);
  EXPECT_EQ(h.seen_remote, 77u);
  EXPECT_EQ(h.op_keys.send, h.remote_keys.receive);
  EXPECT_EQ(h.op_keys.receive, h.remote_keys.send);
  EXPECT_NE(h.op_keys.send, h.op_keys.receive);
  // Each handshake makes new keys (fresh ephemeral keys on both sides).
  const Handshake again = handshake(key_of(1), key_of(1));
  EXPECT_NE(again.op_keys.send, h.op_keys.send);
}

TEST(Handshake, AnotherKeyIsRefusedAtTheHello) {
  EXPECT_EQ(handshake(key_of(1), key_of(2)).remote, AuthReject::kBadMac);
  // A key differing in one bit.
  LinkKey k = key_of(1);
  k.bytes[31] ^= 1;
  EXPECT_EQ(handshake(key_of(1), k).remote, AuthReject::kBadMac);
}

TEST(Handshake, InsecureAndKeyedStationsRefuseEachOtherByName) {
  EXPECT_EQ(handshake(insecure_key(), key_of(1)).remote, AuthReject::kInsecure);
  EXPECT_EQ(handshake(key_of(1), insecure_key()).remote, AuthReject::kInsecure);
  EXPECT_EQ(handshake(insecure_key(), insecure_key()).op, AuthReject::kNone);
}

TEST(Handshake, AForgedOrDamagedWelcomeIsRefused) {
  const LinkKey k = key_of(3);
  HandshakeInitiator init(k, 5u);
  std::array<std::uint8_t, kWelcomeSize> welcome{};
  SessionKeys keys;
  std::uint32_t id = 0;
  ASSERT_EQ(answer_hello(k, 9u, init.hello().data(), kHelloSize, id, welcome, keys), AuthReject::kNone);
  // Every byte flipped in turn: refused (the format's bytes, or the tag).
  for (std::size_t i = 0; i < kWelcomeSize; ++i) {
    auto w = welcome;
    w[i] ^= 0x40;
    SessionKeys out;
    std::uint32_t remote = 0;
    EXPECT_NE(init.accept(w.data(), w.size(), out, remote), AuthReject::kNone) << "byte " << i;
  }
  // A WELCOME made for another HELLO (a replayed answer) does not verify.
  HandshakeInitiator other(k, 5u);
  SessionKeys out;
  std::uint32_t remote = 0;
  EXPECT_EQ(other.accept(welcome.data(), welcome.size(), out, remote), AuthReject::kBadMac);
  EXPECT_EQ(init.accept(welcome.data(), kWelcomeSize - 1, out, remote), AuthReject::kTruncated);
  EXPECT_EQ(init.accept(welcome.data(), 3, out, remote), AuthReject::kTruncated);
}

TEST(Handshake, ADamagedHelloIsRefusedNeverAnswered) {
  const LinkKey k = key_of(4);
  HandshakeInitiator init(k, 5u);
  for (std::size_t i = 0; i < kHelloSize; ++i) {
    auto h = init.hello();
    h[i] ^= 0x01;
    std::array<std::uint8_t, kWelcomeSize> welcome{};
    SessionKeys keys;
    std::uint32_t id = 0;
    EXPECT_NE(answer_hello(k, 1u, h.data(), h.size(), id, welcome, keys), AuthReject::kNone) << "byte " << i;
  }
  // Random bytes of every length up to twice a HELLO: never accepted.
  std::mt19937 rng(11);
  for (int n = 0; n < 2 * int(kHelloSize); ++n) {
    std::vector<std::uint8_t> junk(static_cast<std::size_t>(n));
    for (auto& b : junk) b = std::uint8_t(rng());
    std::array<std::uint8_t, kWelcomeSize> welcome{};
    SessionKeys keys;
    std::uint32_t id = 0;
    EXPECT_NE(answer_hello(k, 1u, junk.data(), junk.size(), id, welcome, keys), AuthReject::kNone);
  }
}

// A session's two channels, joined by a handshake.
struct Session {
  Session() {
    const Handshake h = handshake(key_of(7), key_of(7));
    op = std::make_unique<SecureChannel>(h.op_keys);
    remote = std::make_unique<SecureChannel>(h.remote_keys);
  }
  std::unique_ptr<SecureChannel> op, remote;
};

std::vector<std::uint8_t> seal(SecureChannel& c, std::uint8_t channel, const std::vector<std::uint8_t>& m) {
  std::vector<std::uint8_t> out(m.size() + kSealOverhead);
  out.resize(c.seal(channel, m.data(), m.size(), out.data()));
  return out;
}

AuthReject open(SecureChannel& c, const std::vector<std::uint8_t>& d, std::vector<std::uint8_t>& m,
                std::uint8_t& channel) {
  m.assign(d.size(), 0);
  std::size_t n = 0;
  const AuthReject r = c.open(d.data(), d.size(), m.data(), n, channel);
  m.resize(r == AuthReject::kNone ? n : 0);
  return r;
}

TEST(SecureChannel, OpensWhatTheOtherSideSealedOnItsChannel) {
  Session s;
  const std::vector<std::uint8_t> m{1, 2, 3, 4, 5, 6, 7};
  for (std::uint8_t ch = 0; ch < kSealedChannels; ++ch) {
    const auto d = seal(*s.op, ch, m);
    EXPECT_EQ(d.size(), m.size() + kSealOverhead);
    std::vector<std::uint8_t> got;
    std::uint8_t channel = 99;
    ASSERT_EQ(open(*s.remote, d, got, channel), AuthReject::kNone);
    EXPECT_EQ(got, m);
    EXPECT_EQ(channel, ch);
  }
  // Empty messages too; and the ciphertext does not show the plaintext.
  const auto d = seal(*s.remote, 1, std::vector<std::uint8_t>(64, 0));
  std::size_t zeros = 0;
  for (std::size_t i = kSealHeaderSize; i < d.size(); ++i) zeros += d[i] == 0;
  EXPECT_LT(zeros, 8u);
  std::vector<std::uint8_t> got;
  std::uint8_t channel = 0;
  EXPECT_EQ(open(*s.op, seal(*s.remote, 0, {}), got, channel), AuthReject::kNone);
  EXPECT_TRUE(got.empty());
}

TEST(SecureChannel, AForgedTagAWrongKeyOrADamagedByteIsBadMac) {
  Session s;
  const std::vector<std::uint8_t> m(40, 9);
  const auto d = seal(*s.op, 0, m);
  std::vector<std::uint8_t> got;
  std::uint8_t channel = 0;
  for (std::size_t i = 4; i < d.size(); ++i) {  // the counter, the ciphertext, the tag
    auto bad = d;
    bad[i] ^= 0x80;
    EXPECT_EQ(open(*s.remote, bad, got, channel), AuthReject::kBadMac) << "byte " << i;
  }
  // Sealed with the operator's own receive direction (or another session's key).
  Session other;
  EXPECT_EQ(open(*s.remote, seal(*other.op, 0, m), got, channel), AuthReject::kBadMac);
  EXPECT_EQ(open(*s.op, seal(*s.op, 0, m), got, channel), AuthReject::kBadMac);
  // The real one still opens after all that.
  EXPECT_EQ(open(*s.remote, d, got, channel), AuthReject::kNone);
}

TEST(SecureChannel, AReplayedDatagramIsRefusedOnceOpened) {
  Session s;
  std::vector<std::vector<std::uint8_t>> sent;
  for (int i = 0; i < 3000; ++i) sent.push_back(seal(*s.op, 0, {std::uint8_t(i)}));
  std::vector<std::uint8_t> got;
  std::uint8_t channel = 0;
  // Out of order within the window: each opens once.
  ASSERT_EQ(open(*s.remote, sent[10], got, channel), AuthReject::kNone);
  ASSERT_EQ(open(*s.remote, sent[5], got, channel), AuthReject::kNone);
  EXPECT_EQ(open(*s.remote, sent[5], got, channel), AuthReject::kReplayed);
  EXPECT_EQ(open(*s.remote, sent[10], got, channel), AuthReject::kReplayed);
  ASSERT_EQ(open(*s.remote, sent[6], got, channel), AuthReject::kNone);
  // Far ahead: older than the window is refused even if never seen.
  ASSERT_EQ(open(*s.remote, sent[2500], got, channel), AuthReject::kNone);
  EXPECT_EQ(open(*s.remote, sent[2500 - kReplayWindow], got, channel), AuthReject::kReplayed);
  EXPECT_EQ(open(*s.remote, sent[7], got, channel), AuthReject::kReplayed);
  ASSERT_EQ(open(*s.remote, sent[2500 - kReplayWindow + 1], got, channel), AuthReject::kNone);
  ASSERT_EQ(open(*s.remote, sent[2499], got, channel), AuthReject::kNone);
  EXPECT_EQ(open(*s.remote, sent[2499], got, channel), AuthReject::kReplayed);
  // Channels have their own counters: a reliable datagram is not a replay of an unreliable one.
  EXPECT_EQ(open(*s.remote, seal(*s.op, 1, {1}), got, channel), AuthReject::kNone);
  EXPECT_EQ(channel, 1);
}

TEST(SecureChannel, TruncatedOrForeignBytesAreRefusedByName) {
  Session s;
  const auto d = seal(*s.op, 1, std::vector<std::uint8_t>(20, 3));
  std::vector<std::uint8_t> got;
  std::uint8_t channel = 0;
  for (std::size_t n = 0; n < kSealOverhead; ++n)
    EXPECT_EQ(open(*s.remote, std::vector<std::uint8_t>(d.begin(), d.begin() + std::ptrdiff_t(n)), got, channel),
              AuthReject::kTruncated)
        << n;
  // Shorter than sealed: the tag no longer verifies.
  EXPECT_EQ(open(*s.remote, std::vector<std::uint8_t>(d.begin(), d.end() - 1), got, channel), AuthReject::kBadMac);
  auto bad = d;
  bad[0] = 7;  // not a sealed datagram
  EXPECT_EQ(open(*s.remote, bad, got, channel), AuthReject::kBadFormat);
  bad = d;
  bad[1] = 3;  // no such channel
  EXPECT_EQ(open(*s.remote, bad, got, channel), AuthReject::kBadFormat);
}

TEST(ReplayWindow, AcceptsEachCounterOnceWithinTheWindow) {
  ReplayWindow w;
  std::mt19937 rng(3);
  std::vector<bool> seen(5000, false);
  std::uint64_t newest = 0;
  bool any = false;
  for (int i = 0; i < 20000; ++i) {
    const std::uint64_t c = std::uniform_int_distribution<std::uint64_t>(0, 4999)(rng);
    const bool expect = !any || c > newest || (newest - c < kReplayWindow && !seen[c]);
    ASSERT_EQ(w.fresh(c), expect) << "counter " << c << " newest " << newest;
    if (expect) {
      w.accept(c);
      seen[c] = true;
      if (!any || c > newest) newest = c;
      any = true;
    }
  }
}

// A key file in a fresh folder, with the given text and mode.
fs::path key_file(const std::string& name, const std::string& text, mode_t mode) {
  const fs::path dir = fs::temp_directory_path() / ("terracut_keys_" + std::to_string(getpid()));
  fs::create_directories(dir);
  const fs::path p = dir / name;
  fs::remove(p);
  std::ofstream(p) << text;
  ::chmod(p.c_str(), mode);
  return p;
}

std::string refusal(const fs::path& p) {
  try {
    read_key_file(p);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(KeyFile, WrittenReadBackAndNeverOverwritten) {
  const fs::path p = key_file("new.key", "", 0600), p2 = p.string() + "2";
  fs::remove(p);
  fs::remove(p2);
  const LinkKey k = write_new_key_file(p);
  EXPECT_EQ((fs::status(p).permissions() & fs::perms::mask), fs::perms::owner_read | fs::perms::owner_write);
  EXPECT_EQ(fs::file_size(p), 65u);
  const LinkKey back = read_key_file(p);
  EXPECT_EQ(back.bytes, k.bytes);
  EXPECT_FALSE(back.insecure);
  EXPECT_EQ(fingerprint(back), fingerprint(k));
  EXPECT_EQ(fingerprint(k).size(), 16u);
  EXPECT_NE(fingerprint(k), fingerprint(write_new_key_file(p2)));
  EXPECT_THROW(write_new_key_file(p), InputError);
  EXPECT_EQ(read_key_file(p).bytes, k.bytes);  // untouched
}

TEST(KeyFile, BadFilesAreRefusedNamingWhatIsWrong) {
  const std::string hex(64, 'a');
  EXPECT_EQ(read_key_file(key_file("ok.key", hex + "\n", 0600)).bytes[0], 0xAA);
  EXPECT_EQ(read_key_file(key_file("ok_ro.key", hex, 0400)).bytes[31], 0xAA);
  std::string e = refusal(key_file("open.key", hex + "\n", 0644));
  EXPECT_NE(e.find("read or written by others (mode 0644)"), std::string::npos) << e;
  EXPECT_NE(e.find("chmod 600"), std::string::npos) << e;
  e = refusal(key_file("group.key", hex + "\n", 0620));
  EXPECT_NE(e.find("mode 0620"), std::string::npos) << e;
  e = refusal(key_file("short.key", hex.substr(0, 40) + "\n", 0600));
  EXPECT_NE(e.find("holds 41 bytes"), std::string::npos) << e;
  e = refusal(key_file("long.key", hex + hex + "\n", 0600));
  EXPECT_NE(e.find("holds 129 bytes"), std::string::npos) << e;
  e = refusal(key_file("empty.key", "", 0600));
  EXPECT_NE(e.find("holds 0 bytes"), std::string::npos) << e;
  e = refusal(key_file("nothex.key", std::string(63, 'a') + "g\n", 0600));
  EXPECT_NE(e.find("hex digits"), std::string::npos) << e;
  e = refusal(key_file("missing.key", "", 0600).string() + ".nowhere");
  EXPECT_NE(e.find("cannot be opened"), std::string::npos) << e;
  e = refusal(fs::temp_directory_path());
  EXPECT_NE(e.find("not a regular file"), std::string::npos) << e;
  // Every error names the file.
  EXPECT_NE(refusal(key_file("named.key", "x", 0600)).find("named.key"), std::string::npos);
}

TEST(KeyText, SixtyFourHexDigitsOrANamedRefusal) {
  EXPECT_EQ(parse_key("  " + std::string(64, 'F') + "\n", "TERRACUT_MMT_KEY").bytes[5], 0xFF);
  try {
    parse_key("abc", "TERRACUT_MMT_KEY");
    FAIL() << "accepted a short key";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("TERRACUT_MMT_KEY: a key is 64 hex digits"), std::string::npos) << e.what();
  }
  EXPECT_THROW(parse_key(std::string(64, 'z'), "env"), InputError);
}

}  // namespace
}  // namespace terracut::net
