// terracut measured against a DEM (LIGGGHTS) reference: the DEM's own
// material tests give terracut its soil material, and terracut runs each
// DEM bulldozing case (the same bed surface, blade, depth and motion) so
// that the two can be compared window by window: the force on the blade
// against the distance pushed, the soil ahead of the blade, the centre line.
//
// The reference lives in the repository (validation/dem/, its README gives
// every parameter and how each number was measured); the files read here:
//   results/material.json                  the material tests (per seed, mean, std)
//   results/bulldoze/<case>/seed<k>/run.json, force.csv, surface_*.npy
// Frames: the DEM's x (push), y (across), z (up) are terracut's X, Z, Y. A
// DEM force is the grains' force ON the blade, as terracut's physical force.
#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "terracut/core/material.hpp"
#include "terracut/core/simulation.hpp"
#include "terracut/validation/calibrate.hpp"

namespace terracut::validation {

/// The DEM sand's own material tests (results/material.json): mean and
/// sample standard deviation over the seeds.
struct DemMaterialTests {
  double repose_deg = 0.0, repose_std_deg = 0.0;                  ///< lifted cylinder
  double bulk_density_kg_per_m3 = 0.0, bulk_density_std = 0.0;     ///< poured bed
  double friction_peak_deg = 0.0, friction_peak_std_deg = 0.0;     ///< shear cell, Mohr-Coulomb fit
  double cohesion_peak_pa = 0.0, cohesion_peak_std_pa = 0.0;       ///< the fit's intercept
  double friction_residual_deg = 0.0, cohesion_residual_pa = 0.0;  ///< at the critical state
  double soil_tool_friction_deg = 0.0, soil_tool_friction_std_deg = 0.0;  ///< grains on a sliding steel plate
  double mean_grain_diameter_m = 0.01;                             ///< the grains' mean diameter
  int seeds = 0;
};

/// Reads results/material.json. Throws InputError naming the file and the
/// missing or bad field.
DemMaterialTests read_dem_material(const std::filesystem::path& json);

// terracut's soil material comes from the DEM's tests alone (never from the
// bulldozing runs it is compared with), as `terracut calibrate --tests
// results/material.json` gives it (calibrate.hpp: the Mohr-Coulomb line of
// every seed's shear tests at the peak, the plate tests' soil-tool
// friction, the mean density and repose; no adhesion, the grains are dry).

/// The comparison's window of push, m: the DEM writes its surface after
/// every 0.1 m, and each window's force is a mean over it.
inline constexpr double kDemWindow_m = 0.1;

/// One DEM bulldozing run (a case and a seed).
struct DemRun {
  std::string case_name;
  int seed = 0;
  double blade_width_m = 0.0;
  double rake_deg = 90.0;
  double depth_m = 0.0;            ///< the tip's depth below the mean initial surface
  double initial_surface_mean_m = 0.0;
  double tip_x_start_m = 0.0;      ///< the tip line at the push's start, DEM x
  double tip_z_start_m = 0.0;      ///< and its height above the floor
  double blade_y_from_m = 0.0, blade_y_to_m = 0.0;  ///< its span across
  double lowering_start_x_m = 0.0, lowering_start_z_m = 0.0;
  double lowering_speed_m_per_s = 0.0;
  double hold_s = 0.0;
  double push_speed_m_per_s = 0.0;
  double push_total_m = 0.0;
  double wall_s = 0.0;             ///< the DEM's own wall-clock time for the run (one core)
  double cpu_s = 0.0;              ///< its process's CPU time; 0 when the run did not record it
  double rear_offset_m = 0.0;      ///< x of the plate's rear top edge from the tip (< 0 for a raked blade)
  int particles = 0;
  // The surfaces: float32 (rows along y) x (cols along x), cell_m, origin at
  // the box corner; metres above the bed floor.
  int rows = 0, cols = 0;
  double cell_m = 0.005;
  std::vector<float> surface_initial;
  std::map<int, std::vector<float>> surface_at_push_mm;  ///< after 0 mm and every window's end
  // The force on the blade during the push (2.5 ms means), DEM frame.
  std::vector<double> push_m, fx_n, fy_n, fz_n;
};

/// Every run under results/bulldoze (case folders holding seed<k>/run.json),
/// sorted by case then seed. Throws InputError naming a file that cannot be
/// read, a field that is missing or of the wrong type, a run whose blade or
/// push does not fit its bed, a missing surface (one per kDemWindow_m of
/// push) or a force record that does not cover the push.
std::vector<DemRun> read_dem_runs(const std::filesystem::path& results_dir);

/// One run's folder (results/bulldoze/<case>/seed<k>). Throws as read_dem_runs.
DemRun read_dem_run(const std::filesystem::path& run_dir);

/// A DEM run replayed in terracut: the simulation's parameters (the bed's
/// grid, the blade, soil that flows with the material given, the
/// relaxation uncapped), the bed, and the blade's pose at every step at
/// rate_hz: the lowering, the hold, the push (from push_first on).
struct DemReplay {
  SimParams params;
  std::vector<float> heights;
  std::vector<BladePose> poses;
  std::size_t push_first = 0;
};
DemReplay dem_replay(const DemRun& run, const SoilMaterial& material, double rate_hz = 1000.0);

/// The DEM run as a force record along the replay's poses (calibrate.hpp):
/// the DEM's force during the push, linear between its 2.5 ms means, in
/// terracut's frame; zero before the push (fit with from_t_s at the push's
/// start: push_first / rate).
ForceRecord dem_force_record(const DemRun& run, const DemReplay& replay);

/// terracut on a DEM run: the same bed surface (the DEM's initial upper
/// envelope as the heights, its 5 mm cells), the blade (width, rake, a thin
/// edge), the same lowering, hold and push, soil that flows with the
/// material given, at rate_hz.
struct TerracutRun {
  std::vector<double> push_m, fx_n, fy_n, fz_n;  ///< per step of the push, DEM frame
  std::map<int, std::vector<float>> surface_at_push_mm;  ///< heights as the DEM's grids
  double wall_s = 0.0;       ///< the whole run (lowering, hold, push), wall clock
  double cpu_s = 0.0;        ///< the same in the process's CPU time
  double push_wall_s = 0.0;  ///< the push alone
  std::int64_t steps = 0;
};
TerracutRun run_terracut(const DemRun& run, const SoilMaterial& material, double rate_hz = 1000.0);

/// The comparison of one window of push (start_m, end_m].
struct WindowComparison {
  double start_m = 0.0, end_m = 0.0;
  double dem_fx_n = 0.0, terracut_fx_n = 0.0;  ///< mean horizontal force resisting the push (> 0)
  double dem_fz_n = 0.0, terracut_fz_n = 0.0;  ///< mean vertical force on the blade (+ up)
  /// The surfaces at the window's end, on both sides; false: the three
  /// below are not measured and the window's surface targets are not judged.
  bool has_surface = false;
  /// Net rise over the initial surface ahead of the tip line at the window's
  /// end (and, for a raked blade, over the plate: the DEM's own region).
  double dem_pile_m3 = 0.0, terracut_pile_m3 = 0.0;
  double dem_peak_m = 0.0, terracut_peak_m = 0.0;    ///< the highest point there above the mean initial surface
  /// The centre line's RMS difference at the window's end, over the span
  /// either surface disturbed (departing from the initial by more than a
  /// quarter of the cut depth, and every column between).
  double profile_rms_m = 0.0;
};

/// A run's comparison: per 0.1 m window, and the force's growth with the
/// distance pushed (the slope of a least-squares line through the steps'
/// horizontal force, N/m, from the first window's end on).
struct RunComparison {
  std::string case_name;
  int seed = 0;
  std::vector<WindowComparison> windows;
  double dem_slope_n_per_m = 0.0, terracut_slope_n_per_m = 0.0;
  double dem_wall_s = 0.0, terracut_wall_s = 0.0;
  double dem_cpu_s = 0.0, terracut_cpu_s = 0.0;  ///< 0 for the DEM when its run did not record it
};
RunComparison compare(const DemRun& dem, const TerracutRun& terracut, double window_m = kDemWindow_m);

/// The targets terracut is held to against the DEM (docs/validation.md):
/// each 0.1 m window's mean horizontal force and the soil ahead of the blade
/// within 15 % of the DEM's mean (or its seed scatter, when larger); the
/// centre line within one grain diameter RMS; the force's growth with the
/// distance pushed within 25 %; at least 1000 times faster.
inline constexpr double kForceTarget = 0.15;
inline constexpr double kPileTarget = 0.15;
inline constexpr double kSlopeTarget = 0.25;
inline constexpr double kSpeedTarget = 1000.0;

/// A case over its seeds: the DEM's mean and sample standard deviation,
/// terracut's mean (terracut ran on each seed's own bed), the relative
/// errors and whether each target is met.
struct CaseSummary {
  std::string case_name;
  int seeds = 0;
  struct Window {
    double start_m = 0.0, end_m = 0.0;
    double dem_fx_n = 0.0, dem_fx_std_n = 0.0, terracut_fx_n = 0.0, force_error = 0.0;
    bool force_met = false;
    double dem_pile_m3 = 0.0, dem_pile_std_m3 = 0.0, terracut_pile_m3 = 0.0, pile_error = 0.0;
    bool pile_met = false;
    double dem_fz_n = 0.0, terracut_fz_n = 0.0;  ///< mean vertical force (+ up), informative
    bool has_surface = false;  ///< false: pile, peak and profile not measured, not judged
    double dem_peak_m = 0.0, terracut_peak_m = 0.0;
    double profile_rms_m = 0.0;
    bool profile_met = false;
  };
  std::vector<Window> windows;
  double dem_slope_n_per_m = 0.0, dem_slope_std_n_per_m = 0.0, terracut_slope_n_per_m = 0.0;
  double slope_error = 0.0;
  bool slope_met = false;
  /// The speed-up in CPU time over the runs whose DEM recorded it (a shared
  /// machine's wall clock counts the time a process waits; dem_cpu_s and
  /// terracut_cpu_s are the means over those cpu_runs runs), else, when none
  /// did, in wall time over every run.
  double dem_wall_s = 0.0, terracut_wall_s = 0.0, dem_cpu_s = 0.0, terracut_cpu_s = 0.0, speedup = 0.0;
  bool speedup_in_cpu_time = false;
  int cpu_runs = 0;  ///< runs whose DEM recorded its CPU time
  bool speed_met = false;
};

/// The runs' comparisons grouped by case (sorted), over their seeds;
/// grain_diameter_m is the profile's target.
std::vector<CaseSummary> summarize(const std::vector<RunComparison>& runs, double grain_diameter_m);

/// The centre line (y at the blade's centre) of a grid, one height per column.
std::vector<double> centre_line(const std::vector<float>& grid, int rows, int cols, double cell_m,
                                double y_m);

}  // namespace terracut::validation
