// terracut against the DEM reference. See dem.hpp; the reference's own
// documentation is validation/dem/README.md.
#include "terracut/validation/dem.hpp"

#include <algorithm>
#include <chrono>
#include <ctime>
#include <cmath>
#include <fstream>
#include <limits>
#include <numbers>
#include <nlohmann/json.hpp>
#include <sstream>

#include "terracut/core/error.hpp"
#include "terracut/core/format.hpp"
#include "terracut/core/simulation.hpp"
#include "terracut/io/image.hpp"

namespace terracut::validation {

namespace fs = std::filesystem;
using Json = nlohmann::json;

namespace {

Json read_json(const fs::path& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path.string() + ": cannot be read");
  try {
    return Json::parse(in);
  } catch (const Json::exception& e) {
    throw InputError(path.string() + ": not valid JSON: " + e.what());
  }
}

// A number at a dotted path of a JSON document, named in the error.
double number(const Json& j, const std::string& path, const fs::path& file) {
  const Json* at = &j;
  std::stringstream s(path);
  for (std::string key; std::getline(s, key, '.');) {
    if (!at->is_object() || !at->contains(key))
      throw InputError(file.string() + ": " + path + ": missing");
    at = &(*at)[key];
  }
  if (!at->is_number()) throw InputError(file.string() + ": " + path + ": expected a number");
  const double v = at->get<double>();
  if (!std::isfinite(v)) throw InputError(file.string() + ": " + path + ": not finite");
  return v;
}

std::vector<float> read_grid(const fs::path& path, int rows, int cols) {
  int r = 0, c = 0;
  std::vector<float> v = io::read_npy(path, &r, &c);
  if (r != rows || c != cols)
    throw InputError(path.string() + ": expected " + std::to_string(rows) + " x " + std::to_string(cols) +
                     " (rows along y, columns along x), got " + std::to_string(r) + " x " + std::to_string(c));
  for (float h : v)
    if (!std::isfinite(h)) throw InputError(path.string() + ": a height is not finite");
  return v;
}

// force.csv: t_s,push_m,fx_n,fy_n,fz_n.
void read_force(const fs::path& path, DemRun& run) {
  std::ifstream in(path);
  if (!in) throw InputError(path.string() + ": cannot be read");
  std::string line;
  std::getline(in, line);
  if (line.rfind("t_s,push_m,fx_n,fy_n,fz_n", 0) != 0)
    throw InputError(path.string() + ": expected the header t_s,push_m,fx_n,fy_n,fz_n");
  int row = 1;
  while (std::getline(in, line)) {
    ++row;
    if (line.empty()) continue;
    double v[5];
    std::stringstream s(line);
    std::string cell;
    for (double& x : v) {
      if (!std::getline(s, cell, ',')) throw InputError(path.string() + ":" + std::to_string(row) + ": 5 numbers expected");
      try {
        std::size_t used = 0;
        x = std::stod(cell, &used);
        if (used != cell.size() || !std::isfinite(x)) throw std::invalid_argument("");
      } catch (const std::exception&) {
        throw InputError(path.string() + ":" + std::to_string(row) + ": '" + cell + "' is not a finite number");
      }
    }
    if (!run.push_m.empty() && !(v[1] > run.push_m.back()))
      throw InputError(path.string() + ":" + std::to_string(row) + ": push_m must increase");
    run.push_m.push_back(v[1]);
    run.fx_n.push_back(v[2]);
    run.fy_n.push_back(v[3]);
    run.fz_n.push_back(v[4]);
  }
  if (run.push_m.empty()) throw InputError(path.string() + ": no rows");
}

// A number at a dotted path that must lie in [lo, hi].
double number_in(const Json& j, const std::string& path, const fs::path& file, double lo, double hi) {
  const double v = number(j, path, file);
  if (!(v >= lo && v <= hi))
    throw InputError(file.string() + ": " + path + ": " + format_number(v) + " is outside [" + format_number(lo) +
                     ", " + format_number(hi) + "]");
  return v;
}

DemRun read_run_json(const fs::path& dir) {
  const fs::path file = dir / "run.json";
  const Json j = read_json(file);
  DemRun r;
  r.case_name = dir.parent_path().filename().string();
  if (j.contains("case")) {
    if (!j["case"].is_string()) throw InputError(file.string() + ": case: expected a name");
    r.case_name = j["case"].get<std::string>();
  }
  r.seed = int(number_in(j, "seed", file, 0, 1e9));
  r.cell_m = number_in(j, "surfaces.cell_m", file, 1e-4, 1.0);
  const Json* shape = j.contains("surfaces") && j["surfaces"].is_object() && j["surfaces"].contains("shape_rows_cols")
                          ? &j["surfaces"]["shape_rows_cols"]
                          : nullptr;
  if (!shape || !shape->is_array() || shape->size() != 2 || !(*shape)[0].is_number_integer() ||
      !(*shape)[1].is_number_integer())
    throw InputError(file.string() + ": surfaces.shape_rows_cols: expected [rows, cols], two whole numbers");
  r.rows = (*shape)[0].get<int>();
  r.cols = (*shape)[1].get<int>();
  if (r.rows < 2 || r.cols < 2 || std::int64_t(r.rows) * r.cols > 100000000)
    throw InputError(file.string() + ": surfaces.shape_rows_cols: " + std::to_string(r.rows) + " x " +
                     std::to_string(r.cols) + " is not a grid (2 x 2 to 1e8 cells)");
  const double length_x = r.cols * r.cell_m, width_y = r.rows * r.cell_m;
  r.blade_width_m = number_in(j, "blade.width_m", file, r.cell_m, width_y);
  r.rake_deg = number_in(j, "blade.rake_deg", file, 1.0, 179.0);
  r.depth_m = number_in(j, "blade.depth_m", file, 1e-4, 10.0);
  r.initial_surface_mean_m = number_in(j, "bed.initial_surface_mean_m", file, 1e-4, 100.0);
  r.tip_x_start_m = number_in(j, "blade.tip_line_at_push_start.x_m", file, 0.0, length_x);
  r.tip_z_start_m = number_in(j, "blade.tip_line_at_push_start.z_m", file, 0.0, 100.0);
  r.blade_y_from_m = number_in(j, "blade.tip_line_at_push_start.y_from_m", file, 0.0, width_y);
  r.blade_y_to_m = number_in(j, "blade.tip_line_at_push_start.y_to_m", file, 0.0, width_y);
  if (!(r.blade_y_to_m > r.blade_y_from_m) ||
      std::abs((r.blade_y_to_m - r.blade_y_from_m) - r.blade_width_m) > r.cell_m)
    throw InputError(file.string() + ": blade.tip_line_at_push_start: the span y_from_m..y_to_m is not the blade's "
                     "width (" + format_number(r.blade_width_m) + " m)");
  r.lowering_start_x_m = number_in(j, "blade.tip_line_at_lowering_start.x_m", file, 0.0, length_x);
  r.lowering_start_z_m = number_in(j, "blade.tip_line_at_lowering_start.z_m", file, 0.0, 100.0);
  r.lowering_speed_m_per_s = number_in(j, "motion.lowering_speed_m_per_s", file, 1e-4, 10.0);
  r.hold_s = number_in(j, "motion.hold_s", file, 0.0, 10.0);
  r.push_speed_m_per_s = number_in(j, "motion.push_speed_m_per_s", file, 1e-4, 10.0);
  r.push_total_m = number_in(j, "motion.push_total_m", file, kDemWindow_m, length_x - r.tip_x_start_m);
  r.wall_s = number_in(j, "wall_clock_s", file, 0.0, 1e9);
  if (j.contains("cpu_s")) r.cpu_s = number_in(j, "cpu_s", file, 0.0, 1e9);
  if (j.contains("blade") && j["blade"].is_object() && j["blade"].contains("rear_top_edge_x_offset_m"))
    r.rear_offset_m = number_in(j, "blade.rear_top_edge_x_offset_m", file, -length_x, 0.0);
  r.particles = int(number_in(j, "bed.particles", file, 0, 1e9));
  // The lowering must take a sensible time (a million steps at 1 kHz at most).
  const double lower_m = std::hypot(r.tip_x_start_m - r.lowering_start_x_m, r.tip_z_start_m - r.lowering_start_z_m);
  if (lower_m / r.lowering_speed_m_per_s > 1000.0 || r.push_total_m / r.push_speed_m_per_s > 1000.0)
    throw InputError(file.string() + ": motion: the lowering or the push lasts more than 1000 s");
  return r;
}

DemRun read_run(const fs::path& dir) {
  DemRun r;
  try {
    r = read_run_json(dir);
  } catch (const Json::exception& e) {
    throw InputError((dir / "run.json").string() + ": " + e.what());
  }
  r.surface_initial = read_grid(dir / "surface_initial.npy", r.rows, r.cols);
  // A surface after every window of push (and at its start, when written).
  const int windows = int(std::lround(r.push_total_m / kDemWindow_m));
  for (int k = 0; k <= windows; ++k) {
    const int mm = int(std::lround(k * kDemWindow_m * 1000.0));
    const fs::path f = dir / ("surface_" + std::to_string(mm) + ".npy");
    if (fs::exists(f)) r.surface_at_push_mm[mm] = read_grid(f, r.rows, r.cols);
    else if (k > 0) throw InputError(f.string() + ": missing (the surface after " + std::to_string(mm) + " mm of push)");
  }
  read_force(dir / "force.csv", r);
  // The force record covers the push: a row within 2 % of it at each end.
  const double slack = 0.02 * r.push_total_m;
  if (r.push_m.front() > slack || r.push_m.back() < r.push_total_m - slack)
    throw InputError((dir / "force.csv").string() + ": covers " + format_number(r.push_m.front()) + " to " +
                     format_number(r.push_m.back()) + " m of push, not the run's 0 to " +
                     format_number(r.push_total_m) + " m");
  return r;
}

DemMaterialTests read_dem_material_json(const fs::path& json) {
  const Json j = read_json(json);
  DemMaterialTests t;
  t.repose_deg = number(j, "repose_deg", json);
  t.repose_std_deg = number(j, "repose_std_deg", json);
  t.bulk_density_kg_per_m3 = number(j, "bulk_density_kg_per_m3", json);
  t.bulk_density_std = number(j, "bulk_density_std_kg_per_m3", json);
  t.friction_peak_deg = number(j, "internal_friction_peak_deg", json);
  t.friction_peak_std_deg = number(j, "internal_friction_peak_std_deg", json);
  t.cohesion_peak_pa = number(j, "cohesion_pa", json);
  t.cohesion_peak_std_pa = number(j, "cohesion_std_pa", json);
  t.friction_residual_deg = number(j, "internal_friction_residual_deg", json);
  t.cohesion_residual_pa = number(j, "cohesion_residual_pa", json);
  t.soil_tool_friction_deg = number(j, "soil_tool_friction_deg", json);
  t.soil_tool_friction_std_deg = number(j, "soil_tool_friction_std_deg", json);
  t.mean_grain_diameter_m = number(j, "parameters.particle.radius_min_m", json) +
                            number(j, "parameters.particle.radius_max_m", json);
  t.seeds = j.contains("seeds") && j["seeds"].is_array() ? int(j["seeds"].size()) : 0;
  return t;
}

}  // namespace

