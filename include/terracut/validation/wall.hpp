// The blade is a wall for flowing soil (soil.hpp): no soil reaches the far
// side of a blade through it or under it, whatever the blade's length, yaw,
// roll and speed, while it plunges, pushes, turns or lifts, steadily or
// with a hand's tremor and wobble. Soil may reach the cut behind a blade
// only round its ends or down the trench's own walls, so the measure takes
// both away: a blade longer than the terrain is wide (no ends on the grid),
// or a blade running in a channel closed by rigid obstacles beyond its ends
// whose cells stand below the trench floor (no walls, nothing to spill
// round). The edge lies in one plane at every step (the cutting plane: a
// ramp along the travel for a plunge or a lift, sloping across it by the
// roll, gentler than the repose angle everywhere), so the cut leaves every
// sample it passes at the plane's height and nothing on the floor moves;
// and no part of the edge ever comes back below the floor it cut (one that
// did would cut that floor with its back and push it behind the blade, as
// a real blade does). Then any soil that comes to stand above the plane
// behind the blade came through or under it: the measure is how far any
// sample behind the blade ever rose above the plane. The cut reads the
// heights as a surface (the default representation) unless the case asks
// for columns (docs/soil.md, "Not done yet", has where those are not yet a
// wall). Used by the tests and by `terracut validate` (check 3.3).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace terracut::validation {

/// What the blade does over its 0.3 m of travel.
enum class WallMotion {
  kPush,    ///< level, the edge 5 cm into the 20 cm layer
  kPlunge,  ///< the edge from 1 cm to 5 cm deep over the travel (a ramp fixed in space, slope 0.133)
  kLift,    ///< the edge from 5 cm to 1 cm deep so
  kTurn,    ///< level, the yaw swinging from -8 to +8 degrees about its centre
};

/// A hand's tremor (physiological tremor lies at 8 to 12 Hz): the blade
/// oscillates along its travel at this frequency on top of its motion.
inline constexpr double kWallTremor_hz = 9.0;
/// A hand's wobble about the vertical: the yaw oscillates about the blade's
/// centre at this frequency (off the tremor's, so the two drift in phase).
inline constexpr double kWallWobble_hz = 10.2;

struct WallCase {
  double length_m = 1.0;  ///< the blade in a channel (spanning the terrain it is 2 m, twice the terrain's side)
  double yaw_deg = 0.0;   ///< about +Y (0: along X, travelling along +Z)
  double speed_m_per_s = 1.0;  ///< along its travel, at 1 kHz
  WallMotion motion = WallMotion::kPush;
  bool channel = false;  ///< between two rigid obstacles beyond its ends (travel along +Z)
  std::int64_t cap = 50000;  ///< the soil's work cap, neighbour visits a step
  double cell_m = 0.01;  ///< along X
  double cell_aspect = 1.0;  ///< the cells' side along Z over cell_m, in [0.25, 4]
  /// The tremor's amplitude along the travel, m (0: none). Above
  /// speed / (2 pi kWallTremor_hz) the blade backs up in every cycle: 4 mm
  /// takes a blade at under 0.23 m/s back and forth.
  double tremor_m = 0.0;
  /// The wobble's amplitude about the vertical, degrees (0: none). The
  /// blade then turns about its centre every cycle, its two halves going
  /// opposite ways across its line (rolled so that its edge stays in the
  /// cutting plane at every yaw).
  double wobble_deg = 0.0;
  /// The roll, degrees (0: level): the cutting plane slopes across the
  /// travel by this angle, so a blade square to its travel has its +X end
  /// higher by it; at other yaws the edge rolls as the plane asks.
  double roll_deg = 0.0;
  /// Where the terrain lies: its corner at (origin_m, 0, origin_m), m (a
  /// georeferenced terrain stands hundreds of kilometres from its origin).
  double origin_m = 0.0;
  /// The cut read as columns instead of a surface (core/cut.hpp). The
  /// columns representation is a wall for a level blade, not yet in every
  /// case (docs/soil.md, "Not done yet"): the tests run the cases it holds.
  bool columns = false;
};

/// The motion's name: push, plunge, lift, turn.
const char* motion_name(WallMotion m);

/// The blade's length as simulated, m: length_m in a channel, 2 m spanning
/// the terrain.
double blade_length_m(const WallCase& w);

/// The case in words, for messages (the blade's length as simulated).
std::string describe(const WallCase& w);

/// The worst height above the cutting plane, m, that a sample behind the
/// blade reached at any step (within its span, on the side it came from,
/// more than a cell and a half from its line). A float step of heights near
/// 0.2 m (1e-8 m) is what an intact wall leaves. Throws
/// std::invalid_argument naming the case where it cannot be set up (a
/// length, speed or cell not finite and positive, cells outside [2 mm,
/// 5 cm], a speed under 1 mm/s, a tremor negative, not finite or over 2 cm,
/// a wobble negative, not finite or over 5 degrees, a roll not finite or
/// over 5 degrees either way, a cell aspect outside [0.25, 4], an origin
/// not finite or beyond 1e7 m, a plane that comes within 3 cm of the
/// terrain's bottom, a channel the blade does not reach across at its
/// largest yaw, nothing to watch).
double worst_rise_behind(const WallCase& w);

/// Float slack of the measure: far below any soil that crossed the blade.
inline constexpr double kWallSlack_m = 1e-5;

/// The cases `terracut validate` runs: blades of 0.2 to 2 m, yaws of -30 to
/// 200 degrees, speeds of 0.05 to 2 m/s (a slow one moves under a hundredth
/// of a cell a step), every motion, spanning the terrain and in a channel,
/// every motion again with a hand's tremor that backs the blade up, pushes
/// and turns with a wobble about the vertical, every motion with the
/// blade rolled 2.5 to 4 degrees (with a tremor or a wobble in three), and
/// two blades turning along a lattice direction (their line through a row
/// of cell centres once), one with the terrain 1e7 m from the origin.
std::vector<WallCase> validation_wall_cases();

}  // namespace terracut::validation
