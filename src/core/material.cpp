// The soil material: presets with their sources, ranges, validation.
// Sources and the choices made: docs/forces.md, "The soil material".
#include "terracut/core/material.hpp"

#include <array>

namespace terracut {

namespace {

// The ranges of SoilMaterial's fields (the scenario reader reads the same
// entries under `soil.`).
constexpr Range kRanges[] = {
    {"unit_weight_n_per_m3", 0.0, kRangeMax, RangeEnds::kOpenLow},
    {"density_kg_per_m3", 0.0, kRangeMax, RangeEnds::kOpenLow},
    {"internal_friction_deg", 0.0, 90.0, RangeEnds::kOpenHigh},
    {"cohesion_pa", 0.0, kRangeMax, RangeEnds::kClosed},
    {"soil_tool_friction_deg", 0.0, 90.0, RangeEnds::kOpenHigh},
    {"adhesion_pa", 0.0, kRangeMax, RangeEnds::kClosed},
    {"repose_deg", 1.0, 80.0, RangeEnds::kClosed},
};

}  // namespace

SoilMaterial soil_preset(SoilPreset preset) {
  SoilMaterial m;
  switch (preset) {
    case SoilPreset::kDrySand:
      // Strength of Wong's LETE sand; unit weight midway between Das' loose
      // (14.5) and dense (18.0) uniform sand; a dry sand's repose, 34 degrees
      // (Al-Hashemi & Al-Amoudi 2018).
      m.unit_weight_n_per_m3 = 16.25e3;
      m.cohesion_pa = 1.3e3;
      m.internal_friction_deg = 31.1;
      m.repose_deg = 34.0;
      break;
    case SoilPreset::kLooseSand:
      // Wong's "dry sand (Land Locomotion Lab.)"; Das' loose uniform sand. A
      // poured heap is loose whatever the soil it came from, so its repose is
      // the dry sand's.
      m.unit_weight_n_per_m3 = 14.5e3;
      m.cohesion_pa = 1.04e3;
      m.internal_friction_deg = 28.0;
      m.repose_deg = 34.0;
      break;
    case SoilPreset::kClay:
      // Wong's "clayey soil (Thailand)" at 38 % moisture; moist unit weight
      // from Das' soft-clay dry unit weight (midpoint 13.0) times 1.38;
      // adhesion assumed half the cohesion; repose the upper end of the
      // tables' 25-40 degrees for excavated clay lumps (its cohesion holds
      // cut faces steeper still, which one angle cannot say).
      m.unit_weight_n_per_m3 = 13.0e3 * 1.38;
      m.cohesion_pa = 4.14e3;
      m.internal_friction_deg = 13.0;
      m.adhesion_pa = 0.5 * 4.14e3;
      m.repose_deg = 40.0;
      break;
    case SoilPreset::kGravel:
      // Medium-dense gravel: friction the middle of Look's 34-39 degrees; dry
      // gravel's 1680 kg/m^3; repose the middle of the tables' 30-45 degrees
      // for loose dry gravel; cohesionless.
      m.unit_weight_n_per_m3 = 1680.0 * kStandardGravity_m_per_s2;
      m.cohesion_pa = 0.0;
      m.internal_friction_deg = 36.5;
      m.repose_deg = 37.5;
      break;
  }
  // Soil-tool friction: two thirds of the internal friction (a rough steel face).
  m.soil_tool_friction_deg = m.internal_friction_deg * 2.0 / 3.0;
  return m;
}

std::span<const Range> material_ranges() { return kRanges; }

std::string validate(const SoilMaterial& m) {
  const auto field = [](std::string_view name, double value) {
    return check(find_range(kRanges, name), value);
  };
  if (auto e = field("unit_weight_n_per_m3", m.unit_weight_n_per_m3); !e.empty()) return e;
  if (auto e = field("internal_friction_deg", m.internal_friction_deg); !e.empty()) return e;
  if (auto e = field("cohesion_pa", m.cohesion_pa); !e.empty()) return e;
  if (auto e = field("soil_tool_friction_deg", m.soil_tool_friction_deg); !e.empty()) return e;
  if (auto e = field("adhesion_pa", m.adhesion_pa); !e.empty()) return e;
  return field("repose_deg", m.repose_deg);
}

}  // namespace terracut
