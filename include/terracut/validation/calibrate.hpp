// Calibration of a soil material from records (`terracut calibrate`, and
// terracut.calibrate_tests / calibrate_record in Python):
//   - from material tests: a bulk density, an angle of repose, a shear test
//     (normal and shear stress at failure, at several normal stresses) and a
//     plate test (the shear and normal stress of the soil sliding on the
//     tool's material), each a list of measurements; the fit is the
//     Mohr-Coulomb line of the shear test (friction angle and cohesion),
//     the plate tests' line through zero (soil-tool friction), the means of
//     the rest, each with its standard uncertainty (+inf where the tests
//     leave no degree of freedom to estimate it: two shear tests, one value);
//   - from a force record along a known path: the tool's poses and the force
//     measured on it (a DEM's, a soil bin's, a robot's log) on a known
//     terrain; terracut replays the path with trial materials and fits the
//     chosen fields to the measured force by Levenberg-Marquardt, with the
//     uncertainty of each from the fit's covariance.
// Sources: docs/validation.md ("Calibration"). A material calibrated on a
// record must not be judged on the same record: the DEM comparison takes
// its material from the DEM's material tests only.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "terracut/core/material.hpp"
#include "terracut/core/simulation.hpp"

namespace terracut::validation {

/// One fitted field of the material.
struct FittedField {
  std::string name;        ///< a SoilMaterial field ("internal_friction_deg", ...)
  double value = 0.0;
  double uncertainty = 0.0;  ///< one standard uncertainty, in the field's unit; +inf: not identified
  std::string how;         ///< how it was obtained, one line
};

/// A calibration's result.
struct Calibration {
  SoilMaterial material;             ///< the fitted material (the rest: its start)
  std::vector<FittedField> fields;   ///< what was fitted, with uncertainties
  double rms_residual = 0.0;         ///< in the records' unit (N, or Pa), after the fit
  double rms_relative = 0.0;         ///< the same over the records' RMS
  int evaluations = 0;               ///< terracut runs (force records) or 0
  std::vector<std::string> notes;    ///< what could not be identified, and why
};

/// Material tests as measured: each a list of values.
struct MaterialTests {
  std::vector<double> bulk_density_kg_per_m3;
  std::vector<double> repose_deg;
  struct Stress {
    double sigma_pa = 0.0, tau_pa = 0.0;
  };
  std::vector<Stress> shear;  ///< the soil's failure (peak), at several normal stresses
  std::vector<Stress> plate;  ///< the soil sliding on the tool's material
};

/// Reads material tests from JSON: either the general form
///   {"bulk_density_kg_per_m3": [..], "repose_deg": [..],
///    "shear": [{"sigma_pa": .., "tau_pa": ..}, ..], "plate": [{"sigma_pa": .., "tau_pa": ..}, ..]}
/// or a DEM's results/material.json (its per-seed values and tests). Throws
/// InputError naming the file and the field.
MaterialTests read_material_tests(const std::filesystem::path& json);

/// The material from tests (see the file comment); start gives the fields
/// the tests do not (adhesion: 0 unless start has one). Throws InputError
/// when a test has too few points to fit (a line needs two normal stresses).
Calibration calibrate_from_tests(const MaterialTests& tests, const SoilMaterial& start = {});

/// A force record along a path: per sample, the time, the tool's world pose
/// and the measured force on it (world N, Y up).
struct ForceRecord {
  std::vector<double> t_s;
  std::vector<BladePose> pose;
  std::vector<Vec3> force_n;
};

/// Reads a force record: CSV with the header
///   t_s,x_m,y_m,z_m,qw,qx,qy,qz,fx_n,fy_n,fz_n
/// (world frame, Y up; samples at a fixed rate). Throws InputError naming
/// the file and the line.
ForceRecord read_force_record(const std::filesystem::path& csv);

/// How to fit a force record.
struct RecordFit {
  /// The fields to fit (SoilMaterial's names); the others keep their start.
  std::vector<std::string> fields = {"internal_friction_deg", "cohesion_pa"};
  /// Samples are compared as means over windows of this many seconds (a
  /// granular force fluctuates around its mean: compare means with means).
  double window_s = 0.05;
  /// Only the samples after this time count (a plunge's transient, say).
  double from_t_s = 0.0;
  int max_iterations = 30;
};

/// Fits params.soil.material's fields to the record: terracut steps the
/// record's poses (params.rate_hz must be the record's rate) over the
/// initial heights, and the residuals are the windows' means of the
/// horizontal force along the motion and of the vertical force. params is
/// the run's (its material is the start). Throws InputError on a bad field
/// name or a record that does not fit the rate.
Calibration calibrate_from_force_record(const SimParams& params, const std::vector<float>& heights,
                                        const ForceRecord& record, const RecordFit& fit = {});

/// The YAML `soil:` section of a material: model: flow (the repose is the
/// flow's) and every field of the material, %.6g.
std::string material_yaml(const SoilMaterial& m);

}  // namespace terracut::validation