DemMaterialTests read_dem_material(const fs::path& json) {
  try {
    return read_dem_material_json(json);
  } catch (const Json::exception& e) {
    throw InputError(json.string() + ": " + e.what());
  }
}


DemRun read_dem_run(const fs::path& run_dir) {
  if (!fs::exists(run_dir / "run.json"))
    throw InputError(run_dir.string() + ": not a DEM run (no run.json; validation/dem/README.md)");
  return read_run(run_dir);
}

std::vector<DemRun> read_dem_runs(const fs::path& results_dir) {
  std::vector<DemRun> runs;
  const fs::path root = results_dir / "bulldoze";
  if (!fs::is_directory(root)) return runs;
  std::vector<fs::path> dirs;
  for (const auto& c : fs::directory_iterator(root)) {
    if (!c.is_directory()) continue;
    for (const auto& s : fs::directory_iterator(c.path()))
      if (s.is_directory() && fs::exists(s.path() / "run.json")) dirs.push_back(s.path());
  }
  std::sort(dirs.begin(), dirs.end());
  for (const fs::path& d : dirs) runs.push_back(read_run(d));
  return runs;
}

DemReplay dem_replay(const DemRun& dem, const SoilMaterial& material, double rate_hz) {
  DemReplay r;
  // The DEM's grid as the terrain: DEM x -> X (columns), y -> Z (rows).
  SimParams& p = r.params;
  p.grid.cols = dem.cols;
  p.grid.rows = dem.rows;
  p.grid.size_x_m = dem.cols * dem.cell_m;
  p.grid.size_z_m = dem.rows * dem.cell_m;
  p.grid.full_scale_m = std::max(0.2, 2.0 * dem.initial_surface_mean_m);
  p.rate_hz = rate_hz;
  p.blade.length_m = dem.blade_width_m;
  p.blade.rake_angle_deg = dem.rake_deg;
  p.blade.edge_thickness_m = 0.005;  // the DEM's plate has none: half a grain's width of bearing
  p.soil.model = SoilModel::kFlow;
  p.soil.material = material;
  p.soil.max_pair_checks_per_step = 1000000000;  // an offline comparison: the converged model
  r.heights = dem.surface_initial;

  // The edge along Z (the DEM's y), centred on the blade's span.
  const double z_centre = 0.5 * (dem.blade_y_from_m + dem.blade_y_to_m);
  const Quat along_z = quat_from_euler_deg({0.0, -90.0, 0.0});
  const auto pose = [&](double x, double y) { return BladePose{{x, y, z_centre}, along_z}; };
  // Lowering: from the DEM's start to the push's start, at its speed.
  const double lx = dem.tip_x_start_m - dem.lowering_start_x_m, ly = dem.tip_z_start_m - dem.lowering_start_z_m;
  const double lower_m = std::hypot(lx, ly);
  const std::int64_t n_lower =
      std::max<std::int64_t>(1, std::llround(lower_m / dem.lowering_speed_m_per_s * rate_hz));
  for (std::int64_t i = 0; i <= n_lower; ++i) {
    const double f = double(i) / double(n_lower);
    r.poses.push_back(pose(dem.lowering_start_x_m + f * lx, dem.lowering_start_z_m + f * ly));
  }
  const std::int64_t n_hold = std::llround(dem.hold_s * rate_hz);
  for (std::int64_t i = 0; i < n_hold; ++i) r.poses.push_back(pose(dem.tip_x_start_m, dem.tip_z_start_m));
  // The push, along +X at the DEM's speed.
  r.push_first = r.poses.size();
  const std::int64_t n_push = std::llround(dem.push_total_m / dem.push_speed_m_per_s * rate_hz);
  for (std::int64_t i = 1; i <= n_push; ++i)
    r.poses.push_back(pose(dem.tip_x_start_m + dem.push_speed_m_per_s * double(i) / rate_hz, dem.tip_z_start_m));
  return r;
}

