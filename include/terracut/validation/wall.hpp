// The blade is a wall for flowing soil (soil.hpp): no soil reaches the far
// side of a blade through it or under it, whatever the blade's length, yaw
// and speed, while it plunges, pushes, turns or lifts. Soil may reach the
// cut behind a blade only round its ends or down the trench's own walls, so
// the measure takes both away: a blade longer than the terrain is wide (no
// ends on the grid), or a blade running in a channel closed by rigid
// obstacles beyond its ends whose cells stand below the trench floor (no
// walls, nothing to spill round). Then any soil that comes to stand above
// the trench floor behind the blade came through or under it. The floor
// behind is left by the cut at the edge's height, and where the edge moves
// up or down it is a ramp gentler than the repose angle, so nothing on it
// moves: the measure is how far any sample the blade has passed ever rose
// above the edge's height there. Used by the tests and by
// `terracut validate` (check 3.3).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace terracut::validation {

/// What the blade does over its 0.3 m of travel.
enum class WallMotion {
  kPush,    ///< level, the edge 5 cm into the 20 cm layer
  kPlunge,  ///< the edge from 1 cm to 5 cm deep over the first two thirds of the travel (a ramp in space)
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
  double cell_m = 0.01;
  /// The tremor's amplitude along the travel, m (0: none). Above
  /// speed / (2 pi kWallTremor_hz) the blade backs up in every cycle: 4 mm
  /// takes a blade at under 0.23 m/s back and forth.
  double tremor_m = 0.0;
  /// The wobble's amplitude about the vertical, degrees (0: none). The
  /// blade then turns about its centre every cycle, its two halves going
  /// opposite ways across its line. Level motions only (push, turn): a ramp
  /// the blade wobbles over is passed by each part at another height each
  /// time, and a part wobbling back over a floor cut higher cuts it with its
  /// back, as a real blade does.
  double wobble_deg = 0.0;
};

/// The motion's name: push, plunge, lift, turn.
const char* motion_name(WallMotion m);

/// The blade's length as simulated, m: length_m in a channel, 2 m spanning
/// the terrain.
double blade_length_m(const WallCase& w);

/// The case in words, for messages (the blade's length as simulated).
std::string describe(const WallCase& w);

/// The worst height above the edge's height, m, that a sample the blade had
/// passed reached at any step (the far side of the blade, more than a cell
/// and a half from its line). A float step of heights near 0.2 m (1e-8 m)
/// is what an intact wall leaves. The samples watched are those now on the
/// side the blade came from. Throws std::invalid_argument naming the case
/// where it cannot be set up (a length, speed or cell not finite and
/// positive, cells outside [2 mm, 5 cm], a speed under 1 mm/s, a tremor
/// negative, not finite or over 2 cm, a wobble negative, not finite, over
/// 5 degrees or on a plunge or a lift, a channel the blade does not reach
/// across at its largest yaw, nothing to watch).
double worst_rise_behind(const WallCase& w);

/// Float slack of the measure: far below any soil that crossed the blade.
inline constexpr double kWallSlack_m = 1e-5;

/// The cases `terracut validate` runs: blades of 0.2 to 2 m, yaws of -30 to
/// 173 degrees, speeds of 0.05 to 2 m/s (a slow one moves under a hundredth
/// of a cell a step), every motion, spanning the terrain and in a channel,
/// every motion again with a hand's tremor that backs the blade up, and
/// pushes and turns with a wobble about the vertical.
std::vector<WallCase> validation_wall_cases();

}  // namespace terracut::validation
