// The blade: a straight cutting edge (a "cutting line", like a hot-wire
// cutter) of a given length centred on its pose, lying along the blade frame's
// local X axis. Its motion is a list of keyframes; position is interpolated
// linearly and rotation by quaternion slerp.
#pragma once

#include <string>
#include <vector>

#include "terracut/core/math.hpp"

namespace terracut {

/// Blade parameters; read-only during a run.
struct BladeSpec {
  double length_m = 1.0;  ///< length of the cutting edge, metres, > 0
};

/// Pose of the blade frame in the world: the edge runs from
/// position - R*(L/2,0,0) to position + R*(L/2,0,0).
struct BladePose {
  Vec3 position_m{};  ///< centre of the edge, world metres
  Quat orientation{};  ///< unit quaternion, blade frame -> world
};

/// A straight segment in the world, metres.
struct Segment {
  Vec3 a{};
  Vec3 b{};
};

/// The cutting edge of a blade of the given spec at the given pose.
Segment blade_segment(const BladeSpec& blade, const BladePose& pose);

/// One keyframe of a blade motion.
struct Keyframe {
  double t_s = 0.0;  ///< time from the start of the motion, seconds, >= 0
  BladePose pose{};
};

/// A motion: keyframes in strictly increasing time, at least one.
struct Motion {
  std::string name;
  std::vector<Keyframe> keyframes;

  /// Time of the last keyframe, seconds.
  double duration_s() const { return keyframes.empty() ? 0.0 : keyframes.back().t_s; }
  /// The pose at time t_s, clamped to the first and last keyframe.
  BladePose sample(double t_s) const;
};

/// Returns an empty string when the motion is valid, else a message naming the
/// bad keyframe (times not increasing, non-finite values, zero quaternion).
std::string validate(const Motion& motion);

}  // namespace terracut
