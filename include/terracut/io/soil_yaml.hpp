// The soil material's keys in a YAML (or JSON) mapping: the one reader of
// them, used by the scenario's `soil:` section and by the files that carry a
// material of their own (a soil-bin data set's "terracut_soil").
#pragma once

#include <string_view>
#include <vector>

#include "terracut/core/material.hpp"
#include "terracut/io/yaml_reader.hpp"

namespace terracut::io {

/// The material's keys: preset, unit_weight_n_per_m3, density_kg_per_m3,
/// internal_friction_deg, cohesion_pa, soil_tool_friction_deg, adhesion_pa,
/// repose_deg (the scenario's soil: section adds its model's keys).
std::vector<std::string_view> soil_material_keys();

/// Sets m from the mapping: a preset's values (m's own without one), each
/// replaced by a field given; density or unit weight, not both; each in its
/// range (material_ranges()). Throws InputError "FILE:LINE: path.key: what".
void read_soil_material(const yaml::Map& soil, SoilMaterial& m);

}  // namespace terracut::io