ForceRecord dem_force_record(const DemRun& dem, const DemReplay& replay) {
  ForceRecord rec;
  const double rate = replay.params.rate_hz;
  std::size_t k = 0;  // the DEM row at or after the step's push
  for (std::size_t i = 0; i < replay.poses.size(); ++i) {
    rec.t_s.push_back(double(i) / rate);
    rec.pose.push_back(replay.poses[i]);
    Vec3 f{};
    if (i >= replay.push_first) {
      // The DEM's 2.5 ms means, linear between their centres (held past
      // the first and the last), in terracut's frame (DEM y -> Z, z -> Y).
      const double pushed = dem.push_speed_m_per_s * double(i - replay.push_first + 1) / rate;
      while (k < dem.push_m.size() && dem.push_m[k] < pushed) ++k;
      double fx, fy, fz;
      if (k == 0 || k == dem.push_m.size()) {
        const std::size_t at = k == 0 ? 0 : dem.push_m.size() - 1;
        fx = dem.fx_n[at], fy = dem.fy_n[at], fz = dem.fz_n[at];
      } else {
        const double w = (pushed - dem.push_m[k - 1]) / (dem.push_m[k] - dem.push_m[k - 1]);
        fx = (1 - w) * dem.fx_n[k - 1] + w * dem.fx_n[k];
        fy = (1 - w) * dem.fy_n[k - 1] + w * dem.fy_n[k];
        fz = (1 - w) * dem.fz_n[k - 1] + w * dem.fz_n[k];
      }
      f = {fx, fz, fy};
    }
    rec.force_n.push_back(f);
  }
  return rec;
}

