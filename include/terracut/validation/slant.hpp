// A push at a slant (docs/soil.md, "Not done yet"; docs/validation.md, check
// 3.4): a blade turned about the vertical, cutting into a layer of dry sand
// (repose 34 degrees) and pushed along its normal across the middle of a
// square grid, then held still; the soil it leaves ahead of it. A model with
// no preferred direction leaves the same pile whatever the turn, and the
// pile at the default work cap is the converged one (the cap lifted). Used
// by the tests and by `terracut validate`.
#pragma once

#include <cstdint>

#include "terracut/core/soil.hpp"

namespace terracut::validation {

/// The sand: a layer this deep over the terrain's bottom.
inline constexpr double kSlantLayer_m = 0.2;

struct SlantPush {
  double yaw_deg = 10.0;        ///< about +Y, degrees (0: the blade along X, pushed along +Z), finite
  double width_m = 1.0;         ///< the blade, (0, 4]
  double depth_m = 0.04;        ///< the cut below the layer's top, (0, kSlantLayer_m)
  double travel_m = 0.8;        ///< along the blade's normal, (0, 4]
  double speed_m_per_s = 1.0;   ///< at 1 kHz, [0.01, 2]
  double hold_s = 0.2;          ///< held still after the push, [0, 10]
  double cell_m = 0.005;        ///< square cells, [0.002, 0.05]
  /// The soil's work cap, neighbour visits a step (1e9: lifted); the library's default.
  std::int64_t cap = SoilFlowParams{}.max_pair_checks_per_step;
  SoilSettle settle = SoilFlowParams{}.settle;  ///< how the displaced pile settles (the default: the fans)
};

/// What the push left.
struct SlantPile {
  double ahead_m3 = 0.0;  ///< soil above the layer ahead of the last edge, within the blade's width
  double peak_m = 0.0;    ///< its highest point above the layer
  int capped_steps = 0;   ///< steps the work cap stopped, of the push's and the hold's
};

/// The push's grid is square, (width + travel + 1.6 m) / cell a side, the
/// push centred on it. Throws std::invalid_argument naming a field out of
/// its range.
SlantPile measure_slant(const SlantPush& push);

}  // namespace terracut::validation
