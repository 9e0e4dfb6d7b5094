// Swept cutting: whatever the cutting line passes through between two poses
// is cut, however far it moved (no tunnelling).
//
// The swept surface between edge `from` (endpoints A0, B0) and edge `to`
// (A1, B1) is taken as the two triangles (A0, B0, B1) and (A0, B1, A1); where
// the two edges cross in plan at a point P inside both (the blade turned
// about a point of its edge: a turn in place, a hand's wobble), that quad is
// a bow-tie and the triangles are its lobes (A0, A1, P) and (P, B0, B1) (the
// diagonal's triangle would reach ahead of the part of the edge that went
// back). The caller splits a motion with a large rotation into sub-steps (see
// Simulation), so this approximates the true sweep to a fraction of a cell.
//
// - Surface representation: every sample point whose ground position lies
//   under a swept triangle (its edges included) is lowered to the
//   triangle's height there.
// - Columns representation: every column whose cell the swept region crosses
//   is lowered to the lowest point of the region inside its cell ("until its
//   top is below the line"). With from == to this is the paper's rule for a
//   line at rest.
// The region and the cells are closed: a sample on the region's edge, or a
// cell the region meets only along a wall or at a corner, is cut
// (docs/model.md, "Boundaries").
// Heights never go below 0 (the rigid floor). Cutting only lowers samples, so
// the final shape after a set of cuts does not depend on their order.
#pragma once

#include <cstdint>

#include "terracut/core/contact.hpp"

namespace terracut {

/// What one swept cut changed.
struct CutResult {
  double removed_volume_m3 = 0.0;  ///< sum of height lowered x cell area
  Rect changed{};                  ///< samples whose height changed
  std::int64_t cells_visited = 0;  ///< samples the sweep examined
};

/// Cuts the terrain with the region swept by the edge moving from `from` to `to`.
CutResult cut_sweep(HeightGrid& grid, Representation representation, const Segment& from,
                    const Segment& to);

}  // namespace terracut
