// Running a scenario and writing its outputs. See run.hpp.
#include "terracut/io/run.hpp"

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

#include "terracut/core/error.hpp"

namespace terracut::io {
namespace {

using Clock = std::chrono::steady_clock;
using Json = nlohmann::ordered_json;

[[noreturn]] void fail_file(const std::filesystem::path& path, const std::string& what) {
  throw InputError(path.string() + ": " + what);
}

// contact.csv, written row by row through a large stdio buffer with fixed
// printf formats (so the text is the same on every run).
class CsvWriter {
 public:
  explicit CsvWriter(std::filesystem::path path) : path_(std::move(path)) {
    file_ = std::fopen(path_.c_str(), "wb");
    if (!file_) fail_file(path_, std::string("cannot create: ") + std::strerror(errno));
    std::setvbuf(file_, nullptr, _IOFBF, 1 << 20);
    put("t,cut,x,y,z,qw,qx,qy,qz,contact_length,removed_volume,section_area,max_depth,"
        "cells_visited\n");
  }
  ~CsvWriter() {
    if (file_) std::fclose(file_);
  }
  CsvWriter(const CsvWriter&) = delete;
  CsvWriter& operator=(const CsvWriter&) = delete;

  void row(const StepRecord& r, const std::string& cut_name, std::int64_t cells_visited) {
    const Vec3& p = r.pose.position_m;
    const Quat& q = r.pose.orientation;
    const int n = std::fprintf(
        file_, "%.9g,%s,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%lld\n", r.t_s,
        cut_name.c_str(), p.x, p.y, p.z, q.w, q.x, q.y, q.z, r.contact.length_m,
        r.removed_volume_m3, r.contact.section_area_m2, r.contact.max_depth_m,
        static_cast<long long>(cells_visited));
    if (n < 0) fail_file(path_, std::string("write failed: ") + std::strerror(errno));
  }

  void close() {
    const bool bad = std::ferror(file_) != 0;
    const int rc = std::fclose(file_);
    file_ = nullptr;
    if (bad || rc != 0) fail_file(path_, std::string("write failed: ") + std::strerror(errno));
  }

 private:
  void put(const char* text) {
    if (std::fputs(text, file_) < 0)
      fail_file(path_, std::string("write failed: ") + std::strerror(errno));
  }

  std::filesystem::path path_;
  std::FILE* file_ = nullptr;
};

// Removes the named outputs from the folder (ignoring ones that do not exist).
void remove_outputs(const std::filesystem::path& dir) {
  for (const char* name : {"contact.csv", "height.npy", "removed.npy", "height.png", "removed.png",
                           "summary.json", "bodies.csv"}) {
    std::error_code ec;
    std::filesystem::remove(dir / name, ec);
  }
}

TimingStats timing_stats(std::vector<double>& seconds) {
  TimingStats s;
  if (seconds.empty()) return s;
  std::sort(seconds.begin(), seconds.end());
  // Nearest-rank percentile.
  auto pct = [&](double p) {
    const std::size_t n = seconds.size();
    std::size_t rank = static_cast<std::size_t>(std::ceil(p / 100.0 * double(n)));
    rank = std::clamp<std::size_t>(rank, 1, n);
    return seconds[rank - 1] * 1e6;
  };
  s.p50_us = pct(50);
  s.p90_us = pct(90);
  s.p99_us = pct(99);
  s.max_us = seconds.back() * 1e6;
  double sum = 0.0;
  for (double v : seconds) sum += v;
  s.mean_us = sum / double(seconds.size()) * 1e6;
  return s;
}

Json timing_json(const TimingStats& s) {
  return Json{{"p50", s.p50_us}, {"p90", s.p90_us}, {"p99", s.p99_us}, {"max", s.max_us},
              {"mean", s.mean_us}};
}

Json summary_json(const Scenario& sc, const RunResult& r) {
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
                       {"removed_volume_m3", c.removed_volume_m3}});
  out["cuts"] = per_cut;
  out["outputs"] = {{"contact_csv", "contact.csv"}, {"height_npy", "height.npy"},
                    {"removed_npy", "removed.npy"}, {"height_png", "height.png"},
                    {"removed_png", "removed.png"}};
  // The only content that differs between two runs of the same scenario.
  out["timing"] = {{"unit", "us"},
                   {"contact_us", timing_json(r.contact_timing)},
                   {"cut_us", timing_json(r.cut_timing)},
                   {"step_us", timing_json(r.step_timing)},
                   {"wall_s", r.wall_s}};
  return out;
}

void write_text(const std::filesystem::path& path, const std::string& text) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  if (!f) fail_file(path, std::string("cannot create: ") + std::strerror(errno));
  f << text;
  f.close();
  if (!f) fail_file(path, std::string("write failed: ") + std::strerror(errno));
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

