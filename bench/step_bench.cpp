// Benchmarks of the 1 kHz step: contact + swept cut of a blade moving through
// material, for both representations, against the terrain side, against the
// paper's brute-force algorithm, and the memory of a run.
//
// Every case uses 1 mm cells (a terrain of side N covers N mm) and a blade
// moving 0.6 mm per step (0.6 m/s at 1 kHz, a brisk hand motion) along +Z at
// 0.1 m above the ground, through a plane of material 0.2 m high with a
// +-0.02 m undulation, so the whole blade is inside material on every step.
// When the blade reaches the far side the terrain is restored and the blade
// put down again (untimed). The direction and tilt cases move the blade
// along its own normal instead, across the middle of the terrain.
//
// Each step is timed on its own (steady_clock, manual timing), so the JSON
// carries per-step percentiles as counters: p50_us, p99_us, max_us, plus
// cells_per_step (cells the contact traversal and the cut examined),
// ns_per_cell (step time / cells visited) and the simulation's own split,
// contact_p50_us and cut_p50_us. The cases with targets (headline, blade256)
// run three times; Google Benchmark adds median aggregates of every counter.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <memory>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "terracut/core/brute_force.hpp"
#include "terracut/core/simulation.hpp"

namespace {

using namespace terracut;
using Clock = std::chrono::steady_clock;

constexpr double kCellM = 1e-3;             // cell size at every side, metres
constexpr double kTravelPerStepM = 0.6e-3;  // blade travel per step, metres
constexpr double kSurfaceM = 0.2;           // mean material height, metres
constexpr double kUndulationM = 0.02;       // amplitude of the surface undulation, metres
constexpr double kBladeYM = 0.1;            // blade height above the ground, metres
constexpr double kBruteForceLimitS = 1.0;   // brute-force sides whose step would exceed this are skipped
// Runs of the cases with targets: the table takes the median run, which
// keeps a burst of other work on a shared machine from deciding a figure.
constexpr int kRepetitions = 3;
constexpr double kInfinity = std::numeric_limits<double>::infinity();
// Blades of the direction cases: 0.7 of the side, so that the footprint
// fits the terrain at any yaw with room to travel.
constexpr double kDirectionBladeFraction = 0.7;
// Blade of the tilt cases, cells: short enough that a 20-degree tilt keeps
// both ends inside the material and above the floor.
constexpr double kTiltBladeCells = 400.0;

/// One benchmark case.
struct Case {
  Representation representation = Representation::kSurface;
  int side = 0;              ///< terrain side, samples (side x side)
  double blade_cells = 0.0;  ///< blade length in cells; 0 = its footprint spans the full width
  double yaw_deg = 0.0;      ///< blade rotation about +Y; 0 = blade along X, moving along Z
  bool brute_force = false;  ///< step with the paper's algorithm instead of the traversal
  int steps = 0;             ///< timed steps
  int warmup_steps = 0;      ///< untimed steps before them
  /// Moves along the blade's own normal (as a blade works) across the
  /// middle of the terrain, instead of along +Z; blade_cells must be set.
  bool along_normal = false;
  double tilt_deg = 0.0;  ///< blade rotation about its direction of travel (before the yaw)
};

/// A plane of material with a smooth undulation (separable, cheap to build at 8192^2).
std::vector<float> plane_terrain(int side) {
  std::vector<double> wave(static_cast<size_t>(side));
  for (int i = 0; i < side; ++i) wave[size_t(i)] = std::sin(2.0 * std::numbers::pi * i / 512.0);
  std::vector<float> h(size_t(side) * size_t(side));
  for (int r = 0; r < side; ++r) {
    float* row = h.data() + size_t(r) * size_t(side);
    for (int c = 0; c < side; ++c) row[c] = float(kSurfaceM + kUndulationM * wave[size_t(c)] * wave[size_t(r)]);
  }
  return h;
}

SimParams params_for(const Case& c) {
  SimParams p;
  p.grid.cols = c.side;
  p.grid.rows = c.side;
  p.grid.size_x_m = c.side * kCellM;
  p.grid.size_z_m = c.side * kCellM;
  p.grid.full_scale_m = 0.5;
  p.representation = c.representation;
  p.rate_hz = 1000.0;
  double yaw = c.yaw_deg * std::numbers::pi / 180.0;
  p.blade.length_m = c.blade_cells > 0.0 ? c.blade_cells * kCellM : c.side * kCellM / std::cos(yaw);
  return p;
}

/// Drives a simulation (or the brute-force functions on its grid) along +Z.
class Runner {
 public:
  explicit Runner(const Case& c)
      : case_(c), sim_(params_for(c), plane_terrain(c.side)) {
    // The brute force (the paper's) edits a grid of its own: the
    // simulation's terrain is changed only by the simulation.
    if (c.brute_force) brute_grid_.emplace(sim_.grid().spec(), plane_terrain(c.side));
    const double deg = std::numbers::pi / 180.0;
    const Quat yaw = quat_from_axis_angle({0.0, 1.0, 0.0}, c.yaw_deg * deg);
    orientation_ = yaw * quat_from_axis_angle({0.0, 0.0, 1.0}, c.tilt_deg * deg);
    const double size = c.side * kCellM, margin = 2.0 * kCellM;
    // The blade's footprint half extents.
    const Vec3 half = rotate(orientation_, {0.5 * sim_.params().blade.length_m, 0.0, 0.0});
    const double hx = std::abs(half.x), hz = std::abs(half.z);
    if (c.along_normal) {
      // Across the middle along the normal, as far as the footprint stays on the terrain.
      travel_ = rotate(yaw, {0.0, 0.0, 1.0});
      origin_ = {0.5 * size, 0.0, 0.5 * size};
      double reach = kInfinity;
      if (std::abs(travel_.x) > 1e-9) reach = std::min(reach, (0.5 * size - margin - hx) / std::abs(travel_.x));
      if (std::abs(travel_.z) > 1e-9) reach = std::min(reach, (0.5 * size - margin - hz) / std::abs(travel_.z));
      s_lo_ = -reach;
      s_hi_ = std::max(s_lo_ + kTravelPerStepM, reach);
    } else {
      travel_ = {0.0, 0.0, 1.0};
      origin_ = {0.5 * size, 0.0, 0.0};
      s_lo_ = hz + margin;
      s_hi_ = std::max(s_lo_ + kTravelPerStepM, size - hz - margin);
    }
    s_ = s_lo_;
  }