TerracutRun run_terracut(const DemRun& dem, const SoilMaterial& material, double rate_hz) {
  const DemReplay replay = dem_replay(dem, material, rate_hz);
  Simulation sim(replay.params, replay.heights);
  TerracutRun out;
  const auto t0 = std::chrono::steady_clock::now();
  const std::clock_t c0 = std::clock();
  for (std::size_t i = 0; i < replay.push_first; ++i) sim.step(replay.poses[i]);
  const auto grid_copy = [&] {
    return std::vector<float>(sim.grid().heights(), sim.grid().heights() + sim.grid().spec().sample_count());
  };
  out.surface_at_push_mm[0] = grid_copy();
  // The push; snapshots at every window's end.
  const auto p0 = std::chrono::steady_clock::now();
  int next_mm = int(std::lround(kDemWindow_m * 1000.0));
  for (std::size_t i = replay.push_first; i < replay.poses.size(); ++i) {
    const double pushed = dem.push_speed_m_per_s * double(i - replay.push_first + 1) / rate_hz;
    const StepOutput& o = sim.step(replay.poses[i]);
    out.push_m.push_back(pushed);
    out.fx_n.push_back(o.force.total_n.x);
    out.fy_n.push_back(o.force.total_n.z);  // the DEM's y is terracut's Z
    out.fz_n.push_back(o.force.total_n.y);
    if (pushed >= next_mm * 1e-3 - 0.25 * dem.push_speed_m_per_s / rate_hz) {
      out.surface_at_push_mm[next_mm] = grid_copy();
      next_mm += int(std::lround(kDemWindow_m * 1000.0));
    }
  }
  const auto t1 = std::chrono::steady_clock::now();
  out.wall_s = std::chrono::duration<double>(t1 - t0).count();
  out.cpu_s = double(std::clock() - c0) / CLOCKS_PER_SEC;
  out.push_wall_s = std::chrono::duration<double>(t1 - p0).count();
  out.steps = sim.step_count();
  return out;
}

