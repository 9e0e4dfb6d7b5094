// A batch run of a scenario and its outputs. See batch.hpp.
#include "terracut/session/batch.hpp"

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <ostream>

#include "bodies_json.hpp"
#include "terracut/core/error.hpp"
#include "terracut/io/files.hpp"
#include "terracut/io/image.hpp"
#include "terracut/session/world.hpp"

namespace terracut::session {

std::int64_t cut_steps(const Motion& motion, double rate_hz) {
  return std::llround(motion.duration_s() * rate_hz) + 1;
}

namespace {

using Clock = std::chrono::steady_clock;
using Json = nlohmann::ordered_json;

// Removes the named outputs from the folder (ignoring ones that do not exist).
void remove_outputs(const std::filesystem::path& dir) {
  for (const char* name : {"contact.csv", "force.csv", "height.npy", "removed.npy", "height.png",
                           "removed.png", "summary.json", "bodies.csv", "deposited.npy",
                           "deposited.png"}) {
    std::error_code ec;
    std::filesystem::remove(dir / name, ec);
  }
}

Json timing_json(const TimingStats& s) {
  return Json{{"p50", s.p50_us}, {"p90", s.p90_us}, {"p99", s.p99_us}, {"max", s.max_us},
              {"mean", s.mean_us}};
}

// The force columns' readers (a table of plain functions: no capture).
#define TERRACUT_FORCE(field, part) [](const StepOutput& o) { return o.force.field.part; }
constexpr ForceColumn kForceColumns[] = {
    {"fx", "N", TERRACUT_FORCE(total_n, x)},
    {"fy", "N", TERRACUT_FORCE(total_n, y)},
    {"fz", "N", TERRACUT_FORCE(total_n, z)},
    {"cutting_x", "N", TERRACUT_FORCE(cutting_n, x)},
    {"cutting_y", "N", TERRACUT_FORCE(cutting_n, y)},
    {"cutting_z", "N", TERRACUT_FORCE(cutting_n, z)},
    {"surcharge_x", "N", TERRACUT_FORCE(surcharge_n, x)},
    {"surcharge_y", "N", TERRACUT_FORCE(surcharge_n, y)},
    {"surcharge_z", "N", TERRACUT_FORCE(surcharge_n, z)},
    {"penetration_y", "N", TERRACUT_FORCE(penetration_n, y)},
    {"twist_x", "N", TERRACUT_FORCE(twist_n, x)},
    {"twist_z", "N", TERRACUT_FORCE(twist_n, z)},
    {"twist_torque", "N m", [](const StepOutput& o) { return o.force.twist_torque_n_m; }},
    {"load_x", "N", TERRACUT_FORCE(load_n, x)},
    {"load_y", "N", TERRACUT_FORCE(load_n, y)},
    {"load_z", "N", TERRACUT_FORCE(load_n, z)},
    {"bodies_x", "N", TERRACUT_FORCE(bodies_n, x)},
    {"bodies_y", "N", TERRACUT_FORCE(bodies_n, y)},
    {"bodies_z", "N", TERRACUT_FORCE(bodies_n, z)},
    {"cut_depth", "m", [](const StepOutput& o) { return o.force.cut_depth_m; }},
    {"cut_width", "m", [](const StepOutput& o) { return o.force.engaged_width_m; }},
    {"pile_height", "m", [](const StepOutput& o) { return o.force.pile_m; }},
    {"vx", "m/s", [](const StepOutput& o) { return o.motion.velocity_m_per_s.x; }},
    {"vy", "m/s", [](const StepOutput& o) { return o.motion.velocity_m_per_s.y; }},
    {"vz", "m/s", [](const StepOutput& o) { return o.motion.velocity_m_per_s.z; }},
};
#undef TERRACUT_FORCE

// force.csv: t, cut and the force columns, one row per step.
class ForceCsv {
 public:
  explicit ForceCsv(const std::filesystem::path& path) : file_(path, header()) {
    cells_.reserve(std::size(kForceColumns) + 2);
  }
  void row(const StepOutput& out, const std::string& cut_name) {
    cells_.clear();
    cells_.emplace_back(out.t_s);
    cells_.emplace_back(cut_name);
    for (const ForceColumn& c : kForceColumns) cells_.emplace_back(c.get(out));
    file_.row(cells_);
  }
  void close() { file_.close(); }

