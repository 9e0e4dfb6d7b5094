// Benchmark of the soil phase (soil.hpp, `soil: {model: flow}`): the step
// cost of a blade bulldozing a layer, and of a collapsing pile spread over
// ticks by the work cap. Prints a Markdown table (and writes it to the file
// given as the first argument, for docs/bench/results.md).
//
// Cases, 1 cm cells, repose 34 degrees, the default work cap (50000
// neighbour visits per step):
//  - bulldoze/side:N: a 2 m blade cutting 5 cm into a 20 cm layer, moving
//    0.6 mm per step (0.6 m/s at 1 kHz) for 1 m along +Z, on an N x N grid
//    (the grid's size must not matter: the phase walks only active cells),
//    and on 512^2 with the patches' settle (the default until 2026-12-07);
//    and the same push with a 1 m blade on 5 mm cells (1024^2 and 8192^2),
//    and turned 10 degrees (driven along its normal) with each settle of
//    the displaced pile, patches and fans (the default);
//  - scoop: a 1 m bucket (0.4 m floor, 0.2 m back: 0.04 m^3 struck) dragged
//    1 m along -Z on a 512 x 512 grid, 0.6 mm per step, heel up 7 degrees
//    as a bucket goes in (its floor and back are solid: a level floor in
//    the soil would shoulder what lies over it), the lip plunging from the
//    surface to 5 cm deep over the first 0.45 m (a ramp of 0.11, under the
//    floor's tan 7 = 0.123, so the floor rides over the cut rather than
//    pressing into it): it fills, then pushes a pile ahead as a blade does;
//  - collapse: a 100 x 100-cell block 0.5 m tall collapsing, relaxation
//    only, until it settles: the soil time of every tick.
// Each step is timed twice: on the wall clock (steady_clock, the step's
// cut + soil timers), and in CPU time of the calling thread
// (CLOCK_THREAD_CPUTIME_ID, the whole step): on a machine shared with other
// work the wall clock also counts the time the thread was not running (a
// preempted step reads 4 ms or more), the CPU time is the step's own work.
// p50 / p99 / max over the steps.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

#include <sys/resource.h>

#include "terracut/core/simulation.hpp"
#include "terracut/core/soil.hpp"
#include "soil_scenes.hpp"

