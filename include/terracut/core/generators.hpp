// Built-in terrains: analytic shapes (a dome, a flat-topped box, a plane)
// sampled at the cell centres of a grid, and the exact geometry of the dome
// that the experiment reports compare against. Pure functions, no I/O.
//
// All X and Z coordinates here are world coordinates in metres, the same frame
// as the blade's keyframes; heights are metres above the ground level
// (GridSpec::origin_m.y).
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "terracut/core/enum_names.hpp"
#include "terracut/core/blade.hpp"
#include "terracut/core/grid.hpp"

namespace terracut {

/// The kinds of built-in terrain.
enum class GeneratorKind {
  kMound,  ///< a dome whose horizontal sections are circles (the paper's experiment 1)
  kBox,    ///< a flat-topped rectangle of material (the paper's experiment 2)
  kPlane,  ///< a constant height everywhere
};

/// Its names (enum_names.hpp: to_string, parse_enum).
inline constexpr EnumName<GeneratorKind> kGeneratorKindNames[] = {
    {GeneratorKind::kMound, "mound"},
    {GeneratorKind::kBox, "box"},
    {GeneratorKind::kPlane, "plane"},
};
constexpr std::span<const EnumName<GeneratorKind>> enum_names(GeneratorKind) { return kGeneratorKindNames; }

/// A dome (half of an ellipsoid of revolution):
///   h(x, z) = height_m * sqrt(1 - (r / radius_m)^2)  for r < radius_m, else 0,
/// where r is the ground-plane distance from (centre_x_m, centre_z_m). Its
/// horizontal section at height y in [0, height_m] is a circle of radius
/// radius_m * sqrt(1 - (y / height_m)^2).
struct MoundShape {
  double centre_x_m = 0.5;  ///< world X of the dome's axis, metres, finite
  double centre_z_m = 0.5;  ///< world Z of the dome's axis, metres, finite
  double radius_m = 0.4;    ///< radius of the dome's footprint, metres, > 0
  double height_m = 0.2;    ///< height of the peak above ground, metres, > 0
};

/// A flat-topped rectangle: height_m where min_x_m <= x <= max_x_m and
/// min_z_m <= z <= max_z_m (boundaries included), 0 elsewhere.
struct BoxShape {
  double min_x_m = 0.0;   ///< world X of the low edge, metres, finite
  double min_z_m = 0.0;   ///< world Z of the low edge, metres, finite
  double max_x_m = 1.0;   ///< world X of the high edge, metres, >= min_x_m
  double max_z_m = 1.0;   ///< world Z of the high edge, metres, >= min_z_m
  double height_m = 1.0;  ///< height of the top above ground, metres, >= 0
};

/// A constant height everywhere.
struct PlaneShape {
  double height_m = 0.0;  ///< height above ground, metres, >= 0
};

/// A built-in terrain: the kind, and the parameters of that kind (the
/// parameters of the other kinds are ignored).
struct Generator {
  GeneratorKind kind = GeneratorKind::kMound;
  MoundShape mound{};
  BoxShape box{};
  PlaneShape plane{};
};

/// The generator of the given kind with the documented defaults for a grid:
/// mound centred on the terrain's middle with radius 0.4 * min(size_x, size_z)
/// and peak full_scale_m; box over the whole extent with height full_scale_m;
/// plane at full_scale_m.
Generator default_generator(GeneratorKind kind, const GridSpec& spec);

/// Returns an empty string when the generator's parameters are valid (finite,
/// positive radius and peak, non-negative heights, min <= max), else a message
/// naming the bad field (e.g. "mound.radius_m must be > 0").
std::string validate(const Generator& generator);

/// Height of the shape at world ground point (x_m, z_m), metres.
double height_at(const MoundShape& mound, double x_m, double z_m);
double height_at(const BoxShape& box, double x_m, double z_m);
double height_at(const Generator& generator, double x_m, double z_m);

/// Samples the generator at the cell centres of the grid: returns rows x cols
/// heights, row-major, index = r * cols + c, metres. The generator must be
/// valid; an invalid grid spec (validate(spec) not empty: a side outside
/// [1, 65536], more than 2^30 samples) throws InputError with validate's
/// message, before anything is allocated.
std::vector<float> generate_heights(const GridSpec& spec, const Generator& generator);

/// Exact length, metres, of the part of a segment that lies inside the solid
/// dome {y >= ground_y_m, ((x-xc)^2 + (z-zc)^2) / R^2 + ((y-ground)/H)^2 <= 1}.
double contact_length(const MoundShape& mound, double ground_y_m, const Segment& edge);

/// Exact chord of an unbounded horizontal line along X at height
/// y_above_ground_m and depth z_m through the dome:
///   2 * sqrt(r^2 - (z - zc)^2) with r = R * sqrt(1 - (y/H)^2), or 0 when the
/// line misses (or y is outside [0, H]).
double horizontal_chord_m(const MoundShape& mound, double y_above_ground_m, double z_m);

}  // namespace terracut
