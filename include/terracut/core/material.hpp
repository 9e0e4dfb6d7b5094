// The soil material: one record of what the soil is, read by every phase
// that needs it (the flow's angle of repose, the cutting, penetration and
// turning forces, the Bullet world's pile pressure, both teleoperation
// stations). Box2D's b2SurfaceMaterial is the model: one plain record, its
// values validated once by its owner (the simulation's parameters).
//
// Units are those of a scenario file: angles in degrees, stresses in
// pascals, unit weight in N/m^3 (density x g). docs/forces.md ("The soil
// material") lists every preset's values with their sources.
#pragma once

#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "terracut/core/enum_names.hpp"
#include "terracut/core/ranges.hpp"

namespace terracut {

/// Standard gravity, m/s^2: a unit weight over it is a density, a carried
/// load's weight over it is its mass (the Bullet world's default gravity).
inline constexpr double kStandardGravity_m_per_s2 = 9.81;

/// A Mohr-Coulomb soil with its soil-tool interface and its angle of repose;
/// read-only during a run. The defaults are the dry_sand preset.
struct SoilMaterial {
  /// gamma: bulk unit weight, N/m^3 (density x 9.81), finite, > 0.
  double unit_weight_n_per_m3 = 16.25e3;
  /// phi: internal friction angle, degrees, [0, 90).
  double internal_friction_deg = 31.1;
  /// c: cohesion, Pa, finite, >= 0.
  double cohesion_pa = 1.3e3;
  /// delta: soil-tool friction angle, degrees, [0, 90).
  double soil_tool_friction_deg = 31.1 * 2.0 / 3.0;
  /// c_a: soil-tool adhesion, Pa, finite, >= 0.
  double adhesion_pa = 0.0;
  /// Angle of repose: the stopping angle of a flowing slope, degrees, in
  /// [1, 80] (the flow relaxes slopes to it; soil.hpp).
  double repose_deg = 34.0;

  /// Bulk density, kg/m^3: the unit weight over kStandardGravity_m_per_s2.
  double density_kg_per_m3() const { return unit_weight_n_per_m3 / kStandardGravity_m_per_s2; }
};

/// Built-in materials with cited values (docs/forces.md, "The soil material").
enum class SoilPreset {
  kDrySand,    ///< medium-dense dry sand
  kLooseSand,  ///< loose dry sand
  kClay,       ///< clayey soil at 38 % moisture
  kGravel,     ///< medium-dense sandy gravel
};

/// The material of a preset.
SoilMaterial soil_preset(SoilPreset preset);
/// Its names (enum_names.hpp: to_string, parse_enum), every preset in the
/// order of the enumeration.
inline constexpr EnumName<SoilPreset> kSoilPresetNames[] = {
    {SoilPreset::kDrySand, "dry_sand"},
    {SoilPreset::kLooseSand, "loose_sand"},
    {SoilPreset::kClay, "clay"},
    {SoilPreset::kGravel, "gravel"},
};
constexpr std::span<const EnumName<SoilPreset>> enum_names(SoilPreset) { return kSoilPresetNames; }

/// The ranges of SoilMaterial's fields, by their names in it (and in a
/// scenario's `soil:` section): "unit_weight_n_per_m3", "repose_deg", ...
std::span<const Range> material_ranges();

/// Returns an empty string when the material is valid, else a message naming
/// the field ("internal_friction_deg must be in [0, 90), got 95").
std::string validate(const SoilMaterial& material);

/// Degrees to radians.
constexpr double radians(double degrees) { return degrees * (3.14159265358979323846 / 180.0); }

}  // namespace terracut
