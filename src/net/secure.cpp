// Keys, the handshake and sealed datagrams (secure.hpp), on libsodium.
#include "terracut/net/secure.hpp"

#include <fcntl.h>
#include <sodium.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>

#include "terracut/core/error.hpp"
#include "terracut/core/wire.hpp"

namespace terracut::net {
namespace {

constexpr std::uint8_t kHandshakeMagic[4] = {'T', 'C', 'A', 'H'};
constexpr std::uint16_t kHandshakeVersion = 1;
constexpr std::uint8_t kKindHello = 1, kKindWelcome = 2, kKindSealed = 3;
constexpr std::uint8_t kFlagInsecure = 1;
constexpr std::size_t kHexDigits = 2 * kKeySize;
// Offsets in HELLO and WELCOME.
constexpr std::size_t kHelloKeyAt = 12, kHelloTagAt = 44;
constexpr std::size_t kWelcomeKeyAt = 16, kWelcomeTagAt = 48;
static_assert(kHelloTagAt + 32 == kHelloSize && kWelcomeTagAt + 32 == kWelcomeSize);
static_assert(crypto_kx_PUBLICKEYBYTES == 32 && crypto_kx_SECRETKEYBYTES == 32 &&
              crypto_kx_SESSIONKEYBYTES == kKeySize);
static_assert(crypto_aead_chacha20poly1305_ietf_NPUBBYTES == kSealHeaderSize &&
              crypto_aead_chacha20poly1305_ietf_ABYTES == kSealTagSize &&
              crypto_aead_chacha20poly1305_ietf_KEYBYTES == kKeySize);

void ensure_sodium() {
  // Safe to call from any thread, any number of times.
  if (sodium_init() < 0) throw InputError("libsodium could not be initialised");
}

using Key = std::array<std::uint8_t, kKeySize>;

// The key the handshake's tags are keyed with, derived from the pre-shared one.
Key handshake_key(const LinkKey& k) {
  Key out{};
  crypto_kdf_derive_from_key(out.data(), out.size(), 1, "tcmm-hs1", k.bytes.data());
  return out;
}

void put_prefix(std::uint8_t* p, std::uint8_t kind, bool insecure) {
  std::memcpy(p, kHandshakeMagic, 4);
  wire::put_u16(p + 4, kHandshakeVersion);
  p[6] = kind;
  p[7] = insecure ? kFlagInsecure : 0;
}

// kNone when data is a handshake message of this kind and its size.
AuthReject check_prefix(const std::uint8_t* data, std::size_t size, std::uint8_t kind,
                        std::size_t expected) {
  if (size < 8) return AuthReject::kTruncated;
  if (std::memcmp(data, kHandshakeMagic, 4) != 0 || wire::get_u16(data + 4) != kHandshakeVersion ||
      data[6] != kind || (data[7] & ~kFlagInsecure) != 0)
    return AuthReject::kBadFormat;
  if (size != expected) return AuthReject::kTruncated;
  return AuthReject::kNone;
}

void tag_of(const Key& hk, const std::uint8_t* a, std::size_t a_size, const std::uint8_t* b,
            std::size_t b_size, std::uint8_t* tag) {
  crypto_generichash_state st;
  crypto_generichash_init(&st, hk.data(), hk.size(), 32);
  crypto_generichash_update(&st, a, a_size);
  if (b_size > 0) crypto_generichash_update(&st, b, b_size);
  crypto_generichash_final(&st, tag, 32);
}

// One direction's key: crypto_kx's shared key hashed with the handshake key,
// the direction and both tags.
Key session_key(const Key& hk, const char* direction, const std::uint8_t* kx_key,
                const std::uint8_t* hello_tag, const std::uint8_t* welcome_tag) {
  Key out{};
  crypto_generichash_state st;
  crypto_generichash_init(&st, hk.data(), hk.size(), out.size());
  crypto_generichash_update(&st, reinterpret_cast<const std::uint8_t*>(direction), 5);
  crypto_generichash_update(&st, kx_key, kKeySize);
  crypto_generichash_update(&st, hello_tag, 32);
  crypto_generichash_update(&st, welcome_tag, 32);
  crypto_generichash_final(&st, out.data(), out.size());
  return out;
}

std::string errno_text() { return std::strerror(errno); }

}  // namespace

std::string_view to_string(AuthReject reason) {
  switch (reason) {
    case AuthReject::kNone: return "none";
    case AuthReject::kTruncated: return "truncated";
    case AuthReject::kBadFormat: return "bad_format";
    case AuthReject::kBadMac: return "bad_mac";
    case AuthReject::kReplayed: return "replayed";
    case AuthReject::kInsecure: return "insecure_mismatch";
  }
  return "unknown";
}

LinkKey insecure_key() {
  LinkKey k;
  k.insecure = true;
  return k;
}

LinkKey parse_key(std::string_view text, const std::string& source) {
  ensure_sodium();
  const auto space = [](char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; };
  while (!text.empty() && space(text.front())) text.remove_prefix(1);
  while (!text.empty() && space(text.back())) text.remove_suffix(1);
  const std::string how = "make one with `terracut key --out FILE`";
  if (text.size() != kHexDigits)
    throw InputError(source + ": a key is " + std::to_string(kHexDigits) + " hex digits (" +
                     std::to_string(kKeySize) + " bytes), got " + std::to_string(text.size()) +
                     " characters; " + how);
  LinkKey k;
  std::size_t got = 0;
  if (sodium_hex2bin(k.bytes.data(), k.bytes.size(), text.data(), text.size(), nullptr, &got,
                     nullptr) != 0 ||
      got != kKeySize)
    throw InputError(source + ": a key is " + std::to_string(kHexDigits) +
                     " hex digits (0-9, a-f); this is not; " + how);
  return k;
}

LinkKey read_key_file(const std::filesystem::path& path) {
  const std::string name = path.string();
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw InputError(name + ": the key file cannot be opened: " + errno_text());
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  struct stat st{};
  if (::fstat(fd, &st) != 0) throw InputError(name + ": the key file cannot be read: " + errno_text());
  if (!S_ISREG(st.st_mode)) throw InputError(name + ": the key file is not a regular file");
  if ((st.st_mode & 077) != 0) {
    char mode[8];
    std::snprintf(mode, sizeof mode, "%04o", unsigned(st.st_mode & 07777));
    throw InputError(name + ": the key file may be read or written by others (mode " + mode +
                     "); a key must be its owner's alone: chmod 600 " + name);
  }
  if (st.st_size < off_t(kHexDigits) || st.st_size > off_t(kHexDigits + 2))
    throw InputError(name + ": the key file holds " + std::to_string(st.st_size) +
                     " bytes; a key file holds " + std::to_string(kHexDigits) +
                     " hex digits and a newline (make one with `terracut key --out FILE`)");
  char text[kHexDigits + 2];
  const ssize_t n = ::read(fd, text, sizeof text);
  if (n != ssize_t(st.st_size)) throw InputError(name + ": the key file cannot be read whole");
  LinkKey k = parse_key(std::string_view(text, std::size_t(n)), name);
  sodium_memzero(text, sizeof text);
  return k;
}

LinkKey write_new_key_file(const std::filesystem::path& path) {
  ensure_sodium();
  const std::string name = path.string();
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  if (fd < 0)
    throw InputError(name + ": cannot create the key file: " + errno_text() +
                     (errno == EEXIST ? " (an existing key is never overwritten)" : ""));
  LinkKey k;
  randombytes_buf(k.bytes.data(), k.bytes.size());
  char hex[kHexDigits + 1];
  sodium_bin2hex(hex, sizeof hex, k.bytes.data(), k.bytes.size());
  hex[kHexDigits] = '\n';
  const bool ok = ::fchmod(fd, 0600) == 0 && ::write(fd, hex, sizeof hex) == ssize_t(sizeof hex) &&
                  ::fsync(fd) == 0;
  sodium_memzero(hex, sizeof hex);
  const bool closed = ::close(fd) == 0;
  if (!ok || !closed) {
    ::unlink(path.c_str());
    throw InputError(name + ": cannot write the key file: " + errno_text());
  }
  return k;
}

std::string fingerprint(const LinkKey& key) {
  ensure_sodium();
  static constexpr char kLabel[] = "terracut mmt key fingerprint";
  std::uint8_t h[8];
  crypto_generichash_state st;
  crypto_generichash_init(&st, nullptr, 0, sizeof h);
  crypto_generichash_update(&st, reinterpret_cast<const std::uint8_t*>(kLabel), sizeof kLabel - 1);
  crypto_generichash_update(&st, key.bytes.data(), key.bytes.size());
  crypto_generichash_final(&st, h, sizeof h);
  char hex[2 * sizeof h + 1];
  sodium_bin2hex(hex, sizeof hex, h, sizeof h);
  return hex;
}

bool is_handshake(const std::uint8_t* data, std::size_t size) {
  return size >= 4 && std::memcmp(data, kHandshakeMagic, 4) == 0;
}

HandshakeInitiator::HandshakeInitiator(const LinkKey& key, std::uint32_t operator_id)
    : insecure_(key.insecure) {
  ensure_sodium();
  handshake_key_ = handshake_key(key);
  put_prefix(hello_.data(), kKindHello, key.insecure);
  wire::put_u32(hello_.data() + 8, operator_id);
  crypto_kx_keypair(hello_.data() + kHelloKeyAt, secret_.data());
  tag_of(handshake_key_, hello_.data(), kHelloTagAt, nullptr, 0, hello_.data() + kHelloTagAt);
}

HandshakeInitiator::~HandshakeInitiator() {
  sodium_memzero(secret_.data(), secret_.size());
  sodium_memzero(handshake_key_.data(), handshake_key_.size());
}

AuthReject HandshakeInitiator::accept(const std::uint8_t* w, std::size_t size, SessionKeys& keys,
                                      std::uint32_t& remote_id) const {
  if (const AuthReject r = check_prefix(w, size, kKindWelcome, kWelcomeSize); r != AuthReject::kNone)
    return r;
  if (bool(w[7] & kFlagInsecure) != insecure_) return AuthReject::kInsecure;
  std::uint8_t tag[32];
  tag_of(handshake_key_, hello_.data(), hello_.size(), w, kWelcomeTagAt, tag);
  if (sodium_memcmp(tag, w + kWelcomeTagAt, 32) != 0 ||
      std::memcmp(w + 8, hello_.data() + 8, 4) != 0)
    return AuthReject::kBadMac;
  std::uint8_t rx[kKeySize], tx[kKeySize];
  if (crypto_kx_client_session_keys(rx, tx, hello_.data() + kHelloKeyAt, secret_.data(),
                                    w + kWelcomeKeyAt) != 0)
    return AuthReject::kBadMac;
  keys.send = session_key(handshake_key_, "op>rm", tx, hello_.data() + kHelloTagAt, w + kWelcomeTagAt);
  keys.receive = session_key(handshake_key_, "rm>op", rx, hello_.data() + kHelloTagAt, w + kWelcomeTagAt);
  sodium_memzero(rx, sizeof rx);
  sodium_memzero(tx, sizeof tx);
  remote_id = wire::get_u32(w + 12);
  return AuthReject::kNone;
}

AuthReject answer_hello(const LinkKey& key, std::uint32_t remote_id, const std::uint8_t* h,
                        std::size_t size, std::uint32_t& operator_id,
                        std::array<std::uint8_t, kWelcomeSize>& welcome, SessionKeys& keys) {
  if (sodium_init() < 0) return AuthReject::kBadMac;
  if (const AuthReject r = check_prefix(h, size, kKindHello, kHelloSize); r != AuthReject::kNone)
    return r;
  if (bool(h[7] & kFlagInsecure) != key.insecure) return AuthReject::kInsecure;
  Key hk = handshake_key(key);
  std::uint8_t tag[32];
  tag_of(hk, h, kHelloTagAt, nullptr, 0, tag);
  if (sodium_memcmp(tag, h + kHelloTagAt, 32) != 0) {
    sodium_memzero(hk.data(), hk.size());
    return AuthReject::kBadMac;
  }
  std::uint8_t secret[32];
  put_prefix(welcome.data(), kKindWelcome, key.insecure);
  std::memcpy(welcome.data() + 8, h + 8, 4);
  wire::put_u32(welcome.data() + 12, remote_id);
  crypto_kx_keypair(welcome.data() + kWelcomeKeyAt, secret);
  std::uint8_t rx[kKeySize], tx[kKeySize];
  const bool ok = crypto_kx_server_session_keys(rx, tx, welcome.data() + kWelcomeKeyAt, secret,
                                                h + kHelloKeyAt) == 0;
  sodium_memzero(secret, sizeof secret);
  if (ok) {
    tag_of(hk, h, kHelloSize, welcome.data(), kWelcomeTagAt, welcome.data() + kWelcomeTagAt);
    keys.send = session_key(hk, "rm>op", tx, h + kHelloTagAt, welcome.data() + kWelcomeTagAt);
    keys.receive = session_key(hk, "op>rm", rx, h + kHelloTagAt, welcome.data() + kWelcomeTagAt);
    operator_id = wire::get_u32(h + 8);
  }
  sodium_memzero(rx, sizeof rx);
  sodium_memzero(tx, sizeof tx);
  sodium_memzero(hk.data(), hk.size());
  return ok ? AuthReject::kNone : AuthReject::kBadMac;
}

bool ReplayWindow::fresh(std::uint64_t counter) const noexcept {
  if (!any_ || counter > newest_) return true;
  if (newest_ - counter >= kReplayWindow) return false;
  const std::uint64_t bit = counter % kReplayWindow;
  return (bits_[bit / 64] & (std::uint64_t(1) << (bit % 64))) == 0;
}

void ReplayWindow::accept(std::uint64_t counter) noexcept {
  if (!any_ || counter > newest_) {
    // The counters between the newest and this one become unseen.
    if (!any_ || counter - newest_ >= kReplayWindow) {
      bits_.fill(0);
    } else {
      for (std::uint64_t c = newest_ + 1; c < counter; ++c) {
        const std::uint64_t bit = c % kReplayWindow;
        bits_[bit / 64] &= ~(std::uint64_t(1) << (bit % 64));
      }
    }
    newest_ = counter;
    any_ = true;
  }
  const std::uint64_t bit = counter % kReplayWindow;
  bits_[bit / 64] |= std::uint64_t(1) << (bit % 64);
}

SecureChannel::SecureChannel(const SessionKeys& keys) : keys_(keys) { ensure_sodium(); }

SecureChannel::~SecureChannel() {
  sodium_memzero(keys_.send.data(), keys_.send.size());
  sodium_memzero(keys_.receive.data(), keys_.receive.size());
}

std::size_t SecureChannel::seal(std::uint8_t channel, const std::uint8_t* data, std::size_t size,
                                std::uint8_t* out) noexcept {
  out[0] = kKindSealed;
  out[1] = channel;
  wire::put_u16(out + 2, 0);
  wire::put_u64(out + 4, next_[std::min<std::size_t>(channel, kSealedChannels - 1)]++);
  unsigned long long sealed = 0;
  // The header is both the nonce (unique per key: channel and counter) and
  // the additional data the tag covers.
  crypto_aead_chacha20poly1305_ietf_encrypt(out + kSealHeaderSize, &sealed, data, size, out,
                                            kSealHeaderSize, nullptr, out, keys_.send.data());
  return kSealHeaderSize + std::size_t(sealed);
}

AuthReject SecureChannel::open(const std::uint8_t* data, std::size_t size, std::uint8_t* out,
                               std::size_t& out_size, std::uint8_t& channel) noexcept {
  if (size < 1) return AuthReject::kTruncated;
  if (data[0] != kKindSealed) return AuthReject::kBadFormat;
  if (size < kSealOverhead) return AuthReject::kTruncated;
  if (data[1] >= kSealedChannels || wire::get_u16(data + 2) != 0) return AuthReject::kBadFormat;
  unsigned long long opened = 0;
  if (crypto_aead_chacha20poly1305_ietf_decrypt(out, &opened, nullptr, data + kSealHeaderSize,
                                                size - kSealHeaderSize, data, kSealHeaderSize,
                                                data, keys_.receive.data()) != 0)
    return AuthReject::kBadMac;
  ReplayWindow& w = windows_[data[1]];
  const std::uint64_t counter = wire::get_u64(data + 4);
  if (!w.fresh(counter)) return AuthReject::kReplayed;
  w.accept(counter);
  channel = data[1];
  out_size = std::size_t(opened);
  return AuthReject::kNone;
}

}  // namespace terracut::net