std::vector<double> centre_line(const std::vector<float>& grid, int rows, int cols, double cell_m,
                                double y_m) {
  // Linear between the two rows around y (cell centres at (j + 0.5) cell).
  const double fj = std::clamp(y_m / cell_m - 0.5, 0.0, double(rows - 1));
  const int j0 = std::min(int(fj), rows - 2);
  const double w = fj - j0;
  std::vector<double> line(std::size_t(cols), 0.0);
  for (int i = 0; i < cols; ++i)
    line[std::size_t(i)] = (1.0 - w) * grid[std::size_t(j0) * cols + i] + w * grid[std::size_t(j0 + 1) * cols + i];
  return line;
}

namespace {

// Net rise over the initial surface in the DEM's pile region at a tip line
// x = tip_x_m: the cells at or ahead of it (all across) and, for a raked
// blade, the cells over its plate (from the rear top edge, rear_offset_m
// behind the tip, within the blade's span) whose surface lies above the
// plate, the soil carried on its face (validation/dem/bulldoze/bulldoze.py,
// window_metrics), m^3; and the highest point there above the mean initial
// surface, m.
void pile_ahead(const std::vector<float>& now, const DemRun& dem, double tip_x_m, double& volume_m3,
                double& peak_m) {
  volume_m3 = 0.0;
  peak_m = 0.0;
  const double yc = 0.5 * (dem.blade_y_from_m + dem.blade_y_to_m);
  const double tan_rake = dem.rake_deg < 89.999 ? std::tan(dem.rake_deg * std::numbers::pi / 180.0) : 0.0;
  for (int j = 0; j < dem.rows; ++j)
    for (int i = 0; i < dem.cols; ++i) {
      const double x = (i + 0.5) * dem.cell_m, y = (j + 0.5) * dem.cell_m;
      const std::size_t k = std::size_t(j) * dem.cols + i;
      const bool ahead = x >= tip_x_m;
      const bool over_plate = x >= tip_x_m + dem.rear_offset_m && x < tip_x_m &&
                              std::abs(y - yc) <= 0.5 * dem.blade_width_m &&
                              double(now[k]) > dem.tip_z_start_m + (tip_x_m - x) * tan_rake;
      if (!ahead && !over_plate) continue;
      volume_m3 += (double(now[k]) - double(dem.surface_initial[k])) * dem.cell_m * dem.cell_m;
      peak_m = std::max(peak_m, double(now[k]) - dem.initial_surface_mean_m);
    }
}

double mean_of(const std::vector<double>& x, const std::vector<double>& v, double lo, double hi) {
  double s = 0.0;
  int n = 0;
  for (std::size_t i = 0; i < x.size(); ++i)
    if (x[i] > lo && x[i] <= hi) {
      s += v[i];
      ++n;
    }
  return n > 0 ? s / n : std::numeric_limits<double>::quiet_NaN();
}

// The slope of a least-squares line through (x, -v) for x > from, N/m.
double slope_of(const std::vector<double>& x, const std::vector<double>& v, double from) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int n = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    if (!(x[i] > from)) continue;
    sx += x[i];
    sy += -v[i];
    sxx += x[i] * x[i];
    sxy += -x[i] * v[i];
    ++n;
  }
  const double d = n * sxx - sx * sx;
  return n > 1 && d > 0.0 ? (n * sxy - sx * sy) / d : 0.0;
}

}  // namespace

