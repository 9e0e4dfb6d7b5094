// The entries of an MMT summary.json, for the single-process run, the
// stations of two processes and their report alike (the same figures in
// each). Internal to the session layer.
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>

#include "terracut/core/soil_estimator.hpp"
#include "terracut/net/emulator.hpp"
#include "terracut/net/messages.hpp"
#include "terracut/session/mmt.hpp"

namespace terracut::session {

/// Rejected datagrams by reason name ("truncated": n, ...).
nlohmann::ordered_json rejected_json(const net::RejectCounts& c);
/// A direction's emulated conditions (the "link" entry's keys).
nlohmann::ordered_json link_json(const net::LinkConditions& c);
/// Everything of a run's summary.json from "duration_s" on: force and
/// terrain errors, tracking, traffic, updates, the error after the first
/// second of cutting, the estimate, the remote arm, passivity, rejections
/// and timing.
nlohmann::ordered_json summary_json(const MmtSummary& s);

namespace detail {

/// The fitted fields of a material, by their names in a scenario's soil:.
nlohmann::ordered_json material_json(const SoilMaterial& m);
/// The material material_json wrote; where: the file, for the error.
/// Throws InputError naming a missing field.
SoilMaterial material_from_json(const nlohmann::ordered_json& j, const std::filesystem::path& where);

/// The estimate: its material, standard uncertainties, the identifiable
/// fields, samples, restarts and residual; with the true material (a
/// simulated remote knows it), each field's distance from the truth in
/// standard uncertainties and whether it lies within two of them.
nlohmann::ordered_json estimate_json(const SoilEstimate& e, const SoilMaterial* truth);
/// The estimate estimate_json wrote (its "truth" into *truth when given).
/// Throws InputError naming a missing field.
SoilEstimate estimate_from_json(const nlohmann::ordered_json& j, const std::filesystem::path& where,
                                SoilMaterial* truth);

}  // namespace detail
}  // namespace terracut::session
