// The DEM section of `terracut validate`. See validate_dem.hpp and
// docs/validation.md, "Against a DEM".
#include "validate_dem.hpp"

#include <algorithm>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "report_files.hpp"
#include "terracut/core/error.hpp"
#include "terracut/io/image.hpp"
#include "terracut/validation/calibrate.hpp"
#include "terracut/validation/dem.hpp"

namespace terracut::cli {

namespace fs = std::filesystem;
using namespace terracut::validation;

namespace {

std::string pct(double x) { return fmt("%+.0f %%", 100.0 * x); }
std::string verdict(bool met) { return met ? "met" : "**missed**"; }

}  // namespace

DemSection run_dem_section(const fs::path& results_dir, const fs::path& out_dir,
                           const std::function<void(const std::string&)>& say) {
  DemSection section;
  std::ostringstream md;
  md << "## Against a DEM (LIGGGHTS)\n\n";
  const fs::path material_json = results_dir / "material.json";
  if (!fs::exists(material_json)) {
    md << "No DEM results in `" << results_dir.string() << "` (validation/dem/README.md makes them).\n";
    section.markdown = md.str();
    return section;
  }
  const DemMaterialTests tests = read_dem_material(material_json);
  const Calibration calibration = calibrate_from_tests(read_material_tests(material_json));
  // Every field from the DEM's own tests: none may keep a default.
  for (const char* field :
       {"unit_weight_n_per_m3", "repose_deg", "internal_friction_deg", "cohesion_pa", "soil_tool_friction_deg"})
    if (std::none_of(calibration.fields.begin(), calibration.fields.end(),
                     [&](const FittedField& f) { return f.name == field; }))
      throw InputError(material_json.string() + ": the tests give no " + field +
                       " (bulk density, repose, shear and soil-tool tests are all needed)");
  const SoilMaterial& material = calibration.material;
  // The sensitivity to the choice of the peak: the same runs with the
  // critical state's friction and cohesion (reported, not a target).
  SoilMaterial critical = material;
  critical.internal_friction_deg = tests.friction_residual_deg;
  critical.cohesion_pa = std::max(0.0, tests.cohesion_residual_pa);
  const auto plus_minus = [&](const char* name, const char* format) {
    for (const FittedField& f : calibration.fields)
      if (f.name == name) return fmt(format, f.value) + " +- " + fmt(format, f.uncertainty);
    return std::string("(not in the tests)");
  };
  const std::vector<DemRun> runs = read_dem_runs(results_dir);
  section.ran = true;
  section.runs = int(runs.size());
  const fs::path dir = out_dir / "dem";
  create_output_folder(dir);
  {
    nlohmann::ordered_json j;
    j["from"] = material_json.string();
    j["unit_weight_n_per_m3"] = material.unit_weight_n_per_m3;
    j["internal_friction_deg"] = material.internal_friction_deg;
    j["cohesion_pa"] = material.cohesion_pa;
    j["soil_tool_friction_deg"] = material.soil_tool_friction_deg;
    j["adhesion_pa"] = material.adhesion_pa;
    j["repose_deg"] = material.repose_deg;
    j["grain_diameter_m"] = tests.mean_grain_diameter_m;
    write_file(dir / "material.json", j.dump(2) + "\n");
  }
  md << "terracut's soil comes from the DEM sand's own material tests only "
        "(`validation/dem/results/material.json`, " << tests.seeds << " seeds), as `terracut calibrate --tests` "
        "gives it (one standard uncertainty after +-), never from the bulldozing runs it is compared with:\n\n"
     << "| quantity | DEM test (mean +- seeds' std) | terracut's material |\n|---|---|---|\n"
     << "| bulk density | poured bed: " << fmt("%.0f", tests.bulk_density_kg_per_m3) << " +- "
     << fmt("%.0f", tests.bulk_density_std) << " kg/m^3 | unit weight "
     << plus_minus("unit_weight_n_per_m3", "%.0f") << " N/m^3 |\n"
     << "| internal friction | shear cell, peak Mohr-Coulomb fit per seed: " << fmt("%.1f", tests.friction_peak_deg)
     << " +- " << fmt("%.1f", tests.friction_peak_std_deg) << " deg (critical state "
     << fmt("%.1f", tests.friction_residual_deg) << " deg) | " << plus_minus("internal_friction_deg", "%.1f")
     << " deg (every seed's tests on one line) |\n"
     << "| cohesion | its intercept: " << fmt("%.0f", tests.cohesion_peak_pa) << " +- "
     << fmt("%.0f", tests.cohesion_peak_std_pa) << " Pa (critical state " << fmt("%.0f", tests.cohesion_residual_pa)
     << " Pa) | " << plus_minus("cohesion_pa", "%.0f") << " Pa |\n"
     << "| soil-tool friction | grains on a sliding steel plate: " << fmt("%.1f", tests.soil_tool_friction_deg)
     << " deg | " << plus_minus("soil_tool_friction_deg", "%.2f") << " deg, no adhesion |\n"
     << "| angle of repose | lifted cylinder: " << fmt("%.1f", tests.repose_deg) << " +- "
     << fmt("%.1f", tests.repose_std_deg) << " deg | " << plus_minus("repose_deg", "%.1f") << " deg |\n\n";
  if (runs.empty()) {
    md << "No bulldozing run under `" << (results_dir / "bulldoze").string() << "` yet.\n";
    section.markdown = md.str();
    return section;
  }

  std::vector<RunComparison> comparisons, critical_comparisons;
  std::ofstream force(dir / "force.csv"), profiles(dir / "profiles.csv"), windows(dir / "windows.csv");
  if (!force || !profiles || !windows) throw InputError(dir.string() + ": cannot be written");
  force << "case,seed,source,push_m,fx_n,fz_n\n";
  profiles << "case,seed,push_mm,x_m,dem_m,terracut_m,initial_m\n";
  windows << "case,seed,start_m,end_m,dem_fx_n,terracut_fx_n,dem_fz_n,terracut_fz_n,dem_pile_m3,"
             "terracut_pile_m3,dem_peak_m,terracut_peak_m,profile_rms_m\n";
  for (const DemRun& run : runs) {
    const TerracutRun tc = run_terracut(run, material);
    comparisons.push_back(compare(run, tc));
    critical_comparisons.push_back(compare(run, run_terracut(run, critical)));
    const RunComparison& c = comparisons.back();
    say("DEM " + run.case_name + " seed " + std::to_string(run.seed) + ": last 0.1 m DEM " +
        fmt("%.1f", c.windows.back().dem_fx_n) + " N, terracut " + fmt("%.1f", c.windows.back().terracut_fx_n) +
        " N; terracut " + fmt("%.3f", tc.cpu_s) + " s of CPU against the DEM's " +
        (run.cpu_s > 0.0 ? fmt("%.0f", run.cpu_s) + " s" : "(not recorded; wall " + fmt("%.0f", run.wall_s) + " s)"));
    for (std::size_t i = 0; i < run.push_m.size(); ++i)
      force << run.case_name << "," << run.seed << ",dem," << run.push_m[i] << "," << run.fx_n[i] << ","
            << run.fz_n[i] << "\n";
    // terracut's force every 2.5 ms as the DEM's (the mean over its steps).
    const std::size_t every = std::max<std::size_t>(1, std::size_t(std::lround(0.0025 * 1000.0)));
    for (std::size_t i = 0; i + every <= tc.push_m.size(); i += every) {
      double fx = 0.0, fz = 0.0;
      for (std::size_t k = i; k < i + every; ++k) {
        fx += tc.fx_n[k];
        fz += tc.fz_n[k];
      }
      force << run.case_name << "," << run.seed << ",terracut," << tc.push_m[i + every / 2] << ","
            << fx / double(every) << "," << fz / double(every) << "\n";
    }
    // The surfaces after the whole push, for the maps (float32, rows along
    // the DEM's y): the DEM's, terracut's, and the bed before the push.
    const int last_mm = int(std::lround(run.push_total_m * 1000.0));
    if (run.surface_at_push_mm.count(last_mm) && tc.surface_at_push_mm.count(last_mm)) {
      const fs::path maps = dir / "maps";
      create_output_folder(maps);
      const std::string stem = run.case_name + "_seed" + std::to_string(run.seed);
      io::write_npy(maps / (stem + "_initial.npy"), run.surface_initial.data(), run.rows, run.cols);
      io::write_npy(maps / (stem + "_dem.npy"), run.surface_at_push_mm.at(last_mm).data(), run.rows, run.cols);
      io::write_npy(maps / (stem + "_terracut.npy"), tc.surface_at_push_mm.at(last_mm).data(), run.rows, run.cols);
    }
    const double yc = 0.5 * (run.blade_y_from_m + run.blade_y_to_m);
    const std::vector<double> init = centre_line(run.surface_initial, run.rows, run.cols, run.cell_m, yc);
    for (const auto& [mm, grid] : run.surface_at_push_mm) {
      const auto t = tc.surface_at_push_mm.find(mm);
      if (t == tc.surface_at_push_mm.end()) continue;
      const std::vector<double> a = centre_line(grid, run.rows, run.cols, run.cell_m, yc);
      const std::vector<double> b = centre_line(t->second, run.rows, run.cols, run.cell_m, yc);
      for (int i = 0; i < run.cols; ++i)
        profiles << run.case_name << "," << run.seed << "," << mm << "," << (i + 0.5) * run.cell_m << ","
                 << a[std::size_t(i)] << "," << b[std::size_t(i)] << "," << init[std::size_t(i)] << "\n";
    }
    for (const WindowComparison& w : c.windows)
      windows << run.case_name << "," << run.seed << "," << w.start_m << "," << w.end_m << "," << w.dem_fx_n << ","
              << w.terracut_fx_n << "," << w.dem_fz_n << "," << w.terracut_fz_n << "," << w.dem_pile_m3 << ","
              << w.terracut_pile_m3 << "," << w.dem_peak_m << "," << w.terracut_peak_m << "," << w.profile_rms_m
              << "\n";
  }

  const std::vector<CaseSummary> cases = summarize(comparisons, tests.mean_grain_diameter_m);
  const std::vector<CaseSummary> critical_cases = summarize(critical_comparisons, tests.mean_grain_diameter_m);
  std::ofstream cases_csv(dir / "cases.csv");
  if (!cases_csv) throw InputError((dir / "cases.csv").string() + ": cannot be written");
  cases_csv << "case,seeds,start_m,end_m,dem_fx_n,dem_fx_std_n,terracut_fx_n,force_error,force_met,dem_fz_n,terracut_fz_n,"
               "dem_pile_m3,dem_pile_std_m3,terracut_pile_m3,pile_error,pile_met,dem_peak_m,terracut_peak_m,"
               "profile_rms_m,profile_met\n";
  md << "Each case with the DEM's mean +- its scatter over the seeds (sample standard deviation) and "
        "terracut's mean over the same beds. Targets: the mean horizontal force of each 0.1 m of push "
        "and the soil ahead of the blade within " << fmt("%.0f", 100 * kForceTarget)
     << " % of the DEM's (or its scatter, when larger), the centre line within one grain diameter ("
     << fmt("%.0f", tests.mean_grain_diameter_m * 1000) << " mm) RMS, the force's growth with the distance "
     << "pushed within " << fmt("%.0f", 100 * kSlopeTarget) << " %, at least " << fmt("%.0f", kSpeedTarget)
     << " times faster.\n\n";
  for (const CaseSummary& c : cases) {
    md << "### " << c.case_name << " (" << c.seeds << " seed" << (c.seeds == 1 ? "" : "s") << ")\n\n"
       << "| push (m) | DEM force (N) | terracut (N) | error | target | vertical, DEM / terracut (N, + up) | "
          "DEM ahead (l) | terracut (l) | error | target | DEM peak (mm) | terracut (mm) | centre line RMS (mm) | "
          "target |\n"
       << "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (const CaseSummary::Window& w : c.windows) {
      md << "| " << fmt("%.1f", w.start_m) << "-" << fmt("%.1f", w.end_m) << " | " << fmt("%.1f", w.dem_fx_n)
         << " +- " << fmt("%.1f", w.dem_fx_std_n) << " | " << fmt("%.1f", w.terracut_fx_n) << " | "
         << pct(w.force_error) << " | " << verdict(w.force_met) << " | " << fmt("%.1f", w.dem_fz_n) << " / "
         << fmt("%.1f", w.terracut_fz_n) << " | " << fmt("%.2f", w.dem_pile_m3 * 1e3)
         << " +- " << fmt("%.2f", w.dem_pile_std_m3 * 1e3) << " | " << fmt("%.2f", w.terracut_pile_m3 * 1e3)
         << " | " << pct(w.pile_error) << " | " << verdict(w.pile_met) << " | " << fmt("%.1f", w.dem_peak_m * 1e3)
         << " | " << fmt("%.1f", w.terracut_peak_m * 1e3) << " | " << fmt("%.1f", w.profile_rms_m * 1e3) << " | "
         << verdict(w.profile_met) << " |\n";
      if (!w.has_surface) {
        // Not measured: said, not judged (the table's surface cells read 0).
        md << "| | (no surfaces at " << fmt("%.1f", w.end_m) << " m: the soil ahead and the centre line are not "
              "judged) |\n";
      }
      cases_csv << c.case_name << "," << c.seeds << "," << w.start_m << "," << w.end_m << "," << w.dem_fx_n << ","
                << w.dem_fx_std_n << "," << w.terracut_fx_n << "," << w.force_error << "," << int(w.force_met) << ","
                << w.dem_fz_n << "," << w.terracut_fz_n << ","
                << w.dem_pile_m3 << "," << w.dem_pile_std_m3 << "," << w.terracut_pile_m3 << "," << w.pile_error
                << "," << int(w.pile_met) << "," << w.dem_peak_m << "," << w.terracut_peak_m << ","
                << w.profile_rms_m << "," << int(w.profile_met) << "\n";
      section.targets += w.has_surface ? 3 : 1;
      section.met += int(w.force_met) + int(w.pile_met) + int(w.profile_met);
    }
    md << "\nThe force's growth from 0.1 m on: DEM " << fmt("%.0f", c.dem_slope_n_per_m) << " +- "
       << fmt("%.0f", c.dem_slope_std_n_per_m) << " N/m, terracut " << fmt("%.0f", c.terracut_slope_n_per_m)
       << " N/m (" << pct(c.slope_error) << ", " << verdict(c.slope_met) << "). Time (lowering, hold and push; "
       << "terracut's relaxation uncapped): ";
    if (c.speedup_in_cpu_time)
      md << "the DEM " << fmt("%.0f", c.dem_cpu_s) << " s of CPU, terracut " << fmt("%.3f", c.terracut_cpu_s)
         << " s of CPU"
         << (c.cpu_runs < c.seeds
                 ? " (the " + std::to_string(c.cpu_runs) + " of " + std::to_string(c.seeds) +
                       " runs whose DEM recorded its CPU time)"
                 : std::string());
    else
      md << "the DEM " << fmt("%.0f", c.dem_wall_s) << " s of wall clock (its CPU time was not recorded), terracut "
         << fmt("%.3f", c.terracut_wall_s) << " s of wall clock on the same machine";
    md << ": " << fmt("%.0f", c.speedup) << " times faster (" << verdict(c.speed_met) << ").";
    for (const CaseSummary& k : critical_cases)
      if (k.case_name == c.case_name) {
        md << " With the critical state's friction and cohesion instead of the peak's ("
           << fmt("%.1f", critical.internal_friction_deg) << " degrees, " << fmt("%.0f", critical.cohesion_pa)
           << " Pa; a sensitivity, not a target), terracut's force per window:";
        for (const CaseSummary::Window& w : k.windows) md << " " << fmt("%.1f", w.terracut_fx_n) << " N";
        md << " (" << pct(k.windows.back().force_error) << " in the last).";
      }
    md << "\n\n";
    section.targets += 2;
    section.met += int(c.slope_met) + int(c.speed_met);
  }
  md << "Targets met: " << section.met << " of " << section.targets << ". Figures: `soil_dem_force.png` "
        "(force against the distance pushed), `soil_dem_profiles.png` (the centre line), "
        "`soil_dem_piles.png` (the soil ahead of the blade), `soil_dem_maps.png` (the surfaces after the push), "
        "`soil_dem_sections.png` (the surfaces across the push, ahead of the blade and behind it).\n\n"
     << "![force against distance pushed](soil_dem_force.png)\n\n![centre lines](soil_dem_profiles.png)\n\n"
        "![the soil ahead of the blade](soil_dem_piles.png)\n\n![the surfaces after the push](soil_dem_maps.png)\n\n"
        "![the surfaces across the push](soil_dem_sections.png)\n";
  section.markdown = md.str();
  return section;
}

}  // namespace terracut::cli