 private:
  static std::string header() {
    std::string h = "t,cut";
    for (const ForceColumn& c : kForceColumns) h += std::string(",") + c.name;
    return h;
  }
  io::CsvFile file_;
  std::vector<io::CsvFile::Cell> cells_;  // a row's, reserved once
};

// A cut's force statistics, summed step by step.
class ForceStats {
 public:
  void add(const ToolForce& f) {
    const Vec3 t = f.total_n;
    const double h = std::hypot(t.x, t.z);
    sum_ = sum_ + t;
    sum_h_ += h;
    sum_pile_h_ += std::hypot(f.surcharge_n.x, f.surcharge_n.z);
    out_.peak_horizontal_n = std::max(out_.peak_horizontal_n, h);
    if (std::abs(t.y) > std::abs(out_.peak_vertical_n)) out_.peak_vertical_n = t.y;
    ++n_;
  }
  CutForceStats result() const {
    CutForceStats r = out_;
    if (n_ > 0) {
      r.mean_n = sum_ * (1.0 / double(n_));
      r.mean_horizontal_n = sum_h_ / double(n_);
      r.mean_vertical_n = r.mean_n.y;
      r.mean_surcharge_horizontal_n = sum_pile_h_ / double(n_);
    }
    return r;
  }

 private:
  CutForceStats out_{};
  Vec3 sum_{};
  double sum_h_ = 0.0, sum_pile_h_ = 0.0;
  std::int64_t n_ = 0;
};

Json force_json(const CutForceStats& f) {
  return Json{{"mean_n", {f.mean_n.x, f.mean_n.y, f.mean_n.z}},
              {"mean_horizontal_n", f.mean_horizontal_n},
              {"peak_horizontal_n", f.peak_horizontal_n},
              {"mean_vertical_n", f.mean_vertical_n},
              {"peak_vertical_n", f.peak_vertical_n},
              {"mean_surcharge_horizontal_n", f.mean_surcharge_horizontal_n}};
}

Json material_json(const SoilMaterial& m) {
  return Json{{"unit_weight_n_per_m3", m.unit_weight_n_per_m3},
              {"density_kg_per_m3", m.density_kg_per_m3()},
              {"internal_friction_deg", m.internal_friction_deg},
              {"cohesion_pa", m.cohesion_pa},
              {"soil_tool_friction_deg", m.soil_tool_friction_deg},
              {"adhesion_pa", m.adhesion_pa},
              {"repose_deg", m.repose_deg}};
}

}  // namespace

std::span<const ForceColumn> force_columns() { return kForceColumns; }

namespace {

// Whether segment a-b, seen from above (X-Z), meets the rectangle [x0, x1] x
// [z0, z1] (Liang-Barsky clipping of the segment's parameter).
bool crosses_from_above(const Vec3& a, const Vec3& b, double x0, double x1, double z0, double z1) {
  double t0 = 0.0, t1 = 1.0;
  const auto clip = [&](double p, double q) {  // the part where p t <= q
    if (p == 0.0) return q >= 0.0;
    const double t = q / p;
    if (p < 0.0) t0 = std::max(t0, t);
    else t1 = std::min(t1, t);
    return t0 <= t1;
  };
  const double dx = b.x - a.x, dz = b.z - a.z;
  return clip(-dx, a.x - x0) && clip(dx, x1 - a.x) && clip(-dz, a.z - z0) && clip(dz, z1 - a.z);
}

}  // namespace

std::vector<std::string> cut_warnings(const io::Scenario& sc) {
  std::vector<std::string> w;
  const GridSpec g = io::grid_spec(sc);
  const double x0 = g.origin_m.x, x1 = g.origin_m.x + g.size_x_m;
  const double z0 = g.origin_m.z, z1 = g.origin_m.z + g.size_z_m;
  std::vector<bool> seen(sc.cuts.size(), false);
  for (const int index : sc.sequence) {
    if (seen[std::size_t(index)]) continue;
    seen[std::size_t(index)] = true;
    const Motion& motion = sc.cuts[std::size_t(index)];
    const std::int64_t n = cut_steps(motion, sc.rate_hz);
    bool crosses = false;
    for (std::int64_t i = 0; i < n && !crosses; ++i) {
      const Segment e = blade_segment(sc.blade, motion.sample(double(i) / sc.rate_hz));
      crosses = crosses_from_above(e.a, e.b, x0, x1, z0, z1);
    }
    if (crosses) continue;
    char extent[200];
    std::snprintf(extent, sizeof extent, "x in [%.6g, %.6g] m, z in [%.6g, %.6g] m", x0, x1, z0, z1);
    w.push_back("cut '" + motion.name + "': the blade never crosses the terrain (" + extent +
                ", seen from above) in any of its " + std::to_string(n) +
                " steps, so it cuts nothing: its keyframes' position_m are world coordinates, not "
                "offsets from the terrain's corner");
  }
  return w;
}

std::vector<std::string> bounds_warnings(std::int64_t samples, double deleted_m3, double max_height_m) {
  std::vector<std::string> w;
  if (samples <= 0) return w;
  char line[600];
  std::snprintf(line, sizeof line,
                "bodies: %lld times a sample rose above the rigid bodies' heightfield's upper bound (%.4g m "
                "above the ground, fixed when the world is built: the larger of 2 x terrain.full_scale_m and "
                "the highest initial height + terrain.full_scale_m) and was lowered to it, deleting %.3g m^3 "
                "of soil (left out of the conservation check); raise terrain.full_scale_m for more room",
                (long long)samples, max_height_m, deleted_m3);
  w.push_back(line);
  return w;
}

std::vector<std::string> soil_warnings(const SoilFlowParams& soil, const GridSpec& grid,
                                       std::int64_t final_backlog_cells, std::int64_t capped_steps) {
  std::vector<std::string> w;
  if (soil.model != SoilModel::kFlow) return w;
  if (capped_steps > 0)
    w.push_back("soil: the relaxation's work cap (soil.max_pair_checks_per_step = " +
                std::to_string(soil.max_pair_checks_per_step) + " neighbour visits a step) stopped it in " +
                std::to_string(capped_steps) +
                " steps; what it left for later steps can change a pushed pile (docs/soil.md, \"What the cap "
                "defers\"): lift the cap for an offline run to compare");
  if (final_backlog_cells > 0)
    w.push_back("soil: the relaxation was not done at the end (a backlog of " + std::to_string(final_backlog_cells) +
                " cells to examine and fluxes to apply): the work cap (soil.max_pair_checks_per_step = " +
                std::to_string(soil.max_pair_checks_per_step) +
                " neighbour visits a step) stopped it short, so slopes may still stand steeper than the angle "
                "of repose; raise the cap for an offline run");
  // Cells far from square leave planes steeper than on square cells
  // standing (the 8 neighbours' directions leave wider gaps).
  const double dx = grid.cell_x_m(), dz = grid.cell_z_m();
  const double here = steepest_standing_slope_deg(dx, dz, soil.material.repose_deg);
  const double square = steepest_standing_slope_deg(dx, dx, soil.material.repose_deg);
  if (here > square + 0.5) {
    char line[400];
    std::snprintf(line, sizeof line,
                  "soil: cells of %.4g x %.4g m (X x Z) let planes up to %.1f degrees stand between the "
                  "relaxation's 8 neighbour directions, against %.1f on square cells, for a repose angle of "
                  "%.4g: use square cells to keep every direction within %.1f degrees of it",
                  dx, dz, here, square, soil.material.repose_deg, square - soil.material.repose_deg);
    w.push_back(line);
  }
  return w;
}

namespace {

Json summary_json(const io::Scenario& sc, const RunResult& r) {
  Json inputs;
  inputs["scenario"] = sc.source_path.string();
  inputs["name"] = sc.name;
  Json terrain;
  if (sc.generator) {
    const Generator& g = *sc.generator;
    terrain["generator"] = std::string(to_string(g.kind));
    switch (g.kind) {
      case GeneratorKind::kMound:
        terrain["mound"] = {{"centre_m", {g.mound.centre_x_m, g.mound.centre_z_m}},
                            {"radius_m", g.mound.radius_m},
                            {"height_m", g.mound.height_m}};
        break;
      case GeneratorKind::kBox:
        terrain["box"] = {{"min_m", {g.box.min_x_m, g.box.min_z_m}},
                          {"max_m", {g.box.max_x_m, g.box.max_z_m}},
                          {"height_m", g.box.height_m}};
        break;
      case GeneratorKind::kPlane:
        terrain["plane"] = {{"height_m", g.plane.height_m}};
        break;
    }
  } else {
    terrain["image"] = sc.image_path.string();
    terrain["image_size"] = {sc.image.cols, sc.image.rows};
  }
  terrain["resolution"] = {sc.resolution.cols, sc.resolution.rows};
  terrain["size_m"] = {sc.size_x_m, sc.size_z_m};
  terrain["origin_m"] = {sc.origin_m.x, sc.origin_m.y, sc.origin_m.z};
  terrain["full_scale_m"] = sc.full_scale_m;
  terrain["cell_m"] = {sc.size_x_m / sc.resolution.cols, sc.size_z_m / sc.resolution.rows};
  inputs["terrain"] = terrain;
  inputs["representation"] = std::string(to_string(sc.representation));
  inputs["rate_hz"] = sc.rate_hz;
  inputs["blade_length_m"] = sc.blade.length_m;
  inputs["blade_rake_angle_deg"] = sc.blade.rake_angle_deg;
  if (std::isfinite(sc.blade.height_m)) inputs["blade_height_m"] = sc.blade.height_m;  // (absent: unbounded)
  inputs["soil_material"] = material_json(sc.soil.material);
  inputs["sequence"] = sc.sequence_names();
  Json cuts = Json::array();
  for (const Motion& m : sc.cuts)
    cuts.push_back({{"name", m.name},
                    {"duration_s", m.duration_s()},
                    {"keyframes", m.keyframes.size()}});
  inputs["cuts"] = cuts;

  Json out;
  out["inputs"] = inputs;
  out["steps"] = r.steps;
  out["initial_volume_m3"] = r.initial_volume_m3;
  out["final_volume_m3"] = r.final_volume_m3;
  out["removed_volume_m3"] = r.removed_volume_m3;
  out["conservation"] = {{"max_sample_error_m", r.max_sample_error_m},
                         {"volume_error_m3", r.volume_error_m3}};
  Json per_cut = Json::array();
  for (const CutStats& c : r.cuts)
    per_cut.push_back({{"name", c.name},
                       {"sequence_index", c.sequence_index},
                       {"start_t_s", c.start_t_s},
                       {"duration_s", c.duration_s},
                       {"steps", c.steps},
                       {"peak_contact_m", c.peak_contact_m},
                       {"mean_contact_m", c.mean_contact_m},
                       {"removed_volume_m3", c.removed_volume_m3},
                       {"force", force_json(c.force)}});
  out["cuts"] = per_cut;
  out["outputs"] = {{"contact_csv", "contact.csv"}, {"force_csv", "force.csv"}, {"height_npy", "height.npy"},
                    {"removed_npy", "removed.npy"}, {"height_png", "height.png"},
                    {"removed_png", "removed.png"}};
  // The only content that differs between two runs of the same scenario.
  if (r.soil) {
    const SoilRunStats& s = *r.soil;
    out["soil"] = {{"model", "flow"},
                   {"repose_deg", sc.soil.material.repose_deg},
                   {"edge", std::string(to_string(sc.soil.edge))},
                   {"settle", std::string(to_string(sc.soil.settle))},
                   {"volume_m3",
                    {{"initial", r.initial_volume_m3},
                     {"final", r.final_volume_m3},
                     {"left_over_edge", s.left_over_edge_m3},
                     {"error", r.volume_error_m3}}},
                   // What the blade cut out of the ground, what it pushed
                   // (a pile pushed on is counted at every step), and the
                   // soil no longer where it was at the end.
                   {"cut_from_ground_m3", s.cut_from_ground_m3},
                   {"displaced_volume_m3", s.displaced_volume_m3},
                   {"net_moved_m3", s.net_moved_m3},
                   {"over_top_m3", s.over_top_m3},
                   {"relaxation",
                    {{"passes", s.passes},
                     {"pair_checks", s.pair_checks},
                     {"settle_visits", s.settle_visits},
                     {"max_backlog_cells", s.max_backlog_cells},
                     {"final_backlog_cells", s.final_backlog_cells},
                     {"capped_steps", s.capped_steps},
                     {"max_pair_checks_per_step", sc.soil.max_pair_checks_per_step}}}};
    if (sc.blade.bucket.enabled())
      out["soil"]["bucket"] = {{"depth_m", sc.blade.bucket.depth_m},
                               {"height_m", sc.blade.bucket.height_m},
                               {"level_capacity_m3", bucket_retained_m3(sc.blade, Quat{}, sc.soil.material.repose_deg)},
                               {"taken_in_m3", s.bucket_in_m3},
                               {"poured_m3", s.poured_m3},
                               {"max_load_m3", s.max_bucket_load_m3},
                               {"final_load_m3", s.final_bucket_load_m3}};
    out["outputs"]["deposited_npy"] = "deposited.npy";
    out["outputs"]["deposited_png"] = "deposited.png";
  }
  out["timing"] = {{"unit", "us"},
                   {"contact_us", timing_json(r.contact_timing)},
                   {"cut_us", timing_json(r.cut_timing)},
                   {"step_us", timing_json(r.step_timing)},
                   {"wall_s", r.wall_s}};
  if (r.soil) out["timing"]["soil_us"] = timing_json(r.soil->soil_timing);
  if (r.listeners_timing) out["timing"]["listeners_us"] = timing_json(*r.listeners_timing);
  out["warnings"] = r.warnings;
  return out;
}

// Writes a progress line about once a second after the first progress_after_s.
class Progress {
 public:
  Progress(const RunOptions& options, std::int64_t total_steps)
      : options_(options), total_(total_steps), start_(Clock::now()), last_(start_) {}

