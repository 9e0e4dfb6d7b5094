// The soil estimate's entries of summary.json (mmt_json.hpp).
#include "mmt_json.hpp"

#include <cmath>
#include <string>

namespace terracut::session::detail {

nlohmann::ordered_json material_json(const SoilMaterial& m) {
  nlohmann::ordered_json j;
  for (int f = 0; f < kSoilFieldCount; ++f)
    j[std::string(to_string(SoilField(f)))] = field_value(m, SoilField(f));
  return j;
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

}  // namespace terracut::session::detail
