// The device side of the UDP bridge, played by a program instead of a real
// device: the handle follows a cut's path (`script`) or is a simulated hand
// that feels the forces coming back (`sim`). terracut-device runs it; so can
// a test, tick by tick, in a thread.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "terracut/haptics/settings.hpp"
#include "terracut/haptics/sim_hand.hpp"
#include "terracut/haptics/udp_device.hpp"

namespace terracut::haptics {

/// What the player's handle does.
enum class PlayerMode {
  kScript,  ///< exactly on the path; received forces are only counted
  kSim,     ///< the simulated hand; received forces act on it
};

/// Counters and figures of a played session.
struct PlayerStats {
  std::int64_t ticks = 0;            ///< ticks played
  std::int64_t poses_sent = 0;       ///< pose packets handed to the socket
  std::int64_t forces_accepted = 0;  ///< force packets accepted (newest per tick counted once)
  BridgeStats bridge{};              ///< socket-level counters, rejections by reason
  double max_force_n = 0.0;          ///< largest |force| received, device N
  /// Round trip from sending a pose to receiving a force that answers it
  /// (pose_sequence echo), microseconds; 0 when none was measured.
  double rtt_p50_us = 0.0;
  double rtt_p99_us = 0.0;
  double rtt_max_us = 0.0;
  std::int64_t rtt_samples = 0;
};

class DevicePlayer {
 public:
  /// Opens the socket toward address:port (BridgeClient). mode kSim needs
  /// hand (validated SimHandParams) and inherent_damping_n_s_per_m; rate_hz:
  /// the player's tick rate (sub-steps of the hand). Throws InputError on a
  /// bad address.
  DevicePlayer(const std::string& address, int port, std::uint32_t session, PlayerMode mode,
               DevicePath path, const SimHandParams& hand, double inherent_damping_n_s_per_m,
               double rate_hz);

  /// One tick at path time t_s (seconds from the start) and local monotonic
  /// time now_ns (the packet's timestamp): take the newest force, move the
  /// handle, send its pose. Never blocks; allocates nothing.
  void tick(double t_s, std::uint64_t now_ns) noexcept;

  /// Sends raw bytes to the loop (tests: malformed packets).
  void send_raw(const std::uint8_t* data, std::size_t size) noexcept {
    client_.send_raw(data, size);
  }

  /// The figures so far (round-trip percentiles computed here, not per tick).
  PlayerStats stats() const;
  /// The handle's position now, device frame, metres.
  Vec3 position_m() const { return position_m_; }
  /// The newest force received, device N.
  Vec3 force_n() const { return force_n_; }
  /// The simulated hand (kSim).
  const std::optional<SimHand>& hand() const { return hand_; }

 private:
  static constexpr std::size_t kSentRing = 4096;  // send times by sequence, for round trips

  BridgeClient client_;
  PlayerMode mode_;
  DevicePath path_;
  std::optional<SimHand> hand_;
  Vec3 position_m_{};
  Vec3 force_n_{};
  std::int64_t ticks_ = 0;
  std::int64_t poses_sent_ = 0;
  std::int64_t forces_accepted_ = 0;
  double max_force_n_ = 0.0;
  std::array<std::uint64_t, kSentRing> sent_ns_{};
  std::array<std::uint32_t, kSentRing> sent_seq_{};
  std::vector<float> rtt_us_;  // reserved at construction; full -> no more samples
};

}  // namespace terracut::haptics
