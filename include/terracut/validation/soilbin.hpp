// terracut against published soil-bin measurements: the mean horizontal
// (draft) force on flat blades cutting a soil whose properties were
// published with the forces. terracut predicts each point from the published
// properties alone (no per-point fitting) and the comparison reports the
// error of each point, the mean absolute relative error and the worst factor.
//
// A data set is two files in one folder (data/soilbin/README.md):
//   <name>.csv   point_id,blade_width_m,rake_angle_deg,depth_m,speed_m_per_s,
//                horizontal_force_n,vertical_force_n,source_location,reading
//                (force on the whole blade, N; vertical_force_n may be empty)
//   <name>.json  {"citation": "...", "how_read": "...",
//                 "terracut_soil": {the scenario's soil: fields}}
// A JSON without its CSV is a data set whose forces are not stored (listed,
// not compared).
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "terracut/core/material.hpp"

namespace terracut::validation {

/// One measured point.
struct SoilBinPoint {
  std::string id;
  double blade_width_m = 0.0;
  double rake_deg = 90.0;  ///< from the horizontal, 90: vertical (terracut's rake_angle_deg)
  double depth_m = 0.0;
  double speed_m_per_s = 0.0;
  double horizontal_n = 0.0;          ///< the measured mean draft on the whole blade
  std::optional<double> vertical_n;   ///< + pushing the blade down, when published
  std::string source_location;        ///< table or figure it was read from
  std::string reading;                ///< how it was read (table, digitized, with its uncertainty)
};

/// One data set.
struct SoilBinSet {
  std::string name;
  std::string citation;
  std::string how_read;
  SoilMaterial material;             ///< the published soil properties, as terracut's material
  std::vector<SoilBinPoint> points;  ///< empty: the forces are not stored
};

/// Every data set in dir (sorted by name). Throws InputError naming the
/// file, the line and the field of a bad one.
std::vector<SoilBinSet> read_soilbin_sets(const std::filesystem::path& dir);

/// terracut's prediction of a point: a flat layer of the material (three
/// depths deep, 1/5 of the depth per cell, at most 1 cm), the blade at the
/// point's width and rake pushed 0.3 m at its speed (at 1 kHz) with the cut
/// soil leaving the blade (the soil-bin's steady draft, no pile growing
/// ahead: soil: model vanish); the mean over the last 0.1 m.
struct SoilBinPrediction {
  double horizontal_n = 0.0;  ///< resisting the motion, > 0
  double vertical_n = 0.0;    ///< + pushing the blade down
};
SoilBinPrediction predict_soilbin(const SoilBinPoint& point, const SoilMaterial& material);

/// Targets: the mean absolute relative error of the horizontal force at
/// most 15 % over every point, and every point within a factor 1.5.
inline constexpr double kSoilBinMareTarget = 0.15;
inline constexpr double kSoilBinFactorTarget = 1.5;

/// A data set's comparison.
struct SoilBinComparison {
  std::string name;
  std::vector<SoilBinPrediction> predicted;  ///< per point
  std::vector<double> error;                 ///< per point, (terracut - measured) / measured
  double mare = 0.0;                         ///< mean |error|
  double worst_factor = 1.0;                 ///< max over points of max(t/m, m/t)
  bool mare_met = false, factor_met = false;
};
SoilBinComparison compare_soilbin(const SoilBinSet& set);

}  // namespace terracut::validation
