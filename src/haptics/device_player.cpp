#include "terracut/haptics/device_player.hpp"

#include <algorithm>
#include <cmath>

namespace terracut::haptics {

DevicePlayer::DevicePlayer(const std::string& address, int port, std::uint32_t session,
                           PlayerMode mode, DevicePath path, const SimHandParams& hand,
                           double inherent_damping_n_s_per_m, double rate_hz)
    : client_(address, port, session), mode_(mode), path_(std::move(path)) {
  if (mode_ == PlayerMode::kSim) hand_.emplace(hand, inherent_damping_n_s_per_m, path_, rate_hz);
  position_m_ = path_.position_m(0.0) + (mode_ == PlayerMode::kSim ? hand.start_offset_m : Vec3{});
  // Up to 10 minutes of round trips at 1 kHz (40 MB at most, kept for percentiles).
  rtt_us_.reserve(600000);
  sent_seq_.fill(0xFFFFFFFFu);
}

void DevicePlayer::tick(double t_s, std::uint64_t now_ns) noexcept {
  // The newest force, and the round trip of the pose it answers.
  ForcePayload f;
  PacketHeader h;
  if (client_.poll_force(f, h)) {
    ++forces_accepted_;
    if (is_finite(f.force_n)) {
      force_n_ = f.force_n;
      max_force_n_ = std::max(max_force_n_, length(f.force_n));
    } else {
      force_n_ = {};
    }
    const std::size_t slot = f.pose_sequence % kSentRing;
    if (sent_seq_[slot] == f.pose_sequence && rtt_us_.size() < rtt_us_.capacity() &&
        now_ns >= sent_ns_[slot])
      rtt_us_.push_back(float(double(now_ns - sent_ns_[slot]) * 1e-3));
  }

  // Move the handle.
  PosePayload pose;
  if (mode_ == PlayerMode::kSim) {
    hand_->advance_to(t_s, force_n_);
    position_m_ = hand_->position_m();
  } else {
    position_m_ = path_.position_m(t_s);
  }
  pose.position_m = position_m_;
  pose.orientation = path_.orientation(t_s);
  pose.flags = kPoseHasOrientation;

  const std::uint32_t seq = client_.send_pose(pose, now_ns);
  sent_seq_[seq % kSentRing] = seq;
  sent_ns_[seq % kSentRing] = now_ns;
  ++poses_sent_;
  ++ticks_;
}

PlayerStats DevicePlayer::stats() const {
  PlayerStats s;
  s.ticks = ticks_;
  s.poses_sent = poses_sent_;
  s.forces_accepted = forces_accepted_;
  s.bridge = client_.stats();
  s.max_force_n = max_force_n_;
  if (!rtt_us_.empty()) {
    std::vector<float> v = rtt_us_;
    std::sort(v.begin(), v.end());
    const auto at = [&](double q) {
      return double(v[std::min(v.size() - 1, std::size_t(std::ceil(q * double(v.size()))) - 1)]);
    };
    s.rtt_p50_us = at(0.5);
    s.rtt_p99_us = at(0.99);
    s.rtt_max_us = double(v.back());
    s.rtt_samples = std::int64_t(v.size());
  }
  return s;
}

}  // namespace terracut::haptics
