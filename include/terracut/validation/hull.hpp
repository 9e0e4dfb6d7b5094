// The bucket is a solid (docs/soil.md, "The bucket"): after every step of a
// stroke, no cell whose centre lies in the plan of the bucket's floor plate
// or back plate holds soil above that plate's underside there (the lower
// plate's, where both cover it), and the grid's volume plus the bucket's
// load stays what it was. The plates are worked out here from the pose and
// the bucket's shape, apart from the soil model's own marking, so the
// measure also catches a marking that misses cells. A stroke digs, is
// lowered, goes heel first, sideways along its lip or digs while turning,
// on a layer of sand, at any yaw, heel up or curled, rolled, with a hand's
// tremor and wobble, on square or oblong cells, near the origin or far from
// it, in either representation. Used by the tests and by `terracut
// validate` (check 5g).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace terracut::validation {

/// What the bucket does over its stroke (0.5 m of travel, or the time it
/// would take where it does not travel).
enum class BucketMotion {
  kDig,        ///< toward its opening (its frame's -Z): the lip plunges from 1 cm above the sand to dig_m over the first 30 %, drags, and lifts 5 cm clear over the last 15 %
  kLower,      ///< straight down from 3 cm above the sand to dig_m below it over the first two thirds, then held
  kHeelFirst,  ///< toward its heel (+Z), the lip going from the surface to dig_m over the first quarter
  kSideways,   ///< along its lip (+X), the lip going from the surface to dig_m over the first quarter
  kTurn,       ///< kDig while the yaw turns from -15 to +15 degrees about the lip's centre
};

/// The sand: a layer this deep over the terrain's bottom.
inline constexpr double kBucketLayer_m = 0.2;
/// A hand's tremor along the travel and wobble about the vertical, Hz
/// (as the blade's, wall.hpp).
inline constexpr double kBucketTremor_hz = 9.0;
inline constexpr double kBucketWobble_hz = 10.2;

struct BucketStroke {
  double length_m = 0.4;  ///< the lip, (0, 1]
  double depth_m = 0.3;   ///< the floor from the lip to the heel, (0, 0.5]
  double height_m = 0.15;  ///< the back wall, (0, 0.5]
  BucketMotion motion = BucketMotion::kDig;
  double yaw_deg = 0.0;    ///< about +Y (0: the lip along X, the opening toward -Z)
  /// About the lip (the blade frame's X), degrees, [-40, 40]: negative
  /// raises the heel (a bucket going in), positive curls it.
  double pitch_deg = -7.0;
  double roll_deg = 0.0;   ///< about the bucket's Z, degrees, [-10, 10]
  double speed_m_per_s = 0.5;  ///< along the travel, at 1 kHz, [0.01, 2]
  double dig_m = 0.035;    ///< the lip's deepest below the surface, (0, 0.1]
  double tremor_m = 0.0;   ///< along the travel, m, [0, 0.01]
  double wobble_deg = 0.0;  ///< about the vertical, degrees, [0, 5]
  double cell_m = 0.01;    ///< along X, [0.004, 0.04]
  double cell_aspect = 1.0;  ///< the cells' side along Z over cell_m, [0.25, 4]
  double origin_m = 0.0;   ///< the terrain's corner at (origin_m, 0, origin_m), |origin_m| <= 1e7
  bool columns = false;    ///< the cut read as columns instead of a surface
  std::int64_t cap = 50000;  ///< the soil's work cap, neighbour visits a step
};

/// What a stroke gave, over all of its steps.
struct HullMeasure {
  double worst_above_m = 0.0;      ///< the most soil above a plate's underside over a covered centre, m (negative: none reached it)
  double worst_volume_error_m3 = 0.0;  ///< the most |grid + load - initial|, m^3
  double volume_slack_m3 = 0.0;    ///< what float rounding of every height may account for, m^3
  double load_m3 = 0.0;            ///< in the bucket at the end
  double shouldered_m3 = 0.0;      ///< what the hull pushed out of its footprint, all steps
  int steps = 0;
  bool holds() const;
};

/// Float slack of the measure: a float step of heights near 0.5 m, and the
/// 4 float epsilons the shoulder leaves, far below any soil inside the hull.
inline constexpr double kHullSlack_m = 1e-5;

const char* motion_name(BucketMotion m);

/// The stroke in words, for messages.
std::string describe(const BucketStroke& s);

/// Runs the stroke and measures it. Throws std::invalid_argument naming
/// the field where it cannot be set up (a number outside the range its
/// comment gives, or not finite, or a hull that would reach within 2 cm of
/// the terrain's bottom).
HullMeasure measure_hull(const BucketStroke& s);

/// The strokes `terracut validate` runs: every motion, lattice yaws and
/// others, heel up and curled, rolled, with tremor and wobble, square and
/// oblong cells of 5 mm to 2 cm, the terrain at the origin and 1000 km
/// out, both representations, and two strokes that put soil inside the
/// hull before 2026-12-07 (soil flowing into a covered cell from several
/// sides in one pass).
std::vector<BucketStroke> validation_bucket_strokes();

}  // namespace terracut::validation
