#include "terracut/core/blade.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace terracut {

Segment blade_segment(const BladeSpec& blade, const BladePose& pose) {
  Vec3 half = rotate(pose.orientation, Vec3{blade.length_m / 2.0, 0.0, 0.0});
  return {pose.position_m - half, pose.position_m + half};
}

BladePose Motion::sample(double t_s) const {
  if (keyframes.empty()) return {};
  if (!(t_s > keyframes.front().t_s)) return keyframes.front().pose;
  if (!(t_s < keyframes.back().t_s)) return keyframes.back().pose;
  // First keyframe with time > t_s; the pose lies between it and the one before.
  auto next = std::upper_bound(keyframes.begin(), keyframes.end(), t_s,
                               [](double t, const Keyframe& k) { return t < k.t_s; });
  const Keyframe& k1 = *next;
  const Keyframe& k0 = *(next - 1);
  double f = (t_s - k0.t_s) / (k1.t_s - k0.t_s);
  return {lerp(k0.pose.position_m, k1.pose.position_m, f),
          slerp(k0.pose.orientation, k1.pose.orientation, f)};
}

std::string validate(const Motion& motion) {
  std::ostringstream msg;
  if (motion.keyframes.empty()) {
    msg << "motion '" << motion.name << "' has no keyframes";
    return msg.str();
  }
  for (size_t i = 0; i < motion.keyframes.size(); ++i) {
    const Keyframe& k = motion.keyframes[i];
    if (!std::isfinite(k.t_s) || k.t_s < 0.0) {
      msg << "motion '" << motion.name << "' keyframe " << i << ": t_s must be finite and >= 0";
    } else if (i > 0 && !(k.t_s > motion.keyframes[i - 1].t_s)) {
      msg << "motion '" << motion.name << "' keyframe " << i << ": t_s (" << k.t_s
          << ") must be greater than the previous keyframe's (" << motion.keyframes[i - 1].t_s << ")";
    } else if (!is_finite(k.pose.position_m)) {
      msg << "motion '" << motion.name << "' keyframe " << i << ": position is not finite";
    } else if (!is_finite(k.pose.orientation) ||
               !(std::abs(k.pose.orientation.w) + std::abs(k.pose.orientation.x) +
                     std::abs(k.pose.orientation.y) + std::abs(k.pose.orientation.z) > 0.0)) {
      msg << "motion '" << motion.name << "' keyframe " << i << ": rotation is not a valid rotation";
    }
    if (!msg.str().empty()) return msg.str();
  }
  return {};
}

}  // namespace terracut
