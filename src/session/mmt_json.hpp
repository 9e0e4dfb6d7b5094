// The soil estimate's entries of summary.json, for the single-process run
// and the two-process stations alike (the same figures in both). Internal
// to the session layer.
#pragma once

#include <nlohmann/json.hpp>

#include "terracut/core/soil_estimator.hpp"

namespace terracut::session::detail {

/// The fitted fields of a material, by their names in a scenario's soil:.
nlohmann::ordered_json material_json(const SoilMaterial& m);

/// The estimate: its material, standard uncertainties, the identifiable
/// fields, samples, restarts and residual; with the true material (a
/// simulated remote knows it), each field's distance from the truth in
/// standard uncertainties and whether it lies within two of them.
nlohmann::ordered_json estimate_json(const SoilEstimate& e, const SoilMaterial* truth);

}  // namespace terracut::session::detail