RunResult run_into(const Scenario& sc, const RunOptions& options) {
  const std::filesystem::path& dir = options.out_dir;
  const SimParams params = sim_params(sc);
  Simulation sim(params, build_initial_heights(sc));

  // Steps per cut: samples at t = i / rate for i = 0..n, n = round(duration * rate).
  std::vector<std::int64_t> cut_steps;
  std::int64_t total_steps = 0;
  for (int index : sc.sequence) {
    const std::int64_t n =
        std::llround(sc.cuts[std::size_t(index)].duration_s() * sc.rate_hz) + 1;
    cut_steps.push_back(n);
    total_steps += n;
  }

  RunResult result;
  result.initial_volume_m3 = sim.grid().volume_m3();
  if (options.keep_records) result.records.reserve(std::size_t(total_steps));
  std::vector<double> contact_s, cut_s, step_s;
  contact_s.reserve(std::size_t(total_steps));
  cut_s.reserve(std::size_t(total_steps));
  step_s.reserve(std::size_t(total_steps));

  for (RunObserver* o : options.observers) o->start(sim, dir);
  CsvWriter csv(dir / "contact.csv");
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
    stats.steps = cut_steps[k];
    double contact_sum = 0.0;

    // Each cut is a separate stroke: nothing is swept from the previous cut's end.
    sim.lift();
    for (RunObserver* o : options.observers) o->lifted();
    for (std::int64_t i = 0; i < cut_steps[k]; ++i) {
      const BladePose pose = motion.sample(double(i) / sc.rate_hz);
      for (RunObserver* o : options.observers) o->before_step();
      const StepOutput& out = sim.step(pose);
      for (RunObserver* o : options.observers) o->stepped(out);
      StepRecord rec;
      rec.t_s = out.t_s;
      rec.cut = cut_index;
      rec.sequence_index = int(k);
      rec.pose = out.pose;
      rec.contact = out.contact;
      rec.removed_volume_m3 = out.cut.removed_volume_m3;
      csv.row(rec, motion.name, out.contact.cells_visited + out.cut.cells_visited);
      if (i == 0) stats.start_t_s = out.t_s;
      stats.peak_contact_m = std::max(stats.peak_contact_m, out.contact.length_m);
      contact_sum += out.contact.length_m;
      stats.removed_volume_m3 += out.cut.removed_volume_m3;
      contact_s.push_back(out.timers.contact_s);
      cut_s.push_back(out.timers.cut_s);
      step_s.push_back(out.timers.total_s);
      if (options.keep_records) result.records.push_back(rec);
      ++done;
      progress.maybe_report(done, motion.name);
    }
    stats.mean_contact_m = stats.steps > 0 ? contact_sum / double(stats.steps) : 0.0;
    result.removed_volume_m3 += stats.removed_volume_m3;
    result.cuts.push_back(stats);
  }
  result.wall_s = std::chrono::duration<double>(Clock::now() - loop_start).count();
  progress.finish(done);
  csv.close();

  // Final state, conservation and timing.
  const HeightGrid& grid = sim.grid();
  result.steps = done;
  result.final_volume_m3 = grid.volume_m3();
  result.max_sample_error_m = grid.conservation_error_m();
  result.volume_error_m3 =
      result.initial_volume_m3 - result.final_volume_m3 - result.removed_volume_m3;
  result.contact_timing = timing_stats(contact_s);
  result.cut_timing = timing_stats(cut_s);
  result.step_timing = timing_stats(step_s);

  write_npy(dir / "height.npy", grid.heights(), grid.rows(), grid.cols());
  write_npy(dir / "removed.npy", grid.removed(), grid.rows(), grid.cols());
  write_png16(dir / "height.png", grid.heights(), grid.cols(), grid.rows(), sc.full_scale_m);
  write_png16(dir / "removed.png", grid.removed(), grid.cols(), grid.rows(), sc.full_scale_m);
  for (RunObserver* o : options.observers) o->finish();
  nlohmann::json summary = summary_json(sc, result);
  for (RunObserver* o : options.observers) {
    if (!o->summary_key().empty()) summary[o->summary_key()] = nlohmann::json::parse(o->summary_json());
  }
  write_text(dir / "summary.json", summary.dump(2) + "\n");
  return result;
}

}  // namespace

SimParams sim_params(const Scenario& scenario) {
  SimParams params;
  params.grid = grid_spec(scenario);
  params.representation = scenario.representation;
  params.rate_hz = scenario.rate_hz;
  params.blade = scenario.blade;
  return params;
}

RunResult run_scenario(const Scenario& scenario, const RunOptions& options) {
  const std::filesystem::path& dir = options.out_dir;
  if (dir.empty()) throw InputError("--out: no output folder given");
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec || !std::filesystem::is_directory(dir))
    throw InputError(dir.string() + ": cannot create the output folder" +
                     (ec ? ": " + ec.message() : std::string(": a file of that name exists")));

  // Old outputs go first, so a failed run never leaves results that look current.
  remove_outputs(dir);
  try {
    return run_into(scenario, options);
  } catch (...) {
    remove_outputs(dir);
    throw;
  }
}

}  // namespace terracut::io