namespace {

using namespace terracut;
using Clock = std::chrono::steady_clock;

/// CPU time of the calling thread, seconds.
double thread_cpu_s() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

struct Percentiles {
  double p50_us = 0.0, p99_us = 0.0, max_us = 0.0;
};

Percentiles percentiles(std::vector<double> s) {
  std::sort(s.begin(), s.end());
  return {s[s.size() / 2] * 1e6, s[std::min(s.size() - 1, s.size() * 99 / 100)] * 1e6, s.back() * 1e6};
}

struct Stats {
  Percentiles wall, cpu;
  std::int64_t steps = 0, max_backlog = 0;
};

/// The step times on the wall clock and in thread CPU time.
struct Samples {
  std::vector<double> wall, cpu;
  std::int64_t max_backlog = 0;
  Stats stats() const { return {percentiles(wall), percentiles(cpu), std::int64_t(wall.size()), max_backlog}; }
};

/// Drives the blade (or bucket) at `attitude` from `start` by `travel` in
/// `steps` steps (the pose at `start` too unless `from_start` is false, for
/// a leg that goes on from the last), adding the step times to `s`.
void drive(Simulation& sim, const Vec3& start, const Vec3& travel, int steps, Samples& s,
           const Quat& attitude = Quat{}, bool from_start = true) {
  for (int i = from_start ? 0 : 1; i <= steps; ++i) {
    const double t = double(i) / steps;
    const BladePose pose{{start.x + travel.x * t, start.y + travel.y * t, start.z + travel.z * t}, attitude};
    const double c0 = thread_cpu_s();
    const StepOutput& out = sim.step(pose);
    s.cpu.push_back(thread_cpu_s() - c0);
    s.wall.push_back(out.timers.cut_s + out.timers.soil_s);
    s.max_backlog = std::max(s.max_backlog, out.soil.backlog_cells);
  }
}

/// The push, the blade turned yaw_deg about +Y and driven along its normal,
/// its displaced pile settled as `settle` says.
Stats bulldoze(int side, double cell = 0.01, double blade_m = 2.0, double yaw_deg = 0.0,
               SoilSettle settle = SoilFlowParams{}.settle) {
  const scenes::Bulldoze scene{side, side, cell, blade_m, 0.2, 0.05};
  SoilFlowParams soil;
  soil.model = SoilModel::kFlow;
  soil.settle = settle;
  Simulation sim(scene.params(soil), scene.heights());
  const double z0 = 0.5 * side * cell - 0.5, yaw = yaw_deg * std::numbers::pi / 180.0;
  Samples s;
  drive(sim, scene.pose(z0).position_m, {std::sin(yaw), 0.0, std::cos(yaw)}, int(std::lround(1.0 / 0.0006)), s,
        quat_from_axis_angle({0.0, 1.0, 0.0}, yaw));
  return s.stats();
}

Stats scoop() {
  const int side = 512;
  const double cell = 0.01;
  SimParams p;
  p.grid = grid_of_cells(side, side, cell);
  p.blade.length_m = 1.0;
  p.blade.bucket = {0.4, 0.2};
  p.soil.model = SoilModel::kFlow;
  Simulation sim(p, std::vector<float>(std::size_t(side) * side, 0.2f));
  const double x = 0.5 * side * cell, z0 = 0.5 * side * cell + 0.5;
  const Quat heel_up = quat_from_axis_angle({1.0, 0.0, 0.0}, -7.0 * std::numbers::pi / 180.0);
  const double plunge_m = 0.45, depth_m = 0.05;
  Samples s;
  drive(sim, {x, 0.2, z0}, {0.0, -depth_m, -plunge_m}, int(std::lround(plunge_m / 0.0006)), s, heel_up);
  drive(sim, {x, 0.2 - depth_m, z0 - plunge_m}, {0.0, 0.0, -(1.0 - plunge_m)},
        int(std::lround((1.0 - plunge_m) / 0.0006)), s, heel_up, false);
  return s.stats();
}

/// Page faults of the calling thread so far (minor and major): a tick whose
/// CPU time is far above its work's is told apart by them (the kernel's
/// time on the thread's faults counts as its CPU time).
long thread_faults() {
  rusage u{};
  getrusage(RUSAGE_THREAD, &u);
  return u.ru_minflt + u.ru_majflt;
}

/// The collapse's worst tick: what it did, to tell work from the machine.
struct WorstTick {
  double cpu_us = 0.0;
  std::int64_t visits = 0;
  long faults = 0;
  int over_1ms = 0;
};
WorstTick collapse_worst;

Stats collapse() {
  const int side = 300;
  HeightGrid grid(grid_of_cells(side, side, 0.01), scenes::block(side, 100, 200, 0.5f));
  SoilFlowParams p;
  p.model = SoilModel::kFlow;
  SoilFlow flow(p, grid);
  Samples s;
  while (flow.active_cells() > 0) {
    const long f0 = thread_faults();
    const double c0 = thread_cpu_s();
    const Clock::time_point t0 = Clock::now();
    const SoilStepResult r = flow.relax(grid);
    s.wall.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
    s.cpu.push_back(thread_cpu_s() - c0);
    s.max_backlog = std::max(s.max_backlog, r.backlog_cells);
    const double cpu_us = s.cpu.back() * 1e6;
    collapse_worst.over_1ms += cpu_us > 1000.0 ? 1 : 0;
    if (cpu_us > collapse_worst.cpu_us)
      collapse_worst = {cpu_us, r.pair_checks, thread_faults() - f0, collapse_worst.over_1ms};
  }
  return s.stats();
}

/// One row of the table.
std::string row(const char* what, const Stats& s) {
  char line[320];
  std::snprintf(line, sizeof line,
                "| %s | %lld | %.1f us | %.1f us | %.1f us | %.1f us | %.1f us | %.1f us | %lld cells |\n", what,
                static_cast<long long>(s.steps), s.wall.p50_us, s.wall.p99_us, s.wall.max_us, s.cpu.p50_us,
                s.cpu.p99_us, s.cpu.max_us, static_cast<long long>(s.max_backlog));
  return line;
}

}  // namespace

