// Benchmark of the soil phase (soil.hpp, `soil: {model: flow}`): the step
// cost of a blade bulldozing a layer, and of a collapsing pile spread over
// ticks by the work cap. Prints a Markdown table (and writes it to the file
// given as the first argument, for docs/bench/results.md).
//
// Cases, 1 cm cells, repose 34 degrees, the default work cap (100000 pair
// checks per step):
//  - bulldoze/side:N: a 2 m blade cutting 5 cm into a 20 cm layer, moving
//    0.6 mm per step (0.6 m/s at 1 kHz) for 1 m along +Z, on an N x N grid
//    (the grid's size must not matter: the phase walks only active cells);
//  - collapse: a 100 x 100-cell block 0.5 m tall collapsing, relaxation
//    only, until it settles: the soil time of every tick.
// Each step is timed with steady_clock; p50 / p99 / max over the steps.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "terracut/core/simulation.hpp"
#include "terracut/core/soil.hpp"

namespace {

using namespace terracut;
using Clock = std::chrono::steady_clock;

struct Stats {
  double p50_us = 0.0, p99_us = 0.0, max_us = 0.0;
  std::int64_t steps = 0, max_backlog = 0;
};

Stats stats_of(std::vector<double>& s, std::int64_t max_backlog) {
  std::sort(s.begin(), s.end());
  Stats out;
  out.steps = std::int64_t(s.size());
  out.p50_us = s[s.size() / 2] * 1e6;
  out.p99_us = s[std::min(s.size() - 1, s.size() * 99 / 100)] * 1e6;
  out.max_us = s.back() * 1e6;
  out.max_backlog = max_backlog;
  return out;
}

Stats bulldoze(int side) {
  const double cell = 0.01;
  SimParams p;
  p.grid = grid_of_cells(side, side, cell);
  p.blade.length_m = 2.0;
  p.soil.model = SoilModel::kFlow;
  Simulation sim(p, std::vector<float>(std::size_t(side) * side, 0.2f));
  const double x = 0.5 * side * cell, z0 = 0.5 * side * cell - 0.5;
  const int n = int(std::lround(1.0 / 0.0006));
  std::vector<double> times;
  std::int64_t backlog = 0;
  for (int i = 0; i <= n; ++i) {
    const BladePose pose{{x, 0.15, z0 + 1.0 * i / n}, Quat{}};
    const StepOutput& out = sim.step(pose);
    times.push_back(out.timers.cut_s + out.timers.soil_s);
    backlog = std::max(backlog, out.soil.backlog_cells);
  }
  return stats_of(times, backlog);
}

Stats collapse() {
  const int side = 300;
  const GridSpec spec = grid_of_cells(side, side, 0.01);
  std::vector<float> h(std::size_t(side) * side, 0.0f);
  for (int r = 100; r < 200; ++r)
    for (int c = 100; c < 200; ++c) h[std::size_t(r) * side + c] = 0.5f;
  HeightGrid grid(spec, h);
  SoilFlowParams p;
  p.model = SoilModel::kFlow;
  SoilFlow flow(p, grid);
  std::vector<double> times;
  std::int64_t backlog = 0;
  while (flow.active_cells() > 0) {
    const Clock::time_point t0 = Clock::now();
    const SoilStepResult r = flow.relax(grid);
    times.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
    backlog = std::max(backlog, r.backlog_cells);
  }
  return stats_of(times, backlog);
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
      "| soil case (1 cm cells, repose 34 deg) | steps | p50 | p99 | max | largest backlog |\n"
      "|---|---|---|---|---|---|\n";
  char line[256];
  for (int side : {512, 2048, 8192}) {
    const Stats s = bulldoze(side);
    std::snprintf(line, sizeof line,
                  "| 2 m blade bulldozing a 5 cm cut, %d^2 grid (cut + soil per step) | %lld | "
                  "%.1f us | %.1f us | %.1f us | %lld cells |\n",
                  side, static_cast<long long>(s.steps), s.p50_us, s.p99_us, s.max_us,
                  static_cast<long long>(s.max_backlog));
    table += line;
    std::fputs(line, stdout);
    std::fflush(stdout);
  }
  const Stats c = collapse();
  std::snprintf(line, sizeof line,
                "| 100 x 100-cell block 0.5 m tall collapsing (soil per tick) | %lld | %.1f us | "
                "%.1f us | %.1f us | %lld cells |\n",
                static_cast<long long>(c.steps), c.p50_us, c.p99_us, c.max_us,
                static_cast<long long>(c.max_backlog));
  table += line;
  std::fputs(line, stdout);
  if (argc > 1) std::ofstream(argv[1]) << table;
  return 0;
}
