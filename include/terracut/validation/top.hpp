// A blade's top (BladeSpec::height_m, docs/soil.md "Soil over the blade's
// top"): a blade of finite height holds soil up to its top, and what stands
// higher against it falls over it to the other side. The measure pushes a
// 1 m blade of a given height, cutting 5 cm of a 0.2 m layer of dry sand
// (repose 34 degrees), 1.5 m along its normal on a square grid, and watches
// at the end of every step every cell against the blade (its centre within
// three halves of a cell's width across the edge's line, within its
// length): none may stand above the top there while the other side has
// room for what would fall over (down the edge's normal from the first
// cell clear of the blade, a cell below the repose line falling from the
// top before the first cell above it: a cell above the top at once is a
// buried blade). Used by the tests and by `terracut validate` (check 3.6).
#pragma once

#include <string>
#include <vector>

namespace terracut::validation {

struct TopCase {
  double height_m = 0.1;       ///< the blade's top above its edge, m (the layer's surface is 5 cm above the edge)
  double yaw_deg = 0.0;        ///< about +Y (0: along X, pushing along +Z)
  double roll_deg = 0.0;       ///< about the push (0: level), in [-5, 5]
  double speed_m_per_s = 1.0;  ///< along the push, at 1 kHz
  double cell_m = 0.01;        ///< square cells, in [5 mm, 2 cm]
};

struct TopMeasure {
  /// The worst height above the top, m, at the end of any step, of a cell
  /// against the blade whose other side had room for it; 0 when none.
  double worst_unburied_m = 0.0;
  /// The highest any cell against the blade stood above the top at the end
  /// of a step, buried or not, m (negative: the pile never reached the top).
  double reach_m = 0.0;
  double over_top_m3 = 0.0;  ///< what the steps report fell over the top (SoilStepResult::over_top_m3), m^3
  double behind_m3 = 0.0;    ///< soil above the edge's height in the trench behind the last edge, within its span, m^3
  double volume_error_m3 = 0.0;  ///< final less initial volume, m^3
  double volume_slack_m3 = 0.0;  ///< one float rounding a sample of the highest height, m^3
  /// The measure holds: no cell above the top with room on the other side
  /// (to kTopSlack_m), the pile reached the top (to a millimetre) and soil
  /// went over it, the trench behind holds at least what the steps report
  /// over the top (less 0.1 %; it also holds what slid in from its walls and
  /// round the ends), and the volume is kept.
  bool holds() const;
};

/// Float slack of the measure, m.
inline constexpr double kTopSlack_m = 1e-6;

/// The case in words, for messages.
std::string describe(const TopCase& c);

/// Runs the case. Throws std::invalid_argument naming the case where it
/// cannot be set up (a height not finite and positive or over 1 m, a yaw
/// not finite, a roll not finite or beyond 5 degrees, a speed outside
/// [0.05, 2] m/s, cells outside [5 mm, 2 cm]).
TopMeasure measure_top(const TopCase& c);

/// The cases `terracut validate` runs: square to the grid, turned 30, 45
/// and 90 degrees, rolled 3 degrees, at 0.25 to 2 m/s, on 1 cm and 5 mm
/// cells, blades 0.08 and 0.1 m tall.
std::vector<TopCase> validation_top_cases();

}  // namespace terracut::validation
