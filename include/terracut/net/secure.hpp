// Authenticated, encrypted sessions between the two stations of the UDP link
// (docs/teleoperation.md, "Keys and the threat model"). Cryptography is
// libsodium's (Debian libsodium-dev); nothing here is of our own making:
//
//  - Both stations hold a pre-shared key (32 random bytes: a key file made
//    by `terracut key`, or the environment variable TERRACUT_MMT_KEY).
//  - Handshake (two messages): the operator sends HELLO (its station id and
//    an X25519 ephemeral public key, crypto_kx), the remote answers WELCOME
//    (its own ephemeral key), each with a BLAKE2b tag (crypto_generichash)
//    keyed by a key derived from the pre-shared one (crypto_kdf), the
//    WELCOME's over both messages. The session keys, one per direction, are
//    crypto_kx's shared keys hashed with the handshake key and both tags:
//    only a holder of the pre-shared key who made the ephemeral key can
//    compute them, and a recorded session stays secret if the pre-shared key
//    leaks later.
//  - Every datagram after it is sealed with ChaCha20-Poly1305 (IETF,
//    crypto_aead_chacha20poly1305_ietf): a 12-byte header (kind, channel, a
//    64-bit counter per channel) that is both the nonce and the additional
//    data, then the ciphertext and its 16-byte tag. A replay window per
//    channel (kReplayWindow counters) refuses a counter seen before or too old.
//
// --insecure-loopback runs the same protocol with a key of zeros that
// everyone knows (InsecureKey): the mechanics, no secrecy; the HELLO says so
// and a station with a real key refuses it by name.
//
// Wire formats (all integers little-endian):
//   HELLO   (76 B): "TCAH" | u16 version | u8 kind = 1 | u8 flags (1: insecure)
//                   | u32 operator id | 32 B ephemeral key | 32 B tag over [0, 44)
//   WELCOME (80 B): "TCAH" | u16 version | u8 kind = 2 | u8 flags
//                   | u32 operator id (the HELLO's) | u32 remote id
//                   | 32 B ephemeral key | 32 B tag over HELLO + [0, 48)
//   sealed  (28 B + N): u8 kind = 3 | u8 channel | u16 0 | u64 counter
//                   | N B ciphertext | 16 B tag
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace terracut::net {

inline constexpr std::size_t kKeySize = 32;
inline constexpr std::size_t kHelloSize = 76;
inline constexpr std::size_t kWelcomeSize = 80;
inline constexpr std::size_t kSealHeaderSize = 12;
inline constexpr std::size_t kSealTagSize = 16;
inline constexpr std::size_t kSealOverhead = kSealHeaderSize + kSealTagSize;
/// Sealed channels: 0 unreliable, 1 reliable (the stations' messages), 2
/// control (the end of a session).
inline constexpr std::size_t kSealedChannels = 3;
/// Counters behind the newest one a channel still accepts (once each).
inline constexpr std::uint64_t kReplayWindow = 1024;
/// The environment variable a key may come from (64 hex digits).
inline constexpr const char* kKeyEnvironmentVariable = "TERRACUT_MMT_KEY";

/// The pre-shared key of a pair of stations. insecure: the key of zeros of
/// --insecure-loopback (no secret at all).
struct LinkKey {
  std::array<std::uint8_t, kKeySize> bytes{};
  bool insecure = false;
};
/// The key of --insecure-loopback.
LinkKey insecure_key();

/// Reads a key file: 64 hex digits and an optional newline (65 bytes at
/// most), a regular file that only its owner may read or write (no group or
/// other permission bits). Throws InputError naming the file and what is
/// wrong (missing, not a regular file, its permissions, its size, not hex).
LinkKey read_key_file(const std::filesystem::path& path);
/// A key given as text (64 hex digits; surrounding white space ignored).
/// Throws InputError naming `source` (e.g. the environment variable).
LinkKey parse_key(std::string_view text, const std::string& source);
/// Writes a new random key to path, created with mode 0600 (an existing
/// file is refused, never overwritten). Throws InputError naming the file.
LinkKey write_new_key_file(const std::filesystem::path& path);
/// A short public name of a key (16 hex digits of a hash of it), to check
/// that two machines hold the same key without showing it.
std::string fingerprint(const LinkKey& key);

/// Why a handshake message or a sealed datagram was refused.
enum class AuthReject : std::uint8_t {
  kNone = 0,
  kTruncated,   ///< shorter than its format, or longer
  kBadFormat,   ///< not a message of this protocol (magic, version, kind)
  kBadMac,      ///< the tag does not verify: another key, or forged bytes
  kReplayed,    ///< a counter seen before, or older than the replay window
  kInsecure,    ///< one side runs --insecure-loopback and the other has a key
};
inline constexpr std::size_t kAuthRejectCount = 6;
/// "none", "truncated", "bad_format", "bad_mac", "replayed", "insecure_mismatch".
std::string_view to_string(AuthReject reason);

/// The two keys of an authenticated session, one per direction.
struct SessionKeys {
  std::array<std::uint8_t, kKeySize> send{};
  std::array<std::uint8_t, kKeySize> receive{};
};

/// The operator's side of the handshake: makes the HELLO (a fresh ephemeral
/// key) and checks the remote's WELCOME.
class HandshakeInitiator {
 public:
  HandshakeInitiator(const LinkKey& key, std::uint32_t operator_id);
  ~HandshakeInitiator();
  HandshakeInitiator(const HandshakeInitiator&) = delete;
  HandshakeInitiator& operator=(const HandshakeInitiator&) = delete;
  const std::array<std::uint8_t, kHelloSize>& hello() const { return hello_; }
  /// Checks a WELCOME against this HELLO; on kNone fills keys and the
  /// remote's id. kInsecure when the WELCOME's mode is not this one's.
  AuthReject accept(const std::uint8_t* welcome, std::size_t size, SessionKeys& keys,
                    std::uint32_t& remote_id) const;

 private:
  std::array<std::uint8_t, kKeySize> handshake_key_{};
  std::array<std::uint8_t, 32> secret_{};
  std::array<std::uint8_t, kHelloSize> hello_{};
  bool insecure_ = false;
};

/// The remote's side: checks a HELLO and, when it verifies, makes the
/// WELCOME (a fresh ephemeral key) and the session's keys. operator_id is
/// set when the HELLO verified. Never throws, whatever the bytes.
AuthReject answer_hello(const LinkKey& key, std::uint32_t remote_id, const std::uint8_t* hello,
                        std::size_t size, std::uint32_t& operator_id,
                        std::array<std::uint8_t, kWelcomeSize>& welcome, SessionKeys& keys);

/// True when the bytes start like a handshake message ("TCAH").
bool is_handshake(const std::uint8_t* data, std::size_t size);

/// Refuses counters seen before or more than kReplayWindow behind the newest.
class ReplayWindow {
 public:
  /// Whether the counter would be accepted (does not record it).
  bool fresh(std::uint64_t counter) const noexcept;
  /// Records an accepted counter (after its tag verified).
  void accept(std::uint64_t counter) noexcept;

 private:
  std::uint64_t newest_ = 0;
  bool any_ = false;
  std::array<std::uint64_t, kReplayWindow / 64> bits_{};  // bit (c % window) set: c was seen
};

/// Seals and opens the datagrams of one session. Allocates nothing: the
/// caller's buffers hold the results.
class SecureChannel {
 public:
  explicit SecureChannel(const SessionKeys& keys);
  ~SecureChannel();
  SecureChannel(const SecureChannel&) = delete;
  SecureChannel& operator=(const SecureChannel&) = delete;
  /// Writes the sealed datagram of data[0, size) on channel (< kSealedChannels)
  /// to out, which must hold size + kSealOverhead bytes; returns its size.
  std::size_t seal(std::uint8_t channel, const std::uint8_t* data, std::size_t size,
                   std::uint8_t* out) noexcept;
  /// Opens a sealed datagram: the plaintext to out (size - kSealOverhead
  /// bytes; out must hold them) and its channel. kTruncated, kBadFormat (not
  /// sealed, an unknown channel), kBadMac, kReplayed.
  AuthReject open(const std::uint8_t* data, std::size_t size, std::uint8_t* out,
                  std::size_t& out_size, std::uint8_t& channel) noexcept;

 private:
  SessionKeys keys_;
  std::array<std::uint64_t, kSealedChannels> next_{};
  std::array<ReplayWindow, kSealedChannels> windows_{};
};

}  // namespace terracut::net
