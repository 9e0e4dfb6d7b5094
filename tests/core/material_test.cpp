// The soil material (material.hpp): the presets are their cited values, the
// defaults are dry sand's, and the validation names the field.
#include "terracut/core/material.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "terracut/core/earthmoving.hpp"

namespace terracut {
namespace {

TEST(SoilMaterial, PresetsAreCitedValuesAndOrdered) {
  const SoilMaterial dry = soil_preset(SoilPreset::kDrySand);
  const SoilMaterial loose = soil_preset(SoilPreset::kLooseSand);
  const SoilMaterial clay = soil_preset(SoilPreset::kClay);
  const SoilMaterial gravel = soil_preset(SoilPreset::kGravel);
  // docs/forces.md: Wong (2008) Table 2.3 strengths, Das unit weights,
  // delta = 2 phi / 3, repose angles of the cited tables.
  EXPECT_DOUBLE_EQ(dry.internal_friction_deg, 31.1);
  EXPECT_DOUBLE_EQ(dry.cohesion_pa, 1.3e3);
  EXPECT_DOUBLE_EQ(dry.repose_deg, 34.0);
  EXPECT_DOUBLE_EQ(loose.internal_friction_deg, 28.0);
  EXPECT_DOUBLE_EQ(loose.cohesion_pa, 1.04e3);
  EXPECT_DOUBLE_EQ(loose.unit_weight_n_per_m3, 14.5e3);
  EXPECT_DOUBLE_EQ(clay.internal_friction_deg, 13.0);
  EXPECT_DOUBLE_EQ(clay.cohesion_pa, 4.14e3);
  EXPECT_DOUBLE_EQ(gravel.internal_friction_deg, 36.5);
  EXPECT_DOUBLE_EQ(gravel.cohesion_pa, 0.0);
  EXPECT_NEAR(gravel.density_kg_per_m3(), 1680.0, 1e-9);
  for (const auto& [p, preset_name] : kSoilPresetNames) {
    const SoilMaterial s = soil_preset(p);
    EXPECT_TRUE(validate(s).empty()) << to_string(p);
    EXPECT_DOUBLE_EQ(s.soil_tool_friction_deg, 2.0 / 3.0 * s.internal_friction_deg);
    EXPECT_EQ(parse_enum<SoilPreset>(to_string(p)), p);
    EXPECT_NEAR(s.density_kg_per_m3() * kStandardGravity_m_per_s2, s.unit_weight_n_per_m3, 1e-9);
  }
  EXPECT_FALSE(parse_enum<SoilPreset>("sand").has_value());
  // The defaults are the dry-sand preset.
  const SoilMaterial def;
  EXPECT_DOUBLE_EQ(def.unit_weight_n_per_m3, dry.unit_weight_n_per_m3);
  EXPECT_DOUBLE_EQ(def.cohesion_pa, dry.cohesion_pa);
  EXPECT_DOUBLE_EQ(def.internal_friction_deg, dry.internal_friction_deg);
  EXPECT_DOUBLE_EQ(def.soil_tool_friction_deg, dry.soil_tool_friction_deg);
  EXPECT_DOUBLE_EQ(def.repose_deg, dry.repose_deg);
  // Loose sand is weaker and lighter in every parameter, so it resists less.
  EarthmovingParams pd, pl;
  pd.soil = dry;
  pl.soil = loose;
  EXPECT_LT(earthmoving_force(pl, 0.5, 0.1).total_n, earthmoving_force(pd, 0.5, 0.1).total_n);
}

TEST(SoilMaterial, ValidateNamesTheField) {
  SoilMaterial m;
  m.cohesion_pa = -1.0;
  EXPECT_EQ(validate(m).rfind("cohesion_pa", 0), 0u) << validate(m);
  m = {};
  m.internal_friction_deg = 90.0;  // [0, 90)
  EXPECT_NE(validate(m).find("internal_friction_deg must be in [0, 90)"), std::string::npos) << validate(m);
  m = {};
  m.repose_deg = 0.5;
  EXPECT_NE(validate(m).find("repose_deg"), std::string::npos);
  m = {};
  m.unit_weight_n_per_m3 = std::nan("");
  EXPECT_NE(validate(m).find("unit_weight_n_per_m3"), std::string::npos);
  m = {};
  m.soil_tool_friction_deg = -1.0;
  EXPECT_NE(validate(m).find("soil_tool_friction_deg"), std::string::npos);
  m = {};
  m.adhesion_pa = std::numeric_limits<double>::infinity();
  EXPECT_NE(validate(m).find("adhesion_pa"), std::string::npos);
  EXPECT_TRUE(validate(SoilMaterial{}).empty());
}

}  // namespace
}  // namespace terracut