RunComparison compare(const DemRun& dem, const TerracutRun& tc, double window_m) {
  RunComparison c;
  c.case_name = dem.case_name;
  c.seed = dem.seed;
  c.dem_wall_s = dem.wall_s;
  c.terracut_wall_s = tc.wall_s;
  c.dem_cpu_s = dem.cpu_s;
  c.terracut_cpu_s = tc.cpu_s;
  const double y_centre = 0.5 * (dem.blade_y_from_m + dem.blade_y_to_m);
  const std::vector<double> initial = centre_line(dem.surface_initial, dem.rows, dem.cols, dem.cell_m, y_centre);
  const int windows = std::max(1, int(std::lround(dem.push_total_m / window_m)));
  for (int k = 0; k < windows; ++k) {
    WindowComparison w;
    w.start_m = k * window_m;
    w.end_m = (k + 1) * window_m;
    // The force resisting the push is -fx in both (the force on the blade).
    w.dem_fx_n = -mean_of(dem.push_m, dem.fx_n, w.start_m, w.end_m);
    w.terracut_fx_n = -mean_of(tc.push_m, tc.fx_n, w.start_m, w.end_m);
    w.dem_fz_n = mean_of(dem.push_m, dem.fz_n, w.start_m, w.end_m);
    w.terracut_fz_n = mean_of(tc.push_m, tc.fz_n, w.start_m, w.end_m);
    const int mm = int(std::lround(w.end_m * 1000.0));
    const auto d = dem.surface_at_push_mm.find(mm);
    const auto t = tc.surface_at_push_mm.find(mm);
    w.has_surface = d != dem.surface_at_push_mm.end() && t != tc.surface_at_push_mm.end();
    if (w.has_surface) {
      const double tip = dem.tip_x_start_m + w.end_m;
      pile_ahead(d->second, dem, tip, w.dem_pile_m3, w.dem_peak_m);
      pile_ahead(t->second, dem, tip, w.terracut_pile_m3, w.terracut_peak_m);
      // The centre line over the span either surface disturbed, away from
      // the blade's own cells (the DEM's grid does not hold the plate;
      // terracut's has the cut under it).
      const std::vector<double> a = centre_line(d->second, dem.rows, dem.cols, dem.cell_m, y_centre);
      const std::vector<double> b = centre_line(t->second, dem.rows, dem.cols, dem.cell_m, y_centre);
      const double moved = 0.25 * dem.depth_m;
      int first = dem.cols, last = -1;
      for (int i = 0; i < dem.cols; ++i)
        if (std::abs(a[std::size_t(i)] - initial[std::size_t(i)]) > moved ||
            std::abs(b[std::size_t(i)] - initial[std::size_t(i)]) > moved) {
          first = std::min(first, i);
          last = i;
        }
      double s = 0.0;
      int n = 0;
      for (int i = first; i <= last; ++i) {
        if (std::abs((i + 0.5) * dem.cell_m - tip) < 1.5 * dem.cell_m) continue;
        s += (a[std::size_t(i)] - b[std::size_t(i)]) * (a[std::size_t(i)] - b[std::size_t(i)]);
        ++n;
      }
      w.profile_rms_m = n > 0 ? std::sqrt(s / n) : 0.0;
    }
    c.windows.push_back(w);
  }
  c.dem_slope_n_per_m = slope_of(dem.push_m, dem.fx_n, window_m);
  c.terracut_slope_n_per_m = slope_of(tc.push_m, tc.fx_n, window_m);
  return c;
}

