#include "terracut/core/blade.hpp"

#include <algorithm>
#include <cmath>

#include "terracut/core/format.hpp"

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
  const std::string name = "motion '" + motion.name + "'";
  if (motion.keyframes.empty()) return name + " has no keyframes";
  for (size_t i = 0; i < motion.keyframes.size(); ++i) {
    const Keyframe& k = motion.keyframes[i];
    const std::string at = name + " keyframe " + format_number(i) + ": ";
    if (!std::isfinite(k.t_s) || k.t_s < 0.0) return must_be(at + "t_s", "finite and >= 0", k.t_s);
    if (i > 0 && !(k.t_s > motion.keyframes[i - 1].t_s))
      return must_be(at + "t_s",
                     "greater than the previous keyframe's " +
                         format_number(motion.keyframes[i - 1].t_s),
                     k.t_s);
    if (!is_finite(k.pose.position_m)) return at + "position is not finite";
    if (!is_finite(k.pose.orientation) ||
        !(std::abs(k.pose.orientation.w) + std::abs(k.pose.orientation.x) +
              std::abs(k.pose.orientation.y) + std::abs(k.pose.orientation.z) >
          0.0))
      return at + "rotation is not a valid rotation";
  }
  return {};
}

}  // namespace terracut