  /// Moves the blade one step forward; at the far side restores the terrain
  /// and puts the blade down at the start again. Untimed.
  void advance() {
    s_ += kTravelPerStepM;
    if (s_ > s_hi_) {
      sim_.reset();
      if (brute_grid_) brute_grid_->reset();
      has_previous_ = false;
      s_ = s_lo_;
    }
  }

  /// One step at the current pose; returns the cells examined.
  std::int64_t step() {
    const Vec3 centre = origin_ + travel_ * s_;
    BladePose pose{{centre.x, kBladeYM, centre.z}, orientation_};
    if (!case_.brute_force) {
      const StepOutput& o = sim_.step(pose);
      last_contact_s_ = o.timers.contact_s;
      last_cut_s_ = o.timers.cut_s;
      return o.contact.cells_visited + o.cut.cells_visited;
    }
    Segment edge = blade_segment(sim_.params().blade, pose);
    ContactResult contact = measure_contact_brute_force(*brute_grid_, case_.representation, edge);
    CutResult cut = cut_sweep_brute_force(*brute_grid_, case_.representation,
                                          has_previous_ ? previous_ : edge, edge);
    benchmark::DoNotOptimize(contact);
    previous_ = edge;
    has_previous_ = true;
    return contact.cells_visited + cut.cells_visited;
  }

  Simulation& sim() { return sim_; }
  /// Contact and cut time of the last step (the simulation's own timers).
  double last_contact_s() const { return last_contact_s_; }
  double last_cut_s() const { return last_cut_s_; }

 private:
  Case case_;
  Simulation sim_;
  std::optional<HeightGrid> brute_grid_;  // the brute-force cases' terrain
  Quat orientation_{};
  Vec3 origin_{}, travel_{};  ///< the blade's centre is origin_ + travel_ * s_ (ground plane)
  double s_ = 0.0, s_lo_ = 0.0, s_hi_ = 0.0;
  Segment previous_{};
  bool has_previous_ = false;
  double last_contact_s_ = 0.0, last_cut_s_ = 0.0;
};

/// Nearest-rank percentile of sorted values, q in (0, 1].
double percentile(const std::vector<double>& sorted, double q) {
  if (sorted.empty()) return 0.0;
  size_t rank = size_t(std::ceil(q * double(sorted.size())));
  return sorted[std::min(sorted.size(), std::max<size_t>(rank, 1)) - 1];
}

/// Resident and peak resident memory of this process, bytes (Linux /proc).
struct Rss {
  double current = 0.0;
  double peak = 0.0;
};

Rss read_rss() {
  Rss out;
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    long kib = 0;
    if (std::sscanf(line.c_str(), "VmRSS: %ld kB", &kib) == 1) out.current = kib * 1024.0;
    if (std::sscanf(line.c_str(), "VmHWM: %ld kB", &kib) == 1) out.peak = kib * 1024.0;
  }
  return out;
}

