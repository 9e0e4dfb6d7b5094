// The terrain surface as a representation reads the samples: the one height
// query used by the force model (the proxy), the cut-depth estimate, the
// viewer's tool readout and anyone else who asks "how high is the soil at
// (x, z)". Kept next to the grid so that what is drawn and what is felt come
// from the same function.
#pragma once

#include <utility>

#include "terracut/core/contact.hpp"
#include "terracut/core/grid.hpp"

namespace terracut {

/// Height of the terrain surface above the ground level (origin_m.y) at world
/// (x, z), metres, as the representation reads the samples: kColumns, the
/// height of the cell containing the point; kSurface, the triangulated surface
/// through the cell centres (same split as contact.hpp), flat over the
/// half-cell border. Outside the terrain rectangle: 0 (the rigid ground).
double surface_height_m(const HeightGrid& grid, Representation representation, double x,
                        double z) noexcept;

/// The same over a copy of the heights (rows x cols, row-major, metres:
/// e.g. a viewer's frame) laid out as spec says.
double surface_height_m(const GridSpec& spec, const float* heights_m,
                        Representation representation, double x, double z) noexcept;

/// The same over two layers laid out as spec says (e.g. the grid's heights
/// and its initial ones) at one point, found once: each of the pair is
/// surface_height_m over that layer, bit for bit.
std::pair<double, double> surface_heights_m(const GridSpec& spec, const float* first_m, const float* second_m,
                                            Representation representation, double x, double z) noexcept;

/// World Y of the terrain surface at (x, z): origin_m.y + surface_height_m.
double surface_y_m(const HeightGrid& grid, Representation representation, double x,
                   double z) noexcept;

}  // namespace terracut
