// The paper's algorithm as written: test the blade against every column every
// step. Kept as the test oracle for the traversal code and as the baseline of
// the performance work. Cost grows with the whole terrain, not the blade.
// Boundary cases follow docs/model.md ("Boundaries"), decided exactly: contact
// half-open (a point of the edge in one cell), cuts closed.
#pragma once

#include "terracut/core/cut.hpp"

namespace terracut {

/// Contact by testing every cell (columns: slab method against every box;
/// surface: clipping the segment to every triangle's prism).
ContactResult measure_contact_brute_force(const HeightGrid& grid, Representation representation,
                                          const Segment& edge);

/// The same cut as cut_sweep, by testing every sample against every triangle.
CutResult cut_sweep_brute_force(HeightGrid& grid, Representation representation,
                                const Segment& from, const Segment& to);

}  // namespace terracut