/// Resets the peak-RSS mark (Linux >= 4.0); harmless where unsupported.
void reset_peak_rss() {
  std::ofstream clear("/proc/self/clear_refs");
  clear << "5";
}

// Brute-force step time of the largest side measured so far, to skip sides
// that would take longer than kBruteForceLimitS per step.
double g_brute_last_step_s = 0.0;
int g_brute_last_side = 0;

void bm_steps(benchmark::State& state, Case c) {
  if (c.brute_force && g_brute_last_side > 0) {
    double ratio = double(c.side) / g_brute_last_side;
    double predicted_s = g_brute_last_step_s * ratio * ratio;
    if (predicted_s > kBruteForceLimitS) {
      state.SkipWithError(("skipped: predicted brute-force step " + std::to_string(predicted_s) +
                           " s > " + std::to_string(kBruteForceLimitS) + " s")
                              .c_str());
      return;
    }
  }
  Runner run(c);
  for (int i = 0; i < c.warmup_steps; ++i) {
    run.advance();
    run.step();
  }
  std::vector<double> times, contact_times, cut_times;
  times.reserve(size_t(c.steps));
  contact_times.reserve(size_t(c.steps));
  cut_times.reserve(size_t(c.steps));
  std::int64_t cells = 0;
  for (auto _ : state) {
    run.advance();
    Clock::time_point t0 = Clock::now();
    cells += run.step();
    Clock::time_point t1 = Clock::now();
    double dt = std::chrono::duration<double>(t1 - t0).count();
    state.SetIterationTime(dt);
    times.push_back(dt);
    contact_times.push_back(run.last_contact_s());
    cut_times.push_back(run.last_cut_s());
  }
  double total = 0.0;
  for (double t : times) total += t;
  std::sort(times.begin(), times.end());
  state.counters["p50_us"] = percentile(times, 0.50) * 1e6;
  state.counters["p99_us"] = percentile(times, 0.99) * 1e6;
  state.counters["max_us"] = times.empty() ? 0.0 : times.back() * 1e6;
  state.counters["mean_us"] = times.empty() ? 0.0 : total / double(times.size()) * 1e6;
  state.counters["cells_per_step"] = times.empty() ? 0.0 : double(cells) / double(times.size());
  state.counters["ns_per_cell"] = cells > 0 ? total / double(cells) * 1e9 : 0.0;
  state.counters["side"] = c.side;
  if (!c.brute_force && !times.empty()) {
    // The simulation's own split of the step (medians over the steps).
    std::sort(contact_times.begin(), contact_times.end());
    std::sort(cut_times.begin(), cut_times.end());
    state.counters["contact_p50_us"] = percentile(contact_times, 0.50) * 1e6;
    state.counters["cut_p50_us"] = percentile(cut_times, 0.50) * 1e6;
  }
  if (c.brute_force) {
    g_brute_last_step_s = percentile(times, 0.50);
    g_brute_last_side = c.side;
  }
}

/// Memory of a run: a simulation of side^2 samples built and stepped; the
/// resident memory it adds, per sample, and the process's peak.
void bm_memory(benchmark::State& state, Case c) {
  for (auto _ : state) {
    reset_peak_rss();
    Rss before = read_rss();
    auto run = std::make_unique<Runner>(c);
    for (int i = 0; i < c.steps; ++i) {
      run->advance();
      run->step();
    }
    Rss after = read_rss();
    double samples = double(c.side) * double(c.side);
    state.counters["bytes_per_sample"] = (after.current - before.current) / samples;
    state.counters["grid_bytes_per_sample"] = 2.0 * sizeof(float);  // height, initial
    state.counters["rss_mib"] = after.current / (1024.0 * 1024.0);
    state.counters["peak_rss_mib"] = after.peak / (1024.0 * 1024.0);
    state.counters["constant_mib"] = (after.current - 2.0 * sizeof(float) * samples) / (1024.0 * 1024.0);
    state.counters["side"] = c.side;
  }
}

const char* rep_name(Representation r) { return r == Representation::kColumns ? "columns" : "surface"; }

