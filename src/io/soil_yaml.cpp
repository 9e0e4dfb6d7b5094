// The soil material's keys in a YAML mapping. See soil_yaml.hpp.
#include "terracut/io/soil_yaml.hpp"

namespace terracut::io {

using yaml::Map;

std::vector<std::string_view> soil_material_keys() {
  return {"preset",      "unit_weight_n_per_m3",   "density_kg_per_m3", "internal_friction_deg",
          "cohesion_pa", "soil_tool_friction_deg", "adhesion_pa",       "repose_deg"};
}

void read_soil_material(const Map& soil, SoilMaterial& m) {
  if (const auto p = soil.get("preset"))
    m = soil_preset(p->choice({SoilPreset::kDrySand, SoilPreset::kLooseSand, SoilPreset::kClay,
                               SoilPreset::kGravel},
                              "soil preset"));
  const auto in = [&](std::string_view key, double& out) {
    if (const auto f = soil.get(key)) out = f->in(find_range(material_ranges(), key));
  };
  in("unit_weight_n_per_m3", m.unit_weight_n_per_m3);
  if (const auto f = soil.get("density_kg_per_m3")) {
    if (soil.get("unit_weight_n_per_m3"))
      f->fail("give the density or the unit weight (= density x 9.81), not both");
    m.unit_weight_n_per_m3 =
        f->in(find_range(material_ranges(), "density_kg_per_m3")) * kStandardGravity_m_per_s2;
  }
  in("internal_friction_deg", m.internal_friction_deg);
  in("cohesion_pa", m.cohesion_pa);
  in("soil_tool_friction_deg", m.soil_tool_friction_deg);
  in("adhesion_pa", m.adhesion_pa);
  in("repose_deg", m.repose_deg);
}

}  // namespace terracut::io