  void maybe_report(std::int64_t done, const std::string& cut_name) {
    if (!options_.progress || (done & 255) != 0) return;
    const Clock::time_point now = Clock::now();
    const double elapsed = std::chrono::duration<double>(now - start_).count();
    if (elapsed < options_.progress_after_s) return;
    if (printed_ && std::chrono::duration<double>(now - last_).count() < 1.0) return;
    last_ = now;
    printed_ = true;
    char line[256];
    std::snprintf(line, sizeof line, "%s: %5.1f%% (%lld/%lld steps, %.0f steps/s, cut %s)\n",
                  options_.progress_label.c_str(), 100.0 * double(done) / double(total_),
                  static_cast<long long>(done), static_cast<long long>(total_),
                  double(done) / elapsed, cut_name.c_str());
    *options_.progress << line << std::flush;
  }

  void finish(std::int64_t done) {
    if (!options_.progress || !printed_) return;
    const double elapsed = std::chrono::duration<double>(Clock::now() - start_).count();
    char line[256];
    std::snprintf(line, sizeof line, "%s: 100.0%% (%lld steps in %.1f s, %.0f steps/s)\n",
                  options_.progress_label.c_str(), static_cast<long long>(done), elapsed,
                  double(done) / elapsed);
    *options_.progress << line << std::flush;
  }

