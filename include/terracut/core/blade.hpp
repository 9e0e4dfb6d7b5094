// The blade: a straight cutting edge (a "cutting line", like a hot-wire
// cutter) of a given length centred on its pose, lying along the blade frame's
// local X axis. Its motion is a list of keyframes; position is interpolated
// linearly and rotation by quaternion slerp.
#pragma once

#include <limits>
#include <string>
#include <vector>

#include "terracut/core/math.hpp"

namespace terracut {

/// A bucket behind the cutting edge (its lip), in the blade frame: the edge
/// along local X is the lip; the bucket opens toward local -Z (the way it
/// digs); its flat floor runs from the lip back to local z = depth_m and its
/// back wall up to local y = height_m. Its section (local y-z) is the right
/// triangle lip (0, 0), heel (z = depth_m, y = 0), back top (z = depth_m,
/// y = height_m), over the edge's length: the struck capacity (below the
/// plane from the lip to the back's top edge, the SAE J296 definition) is
/// length x depth x height / 2. Zero depth = no bucket (a flat blade).
struct BucketSpec {
  double depth_m = 0.0;   ///< floor length from the lip to the back, metres, >= 0 (0 = no bucket)
  double height_m = 0.0;  ///< back wall height above the floor, metres, > 0 with a bucket

  bool enabled() const { return depth_m > 0.0; }
};

/// Blade parameters; read-only during a run.
struct BladeSpec {
  double length_m = 1.0;  ///< length of the cutting edge, metres, > 0
  /// Rake angle of the blade's face from the horizontal, degrees, in
  /// (0, 180): 90 is a vertical plate; below 90 the edge leads and the face
  /// leans back over the soil it lifts. The cutting force's alpha
  /// (earthmoving.hpp); the cut itself is the edge's sweep whatever the rake.
  double rake_angle_deg = 90.0;
  /// Thickness of the cutting edge, metres, > 0: the width of the strip the
  /// soil bears under it when it is pushed down (penetration.hpp). A 2 cm
  /// steel cutting edge by default.
  double edge_thickness_m = 0.02;
  /// Height of the blade's top above its edge, metres, > 0, along the
  /// blade frame's local Y (the face's vertical extent, whatever its rake):
  /// with soil model flow, soil standing against the blade higher than its
  /// top falls over it to the other side (docs/soil.md, "Soil over the
  /// blade's top"). Infinity (the default): a wall as tall as any pile. A
  /// bucket has its own (bucket.height_m) and takes none.
  double height_m = std::numeric_limits<double>::infinity();
  BucketSpec bucket{};    ///< a bucket behind the edge (soil model flow only)
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