int main(int argc, char** argv) {
  // One optional argument: the file the table is also written to.
  if (argc > 2 || (argc == 2 && argv[1][0] == '-')) {
    std::fprintf(stderr, "usage: terracut_bench_soil [TABLE.md]\n"
                         "Runs the soil-phase benchmarks and prints their table (and writes it to TABLE.md).\n");
    return argc == 2 && std::string(argv[1]) == "--help" ? 0 : 2;
  }
  std::string table =
      "| soil case (1 cm cells unless said, repose 34 deg) | steps | wall p50 | wall p99 | wall max | CPU p50 | CPU p99 | "
      "CPU max | largest backlog |\n"
      "|---|---|---|---|---|---|---|---|---|\n";
  const auto add = [&](const std::string& line) {
    table += line;
    std::fputs(line.c_str(), stdout);
    std::fflush(stdout);
  };
  for (int side : {512, 2048, 8192}) {
    const std::string what = "2 m blade bulldozing a 5 cm cut, " + std::to_string(side) +
                             "^2 grid (wall: cut + soil; CPU: the step)";
    add(row(what.c_str(), bulldoze(side)));
  }
  // The same on 512^2 with the settle of the default until 2026-12-07.
  add(row("2 m blade bulldozing a 5 cm cut, 512^2 grid, settle patches (wall: cut + soil; CPU: the step)",
          bulldoze(512, 0.01, 2.0, 0.0, SoilSettle::kPatches)));
  for (int side : {1024, 8192}) {
    const std::string what = "1 m blade bulldozing a 5 cm cut, 5 mm cells, " + std::to_string(side) +
                             "^2 grid (wall: cut + soil; CPU: the step)";
    add(row(what.c_str(), bulldoze(side, 0.005, 1.0)));
  }
  for (const SoilSettle settle : {SoilSettle::kPatches, SoilSettle::kFans}) {
    const std::string what = "1 m blade turned 10 deg, 5 mm cells, 1024^2 grid, settle " +
                             std::string(to_string(settle)) + " (wall: cut + soil; CPU: the step)";
    add(row(what.c_str(), bulldoze(1024, 0.005, 1.0, 10.0, settle)));
  }
  // At a slant on 1 cm cells, where the spill round the ends at a slant
  // (docs/soil.md, 2026-12-08) took this push's steps at the cap from 771
  // to 443 of 1668 (docs/performance.md, "The soil benchmark again").
  add(row("2 m blade turned 10 deg, 1 cm cells, 512^2 grid (wall: cut + soil; CPU: the step)",
          bulldoze(512, 0.01, 2.0, 10.0)));
  add(row("1 m bucket scooping a 5 cm cut, 512^2 grid (wall: cut + soil; CPU: the step)", scoop()));
  add(row("100 x 100-cell block 0.5 m tall collapsing (soil per tick)", collapse()));
  // Below the table: whether the collapse's worst tick was its work or the
  // machine (page faults, or time the kernel charged to the thread).
  char note[256];
  std::snprintf(note, sizeof note,
                "\nCollapse: %d ticks over 1 ms of CPU; the worst, %.1f us, did %lld neighbour visits and took %ld "
                "page faults.\n",
                collapse_worst.over_1ms, collapse_worst.cpu_us, static_cast<long long>(collapse_worst.visits),
                collapse_worst.faults);
  add(note);
  if (argc > 1) std::ofstream(argv[1]) << table;
  return 0;
}
