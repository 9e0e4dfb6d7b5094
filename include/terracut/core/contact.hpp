// Contact between the cutting line and the terrain: the length of the blade
// that lies inside material, for either terrain representation.
#pragma once

#include <cstdint>
#include <string_view>
#include <optional>

#include "terracut/core/enum_names.hpp"
#include "terracut/core/blade.hpp"
#include "terracut/core/grid.hpp"

namespace terracut {

/// How the height samples are read as a solid.
enum class Representation {
  /// The paper's: each sample is an axis-aligned box over its cell, from the
  /// ground up to its height. Contact by the slab method.
  kColumns,
  /// The default: a continuous surface through the sample points (cell
  /// centres), two triangles per square of four neighbouring samples (split
  /// along the diagonal from sample (c+1, r) to (c, r+1), as Bullet's
  /// heightfield does), extended flat to the terrain's outer edge over the
  /// half-cell border.
  kSurface,
};

/// Its names (enum_names.hpp: to_string, parse_enum).
inline constexpr EnumName<Representation> kRepresentationNames[] = {
    {Representation::kColumns, "columns"},
    {Representation::kSurface, "surface"},
};
constexpr std::span<const EnumName<Representation>> enum_names(Representation) { return kRepresentationNames; }

/// What one contact query found.
struct ContactResult {
  double length_m = 0.0;          ///< length of the edge inside material, metres
  double section_area_m2 = 0.0;   ///< integral of (surface height - edge height) over that length, m^2
  double max_depth_m = 0.0;       ///< largest depth of the edge below the surface, metres
  std::int64_t cells_visited = 0; ///< cells the traversal examined
};

/// Contact of the segment with the terrain, walking only the cells under the
/// segment (a 2-D grid traversal of its footprint on the ground plane). Each
/// point of the segment belongs to one cell, [c, c+1) x [r, r+1) (the last
/// cells holding the grid's far edges), so a segment lying on a cell wall is
/// counted once (docs/model.md, "Boundaries").
ContactResult measure_contact(const HeightGrid& grid, Representation representation,
                              const Segment& edge);

}  // namespace terracut
