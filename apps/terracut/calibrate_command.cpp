// `terracut calibrate`: a soil material from records (terracut::validation's
// calibrate.hpp), printed as a table of fitted fields with their
// uncertainties and as the scenario's `soil:` section, and written as JSON
// and YAML when --out is given.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "commands.hpp"
#include "terracut/core/error.hpp"
#include "terracut/io/scenario.hpp"
#include "terracut/session/scenario.hpp"
#include "terracut/validation/calibrate.hpp"
#include "terracut/validation/dem.hpp"

namespace terracut::cli {
namespace {

namespace fs = std::filesystem;

struct CalibrateOptions {
  std::string tests, record, scenario, dem_run, out;
  std::string fit = "internal_friction_deg,cohesion_pa";
  double window_s = 0.05;
  double from_s = 0.0;
};

void print(const validation::Calibration& c, const std::string& source) {
  std::printf("calibrated from %s\n\n  %-24s %14s %14s  how\n", source.c_str(), "field", "value", "uncertainty");
  for (const validation::FittedField& f : c.fields)
    std::printf("  %-24s %14.6g %14.3g  %s\n", f.name.c_str(), f.value, f.uncertainty, f.how.c_str());
  if (c.evaluations > 0)
    std::printf("\n  residual after the fit: %.4g N RMS (%.1f %% of the record's RMS), %d runs of the path\n",
                c.rms_residual, 100.0 * c.rms_relative, c.evaluations);
  else if (c.rms_residual > 0.0)
    std::printf("\n  shear tests' residual about the line: %.4g Pa RMS (%.1f %% of their mean)\n",
                c.rms_residual, 100.0 * c.rms_relative);
  for (const std::string& n : c.notes) std::printf("  note: %s\n", n.c_str());
  std::printf("\n%s", validation::material_yaml(c.material).c_str());
}

void write(const validation::Calibration& c, const std::string& source, const fs::path& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw InputError(dir.string() + ": cannot create the folder: " + ec.message());
  nlohmann::ordered_json j;
  j["source"] = source;
  for (const validation::FittedField& f : c.fields)
    // An undetermined uncertainty (+inf) is null, and says so.
    j["fields"].push_back({{"name", f.name},
                           {"value", f.value},
                           {"uncertainty", std::isfinite(f.uncertainty) ? nlohmann::ordered_json(f.uncertainty)
                                                                        : nlohmann::ordered_json(nullptr)},
                           {"uncertainty_determined", std::isfinite(f.uncertainty)},
                           {"how", f.how}});
  j["material"] = {{"unit_weight_n_per_m3", c.material.unit_weight_n_per_m3},
                   {"internal_friction_deg", c.material.internal_friction_deg},
                   {"cohesion_pa", c.material.cohesion_pa},
                   {"soil_tool_friction_deg", c.material.soil_tool_friction_deg},
                   {"adhesion_pa", c.material.adhesion_pa},
                   {"repose_deg", c.material.repose_deg}};
  j["rms_residual"] = c.rms_residual;
  j["rms_relative"] = c.rms_relative;
  j["evaluations"] = c.evaluations;
  j["notes"] = c.notes;
  const auto put = [&](const fs::path& p, const std::string& text) {
    std::ofstream o(p);
    o << text;
    if (!o) throw InputError(p.string() + ": cannot be written");
  };
  put(dir / "calibration.json", j.dump(2) + "\n");
  put(dir / "soil.yaml", validation::material_yaml(c.material));
}

}  // namespace

Command add_calibrate_command(CLI::App& app) {
  auto opt = std::make_shared<CalibrateOptions>();
  CLI::App* sub = app.add_subcommand(
      "calibrate",
      "Calibrate a soil material from records: material tests (bulk density, repose, shear\n"
      "and plate tests: --tests) or a force record along a known path (--record with the\n"
      "--scenario that holds its terrain, blade and starting material). Prints each fitted\n"
      "field with its standard uncertainty and the scenario's soil: section.");
  CLI::Option* tests = sub->add_option("--tests", opt->tests,
                                       "Material tests, JSON: {\"bulk_density_kg_per_m3\": [..], \"repose_deg\": [..],\n"
                                       "\"shear\": [{\"sigma_pa\", \"tau_pa\"}, ..], \"plate\": [..]} or a DEM's "
                                       "results/material.json");
  CLI::Option* record = sub->add_option("--record", opt->record,
                                        "A force record, CSV: t_s,x_m,y_m,z_m,qw,qx,qy,qz,fx_n,fy_n,fz_n "
                                        "(the blade's world pose and the force on it, fixed rate)");
  tests->excludes(record);
  CLI::Option* dem_run = sub->add_option(
      "--dem-run", opt->dem_run,
      "A DEM bulldozing run's folder (validation/dem/results/bulldoze/CASE/seedK): its force during the push "
      "as the record, its bed, blade and motion as the path; with --tests, the start is the tests' material");
  dem_run->excludes(record);
  sub->add_option("--scenario", opt->scenario,
                  "With --record: the scenario of the terrain, the blade and the material to start from");
  sub->add_option("--fit", opt->fit,
                  "With --record: the fields to fit, comma-separated (default internal_friction_deg,cohesion_pa)");
  sub->add_option("--window-s", opt->window_s, "With --record: compare means over windows of this length (s)")
      ->check(CLI::Range(1e-6, 1e3));
  sub->add_option("--from-s", opt->from_s, "With --record: ignore the samples before this time (s)");
  sub->add_option("--out", opt->out, "Also write DIR/calibration.json and DIR/soil.yaml");
  sub->footer(
      "The material tests' fit: the Mohr-Coulomb line of the shear tests (friction angle\n"
      "and cohesion with the standard errors of its slope and intercept), the plate tests'\n"
      "line through zero (soil-tool friction), the means of the density and the repose with\n"
      "the standard errors of the means. The record's fit: terracut replays the poses on\n"
      "the scenario's terrain and fits the chosen fields to the means of the horizontal\n"
      "force along the motion and of the vertical force over each window (Levenberg-\n"
      "Marquardt; uncertainties from the covariance at the solution). A field the record\n"
      "cannot identify is named. Judge a calibrated material on records it was not fitted\n"
      "to. docs/validation.md (Calibration).");
  return [opt]() {
    validation::Calibration c;
    std::string source;
    if (!opt->dem_run.empty()) {
      const validation::DemRun run = validation::read_dem_run(opt->dem_run);
      const SoilMaterial start = opt->tests.empty()
                                     ? SoilMaterial{}
                                     : validation::calibrate_from_tests(validation::read_material_tests(opt->tests)).material;
      const validation::DemReplay replay = validation::dem_replay(run, start);
      validation::RecordFit fit;
      fit.fields = io::parse_name_list(opt->fit, "--fit");
      fit.window_s = opt->window_s;
      // The record holds the DEM's force during the push only.
      fit.from_t_s = std::max(opt->from_s, double(replay.push_first) / replay.params.rate_hz);
      c = validation::calibrate_from_force_record(replay.params, replay.heights,
                                                  validation::dem_force_record(run, replay), fit);
      source = opt->dem_run + (opt->tests.empty() ? std::string() : " from " + opt->tests + "'s material");
    } else if (!opt->tests.empty()) {
      c = validation::calibrate_from_tests(validation::read_material_tests(opt->tests));
      source = opt->tests;
    } else if (!opt->record.empty()) {
      if (opt->scenario.empty())
        throw InputError("calibrate: --record needs --scenario (the terrain, the blade and the starting material)");
      const session::Scenario sc = session::load_scenario(opt->scenario);
      const validation::ForceRecord rec = validation::read_force_record(opt->record);
      const double dt = (rec.t_s.back() - rec.t_s.front()) / double(rec.t_s.size() - 1);
      validation::RecordFit fit;
      fit.fields = io::parse_name_list(opt->fit, "--fit");
      fit.window_s = opt->window_s;
      fit.from_t_s = opt->from_s;
      c = validation::calibrate_from_force_record(io::sim_params(sc.base, 1.0 / dt),
                                                  io::build_initial_heights(sc.base), rec, fit);
      source = opt->record + " on " + opt->scenario;
    } else {
      throw InputError("calibrate: give --tests FILE, --record FILE --scenario FILE, or --dem-run DIR");
    }
    print(c, source);
    if (!opt->out.empty()) write(c, source, opt->out);
    return kExitOk;
  };
}

}  // namespace terracut::cli
