// The soil estimate's entries of summary.json and their reading back
// (mmt_json.hpp).
#include "mmt_json.hpp"

#include <cmath>
#include <string>

#include "terracut/core/error.hpp"

namespace terracut::session::detail {
namespace {

const nlohmann::ordered_json& entry(const nlohmann::ordered_json& j, const char* key,
                                    const std::filesystem::path& where) {
  if (!j.is_object() || !j.contains(key) || j[key].is_null())
    throw InputError(where.string() + ": no estimate entry '" + key + "'");
  return j[key];
}

}  // namespace

nlohmann::ordered_json material_json(const SoilMaterial& m) {
  nlohmann::ordered_json j;
  for (int f = 0; f < kSoilFieldCount; ++f)
    j[std::string(to_string(SoilField(f)))] = field_value(m, SoilField(f));
  return j;
}

SoilMaterial material_from_json(const nlohmann::ordered_json& j, const std::filesystem::path& where) {
  SoilMaterial m;
  for (int f = 0; f < kSoilFieldCount; ++f) {
    const std::string name(to_string(SoilField(f)));
    const double v = entry(j, name.c_str(), where).get<double>();
    switch (SoilField(f)) {
      case SoilField::kUnitWeight: m.unit_weight_n_per_m3 = v; break;
      case SoilField::kCohesion: m.cohesion_pa = v; break;
      case SoilField::kAdhesion: m.adhesion_pa = v; break;
      case SoilField::kInternalFriction: m.internal_friction_deg = v; break;
      case SoilField::kSoilToolFriction: m.soil_tool_friction_deg = v; break;
    }
  }
  return m;
}

nlohmann::ordered_json estimate_json(const SoilEstimate& e, const SoilMaterial* truth) {
  nlohmann::ordered_json j;
  j["material"] = material_json(e.material);
  nlohmann::ordered_json sd, identifiable = nlohmann::ordered_json::array();
  for (int f = 0; f < kSoilFieldCount; ++f) {
    const std::string name(to_string(SoilField(f)));
    sd[name] = e.sd[std::size_t(f)];
    if (e.is_identifiable(SoilField(f))) identifiable.push_back(name);
  }
  j["sd"] = sd;
  j["identifiable"] = identifiable;
  j["samples"] = e.samples;
  j["restarts"] = e.restarts;
  j["residual_rms_n"] = e.residual_rms_n;
  if (truth) {
    j["truth"] = material_json(*truth);
    nlohmann::ordered_json z, within;
    for (int f = 0; f < kSoilFieldCount; ++f) {
      const SoilField field = SoilField(f);
      const std::string name(to_string(field));
      const double d = field_value(e.material, field) - field_value(*truth, field);
      const double s = e.sd[std::size_t(f)];
      z[name] = s > 0.0 ? d / s : (d == 0.0 ? 0.0 : HUGE_VAL);
      if (e.is_identifiable(field)) within[name] = std::fabs(d) <= 2.0 * s;
    }
    j["error_in_sd"] = z;
    j["identifiable_within_2sd"] = within;
  }
  return j;
}

SoilEstimate estimate_from_json(const nlohmann::ordered_json& j, const std::filesystem::path& where,
                                SoilMaterial* truth) {
  SoilEstimate e;
  e.material = material_from_json(entry(j, "material", where), where);
  // An unbounded uncertainty is written as null (JSON has no infinity).
  const nlohmann::ordered_json& sd = entry(j, "sd", where);
  for (int f = 0; f < kSoilFieldCount; ++f) {
    const std::string name(to_string(SoilField(f)));
    if (!sd.is_object() || !sd.contains(name))
      throw InputError(where.string() + ": no estimate entry 'sd." + name + "'");
    e.sd[std::size_t(f)] = sd[name].is_null() ? HUGE_VAL : sd[name].get<double>();
  }
  for (const auto& name : entry(j, "identifiable", where)) {
    const auto field = parse_enum<SoilField>(name.get<std::string>());
    if (!field) throw InputError(where.string() + ": estimate: '" + name.get<std::string>() + "' is no soil field");
    e.identifiable |= 1u << int(*field);
  }
  e.samples = entry(j, "samples", where).get<std::int64_t>();
  e.restarts = entry(j, "restarts", where).get<std::int64_t>();
  e.residual_rms_n = entry(j, "residual_rms_n", where).get<double>();
  e.known = e.samples > 0;
  if (truth) *truth = material_from_json(entry(j, "truth", where), where);
  return e;
}

}  // namespace terracut::session::detail