void register_all() {
  const Representation reps[] = {Representation::kSurface, Representation::kColumns};
  // (a) The headline: full-width blade on 4096^2, straight and at 30 degrees of yaw.
  for (Representation rep : reps) {
    for (double yaw : {0.0, 30.0}) {
      Case c{rep, 4096, 0.0, yaw, false, 5000, 300};
      std::string name = std::string("headline/") + rep_name(rep) + "/yaw:" + std::to_string(int(yaw)) +
                         "/side:4096";
      benchmark::RegisterBenchmark(name.c_str(), bm_steps, c)
          ->Iterations(c.steps)->Repetitions(kRepetitions)->UseManualTime()->Unit(benchmark::kMicrosecond);
    }
  }
  // (a2) Every direction: a blade of 0.7 x the side moving along its own
  // normal across the middle of 4096^2, at several yaws, and a tilted blade
  // (rotated about its travel) against the same blade level.
  for (Representation rep : reps) {
    for (double yaw : {0.0, 10.0, 15.0, 30.0, 37.0, 45.0, 53.0, 60.0, 75.0, 82.0, 89.0, 90.0}) {
      Case c{rep, 4096, kDirectionBladeFraction * 4096, yaw, false, 4000, 300, true};
      std::string name = std::string("direction/") + rep_name(rep) + "/yaw:" + std::to_string(int(yaw)) +
                         "/side:4096";
      benchmark::RegisterBenchmark(name.c_str(), bm_steps, c)
          ->Iterations(c.steps)->Repetitions(kRepetitions)->UseManualTime()->Unit(benchmark::kMicrosecond);
    }
    for (double tilt : {0.0, 20.0}) {
      Case c{rep, 4096, kTiltBladeCells, 0.0, false, 4000, 300, true, tilt};
      std::string name = std::string("tilt/") + rep_name(rep) + "/tilt:" + std::to_string(int(tilt)) +
                         "/blade:400/side:4096";
      benchmark::RegisterBenchmark(name.c_str(), bm_steps, c)
          ->Iterations(c.steps)->Repetitions(kRepetitions)->UseManualTime()->Unit(benchmark::kMicrosecond);
    }
  }
  // (b) A 256-cell blade on growing terrains: the step should not grow.
  for (Representation rep : reps) {
    for (int side = 256; side <= 8192; side *= 2) {
      Case c{rep, side, 256.0, 0.0, false, 3000, 200};
      std::string name = std::string("blade256/") + rep_name(rep) + "/side:" + std::to_string(side);
      benchmark::RegisterBenchmark(name.c_str(), bm_steps, c)
          ->Iterations(c.steps)->Repetitions(kRepetitions)->UseManualTime()->Unit(benchmark::kMicrosecond);
    }
  }
  // (c) A full-width blade on growing terrains: the step grows with the side.
  for (Representation rep : reps) {
    for (int side = 64; side <= 8192; side *= 2) {
      Case c{rep, side, 0.0, 0.0, false, 3000, 200};
      std::string name = std::string("full_width/") + rep_name(rep) + "/side:" + std::to_string(side);
      benchmark::RegisterBenchmark(name.c_str(), bm_steps, c)
          ->Iterations(c.steps)->UseManualTime()->Unit(benchmark::kMicrosecond);
    }
  }
  // (d) The paper's brute force on the same full-width case, up to the side
  // where one step would take more than kBruteForceLimitS.
  for (Representation rep : reps) {
    for (int side = 64; side <= 8192; side *= 2) {
      int steps = std::clamp(int(2.0e7 / (double(side) * side)), 3, 200);
      Case c{rep, side, 0.0, 0.0, true, steps, side <= 256 ? 2 : 0};
      std::string name = std::string("brute_force/") + rep_name(rep) + "/side:" + std::to_string(side);
      benchmark::RegisterBenchmark(name.c_str(), [](benchmark::State& s, Case cc) {
        // Reset the skip prediction at the start of each representation's series.
        if (cc.side == 64) g_brute_last_side = 0;
        bm_steps(s, cc);
      }, c)->Iterations(c.steps)->UseManualTime()->Unit(benchmark::kMillisecond);
    }
  }
  // (e) Memory of a run at 8192^2.
  for (Representation rep : reps) {
    Case c{rep, 8192, 0.0, 0.0, false, 1000, 0};
    std::string name = std::string("memory/") + rep_name(rep) + "/side:8192";
    benchmark::RegisterBenchmark(name.c_str(), bm_memory, c)->Iterations(1)->Unit(benchmark::kMillisecond);
  }
}

}  // namespace

int main(int argc, char** argv) {
  register_all();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