 private:
  const RunOptions& options_;
  std::int64_t total_;
  Clock::time_point start_;
  Clock::time_point last_;
  bool printed_ = false;
};

RunResult run_into(const Scenario& scenario, const RunOptions& options) {
  const io::Scenario& sc = scenario.base;
  const std::filesystem::path& dir = options.out_dir;
  WorldOptions wo;
  wo.bodies_csv = dir / "bodies.csv";
  World world(scenario, wo);
  Simulation& sim = world.simulation();

  // Steps per cut: samples at t = i / rate for i = 0..n, n = round(duration * rate).
  std::vector<std::int64_t> steps_of_cut;
  std::int64_t total_steps = 0;
  for (int index : sc.sequence) {
    const std::int64_t n = session::cut_steps(sc.cuts[std::size_t(index)], sc.rate_hz);
    steps_of_cut.push_back(n);
    total_steps += n;
  }

  RunResult result;
  result.initial_volume_m3 = sim.grid().volume_m3();
  if (options.keep_records) result.records.reserve(std::size_t(total_steps));
  const bool flow = sim.params().soil.model == SoilModel::kFlow;
  SoilRunStats soil;
  const bool listening = !sim.listeners().empty();
  std::vector<double> contact_s, cut_s, step_s, soil_s, listeners_s;
  if (flow) soil_s.reserve(std::size_t(total_steps));
  if (listening) listeners_s.reserve(std::size_t(total_steps));
  contact_s.reserve(std::size_t(total_steps));
  cut_s.reserve(std::size_t(total_steps));
  step_s.reserve(std::size_t(total_steps));

  // Real-time pacing: each step starts on its deadline; the first anchors the schedule.
  std::optional<haptics::Pacer> pacer;
  if (options.realtime) pacer.emplace(haptics::PacerSettings{.rate_hz = sc.rate_hz});

  io::ContactCsvWriter csv(dir / "contact.csv");
  ForceCsv force_csv(dir / "force.csv");
  Progress progress(options, total_steps);
  const Clock::time_point loop_start = Clock::now();
  std::int64_t done = 0;
  for (std::size_t k = 0; k < sc.sequence.size(); ++k) {
    const int cut_index = sc.sequence[k];
    const Motion& motion = sc.cuts[std::size_t(cut_index)];
    CutStats stats;
    stats.name = motion.name;
    stats.sequence_index = int(k);
    stats.duration_s = motion.duration_s();
    stats.steps = steps_of_cut[k];
    double contact_sum = 0.0;
    ForceStats force;

    // Each cut is a separate stroke: nothing is swept from the previous cut's end.
    sim.lift();
    for (std::int64_t i = 0; i < steps_of_cut[k]; ++i) {
      const BladePose pose = motion.sample(double(i) / sc.rate_hz);
      if (pacer) {
        if (done == 0)
          pacer->start();
        else
          pacer->wait_next();
      }
      const StepOutput& out = sim.step(pose);
      if (pacer) pacer->record_compute(out.timers.total_s);
      io::StepRecord rec;
      rec.t_s = out.t_s;
      rec.cut = cut_index;
      rec.sequence_index = int(k);
      rec.pose = out.pose;
      rec.contact = out.contact;
      rec.removed_volume_m3 = out.cut.removed_volume_m3;
      csv.row(rec, motion.name, out.contact.cells_visited + out.cut.cells_visited);
      force_csv.row(out, motion.name);
      force.add(out.force);
      if (i == 0) stats.start_t_s = out.t_s;
      stats.peak_contact_m = std::max(stats.peak_contact_m, out.contact.length_m);
      contact_sum += out.contact.length_m;
      stats.removed_volume_m3 += out.cut.removed_volume_m3;
      contact_s.push_back(out.timers.contact_s);
      cut_s.push_back(out.timers.cut_s);
      step_s.push_back(out.timers.total_s);
      if (listening) listeners_s.push_back(out.timers.listeners_s);
      if (flow) {
        soil.displaced_volume_m3 += out.soil.displaced_volume_m3;
        soil.cut_from_ground_m3 += out.soil.cut_from_ground_m3;
        soil.left_over_edge_m3 += out.soil.left_over_edge_m3;
        soil.over_top_m3 += out.soil.over_top_m3;
        soil.passes += out.soil.passes;
        soil.pair_checks += out.soil.pair_checks;
        soil.settle_visits += out.soil.settle_visits;
        soil.max_backlog_cells = std::max(soil.max_backlog_cells, out.soil.backlog_cells);
        soil.capped_steps += out.soil.reached_cap ? 1 : 0;
        soil.bucket_in_m3 += out.soil.bucket_in_m3;
        soil.poured_m3 += out.soil.poured_m3;
        soil.max_bucket_load_m3 = std::max(soil.max_bucket_load_m3, out.soil.bucket_load_m3);
        soil.final_bucket_load_m3 = out.soil.bucket_load_m3;
        soil_s.push_back(out.timers.soil_s);
      }
      if (options.keep_records) result.records.push_back(rec);
      ++done;
      progress.maybe_report(done, motion.name);
    }
    stats.mean_contact_m = stats.steps > 0 ? contact_sum / double(stats.steps) : 0.0;
    stats.force = force.result();
    result.removed_volume_m3 += stats.removed_volume_m3;
    result.cuts.push_back(stats);
  }
  result.wall_s = std::chrono::duration<double>(Clock::now() - loop_start).count();
  progress.finish(done);
  csv.close();
  force_csv.close();

  // Final state, conservation and timing.
  const HeightGrid& grid = sim.grid();
  result.steps = done;
  result.final_volume_m3 = grid.volume_m3();
  result.max_sample_error_m = grid.conservation_error_m();
  // With flow nothing vanishes: what was cut is still on the grid, or left
  // it over an open edge, or the bodies' heightfield deleted it above its
  // upper bound (warned below).
  const detail::BoundsClamp clamp = detail::bounds_clamp(world);
  const double vanished_m3 =
      (flow ? soil.left_over_edge_m3 + soil.final_bucket_load_m3 : result.removed_volume_m3) + clamp.volume_m3;
  result.volume_error_m3 = result.initial_volume_m3 - result.final_volume_m3 - vanished_m3;
  result.contact_timing = timing_stats(contact_s);
  result.cut_timing = timing_stats(cut_s);
  result.step_timing = timing_stats(step_s);
  if (listening) result.listeners_timing = timing_stats(listeners_s);
  if (pacer) result.realtime = pacer->stats();
  if (flow) {
    soil.final_backlog_cells = sim.soil()->active_cells();
    for (std::int64_t i = 0; i < grid.spec().sample_count(); ++i)
      soil.net_moved_m3 += std::max(0.0, double(grid.initial()[i]) - double(grid.heights()[i]));
    soil.net_moved_m3 *= grid.spec().cell_area_m2();
    soil.soil_timing = timing_stats(soil_s);
    result.soil = soil;
  }
  result.warnings = cut_warnings(sc);
  for (std::string& line : bounds_warnings(clamp.samples, clamp.volume_m3, clamp.max_height_m))
    result.warnings.push_back(std::move(line));
  if (flow) {
    const std::vector<std::string> soil_lines = soil_warnings(sc.soil, grid.spec(), soil.final_backlog_cells, soil.capped_steps);
    result.warnings.insert(result.warnings.end(), soil_lines.begin(), soil_lines.end());
  }

  io::write_npy(dir / "height.npy", grid.heights(), grid.rows(), grid.cols());
  io::write_png16(dir / "height.png", grid.heights(), grid.cols(), grid.rows(), sc.full_scale_m);
  // The removed layer is derived (initial - height), so it is written from a copy.
  std::vector<float> removed(std::size_t(grid.spec().sample_count()));
  grid.copy_removed(removed.data());
  if (!flow) {
    io::write_npy(dir / "removed.npy", removed.data(), grid.rows(), grid.cols());
    io::write_png16(dir / "removed.png", removed.data(), grid.cols(), grid.rows(), sc.full_scale_m);
  } else {
    // The signed removed layer as its two parts: taken from, put down on.
    std::vector<float> taken(removed.size());
    std::vector<float> put(taken.size());
    for (std::size_t i = 0; i < taken.size(); ++i) {
      taken[i] = std::max(0.0f, removed[i]);
      put[i] = std::max(0.0f, -removed[i]);
    }
    io::write_npy(dir / "removed.npy", taken.data(), grid.rows(), grid.cols());
    io::write_png16(dir / "removed.png", taken.data(), grid.cols(), grid.rows(), sc.full_scale_m);
    io::write_npy(dir / "deposited.npy", put.data(), grid.rows(), grid.cols());
    io::write_png16(dir / "deposited.png", put.data(), grid.cols(), grid.rows(), sc.full_scale_m);
  }
  world.finish();
  nlohmann::json summary = summary_json(sc, result);
  if (world.bodies()) summary["bodies"] = detail::bodies_json(world, detail::BodiesEntry::kRun);
  if (result.realtime) summary["realtime"] = nlohmann::json::parse(realtime_json(*result.realtime));
  io::write_text_file(dir / "summary.json", summary.dump(2) + "\n");
  return result;
}

}  // namespace

RunResult run_scenario(const Scenario& scenario, const RunOptions& options) {
  const std::filesystem::path& dir = options.out_dir;
  io::make_output_folder(dir);

  // Old outputs go first, so a failed run never leaves results that look current.
  remove_outputs(dir);
  try {
    return run_into(scenario, options);
  } catch (...) {
    remove_outputs(dir);
    throw;
  }
}

namespace {

nlohmann::json to_json_us(const haptics::TimeStats& s) {
  return {{"p50_us", s.p50_s * 1e6}, {"p99_us", s.p99_s * 1e6}, {"max_us", s.max_s * 1e6},
          {"mean_us", s.mean_s * 1e6}, {"count", s.count}};
}

}  // namespace

std::string realtime_json(const haptics::LoopStats& s) {
  nlohmann::json j;
  j["rate_hz"] = s.rate_hz;
  j["period_us"] = 1e6 / s.rate_hz;
  j["ticks"] = s.ticks;
  j["missed_deadlines"] = s.missed_deadlines;
  j["skipped_slots"] = s.skipped_slots;
  j["step_time"] = to_json_us(s.compute);
  j["period_jitter"] = to_json_us(s.period_jitter);
  j["wake_latency"] = to_json_us(s.wake_latency);
  return j.dump();
}

}  // namespace terracut::session