namespace {

struct Stats {
  double mean = 0.0, std = 0.0;
};
Stats stats_of(const std::vector<double>& v) {
  Stats s;
  if (v.empty()) return s;
  for (double x : v) s.mean += x;
  s.mean /= double(v.size());
  if (v.size() > 1) {
    double q = 0.0;
    for (double x : v) q += (x - s.mean) * (x - s.mean);
    s.std = std::sqrt(q / double(v.size() - 1));
  }
  return s;
}

// Within the target, or within the DEM's own scatter when that is larger.
bool within(double measured, const Stats& reference, double target, double& error) {
  error = reference.mean != 0.0 ? (measured - reference.mean) / std::abs(reference.mean) : 0.0;
  return std::abs(measured - reference.mean) <= std::max(target * std::abs(reference.mean), reference.std);
}

}  // namespace

std::vector<CaseSummary> summarize(const std::vector<RunComparison>& runs, double grain_diameter_m) {
  std::vector<std::string> cases;
  for (const RunComparison& r : runs)
    if (std::find(cases.begin(), cases.end(), r.case_name) == cases.end()) cases.push_back(r.case_name);
  std::sort(cases.begin(), cases.end());
  std::vector<CaseSummary> out;
  for (const std::string& name : cases) {
    std::vector<const RunComparison*> rs;
    for (const RunComparison& r : runs)
      if (r.case_name == name) rs.push_back(&r);
    CaseSummary c;
    c.case_name = name;
    c.seeds = int(rs.size());
    std::size_t nw = rs.front()->windows.size();
    for (const RunComparison* r : rs) nw = std::min(nw, r->windows.size());
    for (std::size_t k = 0; k < nw; ++k) {
      std::vector<double> dfx, tfx, dfz, tfz, dpile, tpile, dpeak, tpeak, prof;
      for (const RunComparison* r : rs) {
        const WindowComparison& w = r->windows[k];
        dfx.push_back(w.dem_fx_n);
        tfx.push_back(w.terracut_fx_n);
        dfz.push_back(w.dem_fz_n);
        tfz.push_back(w.terracut_fz_n);
        dpile.push_back(w.dem_pile_m3);
        tpile.push_back(w.terracut_pile_m3);
        dpeak.push_back(w.dem_peak_m);
        tpeak.push_back(w.terracut_peak_m);
        prof.push_back(w.profile_rms_m);
      }
      CaseSummary::Window w;
      w.start_m = rs.front()->windows[k].start_m;
      w.end_m = rs.front()->windows[k].end_m;
      const Stats f = stats_of(dfx), p = stats_of(dpile);
      w.dem_fx_n = f.mean;
      w.dem_fx_std_n = f.std;
      w.terracut_fx_n = stats_of(tfx).mean;
      w.force_met = within(w.terracut_fx_n, f, kForceTarget, w.force_error);
      w.has_surface = std::all_of(rs.begin(), rs.end(), [&](const RunComparison* r) { return r->windows[k].has_surface; });
      w.dem_fz_n = stats_of(dfz).mean;
      w.terracut_fz_n = stats_of(tfz).mean;
      if (w.has_surface) {
        w.dem_pile_m3 = p.mean;
        w.dem_pile_std_m3 = p.std;
        w.terracut_pile_m3 = stats_of(tpile).mean;
        w.pile_met = within(w.terracut_pile_m3, p, kPileTarget, w.pile_error);
        w.dem_peak_m = stats_of(dpeak).mean;
        w.terracut_peak_m = stats_of(tpeak).mean;
        w.profile_rms_m = stats_of(prof).mean;
        w.profile_met = w.profile_rms_m <= grain_diameter_m;
      }
      c.windows.push_back(w);
    }
    std::vector<double> ds, ts, dw, tw, dc, tc;
    for (const RunComparison* r : rs) {
      ds.push_back(r->dem_slope_n_per_m);
      ts.push_back(r->terracut_slope_n_per_m);
      dw.push_back(r->dem_wall_s);
      tw.push_back(r->terracut_wall_s);
      if (r->dem_cpu_s > 0.0) {  // only the runs whose DEM recorded its CPU time
        dc.push_back(r->dem_cpu_s);
        tc.push_back(r->terracut_cpu_s);
      }
    }
    const Stats slope = stats_of(ds);
    c.dem_slope_n_per_m = slope.mean;
    c.dem_slope_std_n_per_m = slope.std;
    c.terracut_slope_n_per_m = stats_of(ts).mean;
    c.slope_met = within(c.terracut_slope_n_per_m, slope, kSlopeTarget, c.slope_error);
    c.dem_wall_s = stats_of(dw).mean;
    c.terracut_wall_s = stats_of(tw).mean;
    c.cpu_runs = int(dc.size());
    c.dem_cpu_s = dc.empty() ? 0.0 : stats_of(dc).mean;
    c.terracut_cpu_s = tc.empty() ? 0.0 : stats_of(tc).mean;
    c.speedup_in_cpu_time = !dc.empty() && c.terracut_cpu_s > 0.0;
    c.speedup = c.speedup_in_cpu_time ? c.dem_cpu_s / c.terracut_cpu_s
                : c.terracut_wall_s > 0.0 ? c.dem_wall_s / c.terracut_wall_s
                                          : 0.0;
    c.speed_met = c.speedup >= kSpeedTarget;
    out.push_back(c);
  }
  return out;
}

}  // namespace terracut::validation
