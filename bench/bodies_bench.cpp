// Benchmark of the rigid-body step (Bullet, bullet/terrain_world.hpp): the
// rescue scenario (scenarios/rescue.yaml: five bodies on 100 x 100 cells of
// 2 cm, four cuts) run through its sequence the way `terracut run` runs it,
// with the bodies' listener on the simulation. Each step's
// TerrainWorld::step (terrain change, tool plate, one Bullet step) is timed
// on its own (WorldStepInfo::total_s); p50 / p99 / max over the steps, over
// all of them and over those with at least one body awake (the steps that
// cost). Prints a Markdown table (and writes it to the file given as the
// first argument, for docs/bench/results.md).
//
// Cases: the terrain as Bullet's own triangles (merge_tolerance_m = 0, two
// triangles per square of samples, no cull: as before the merged collision),
// coplanar squares merged with every triangle of a body's box going to GJK
// (cull_far_triangles = false, as before the cull), and the default world
// (merged, and triangles no contact can come from culled; terrain_world.hpp).
// Each case runs three times; the table shows the run with the median p50.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "terracut/bullet/bodies_listener.hpp"
#include "terracut/core/stats.hpp"
#include "terracut/session/scenario.hpp"

namespace {

using namespace terracut;

struct RunFigures {
  TimingStats all{};
  TimingStats awake{};
  std::int64_t steps = 0;
  std::int64_t awake_steps = 0;
  double body_steps_per_step = 0.0;  ///< mean number of awake bodies per step
};

RunFigures run_rescue(const session::Scenario& sc, const bullet::TerrainWorldParams& params) {
  Simulation sim(io::sim_params(sc.base), io::build_initial_heights(sc.base));
  bullet::BodiesListenerOptions options;
  options.world = params;
  bullet::BodiesListener listener(sim, sc.bodies, options);
  const bullet::TerrainWorld& world = listener.world();
  std::vector<double> all, awake;
  std::int64_t awake_bodies = 0;
  for (int index : sc.base.sequence) {
    const Motion& motion = sc.base.cuts[std::size_t(index)];
    const std::int64_t n = std::llround(motion.duration_s() * sc.base.rate_hz) + 1;
    sim.lift();
    for (std::int64_t i = 0; i < n; ++i) {
      sim.step(motion.sample(double(i) / sc.base.rate_hz));
      const double t = world.last().total_s;
      all.push_back(t);
      int active = 0;
      for (int b = 0; b < world.body_count(); ++b) active += world.body_state(b).active ? 1 : 0;
      awake_bodies += active;
      if (active > 0) awake.push_back(t);
    }
  }
  RunFigures f;
  f.steps = std::int64_t(all.size());
  f.awake_steps = std::int64_t(awake.size());
  f.body_steps_per_step = double(awake_bodies) / double(std::max<std::int64_t>(f.steps, 1));
  f.all = timing_stats(all);
  f.awake = timing_stats(awake);
  return f;
}

RunFigures median_of_three(const session::Scenario& sc, const bullet::TerrainWorldParams& params) {
  std::vector<RunFigures> runs;
  for (int k = 0; k < 3; ++k) runs.push_back(run_rescue(sc, params));
  std::sort(runs.begin(), runs.end(),
            [](const RunFigures& a, const RunFigures& b) { return a.all.p50_us < b.all.p50_us; });
  return runs[1];
}

}  // namespace

int main(int argc, char** argv) {
  // Optional arguments: the file the table is also written to, and a scenario.
  if (argc > 3 || (argc >= 2 && argv[1][0] == '-') || (argc == 3 && argv[2][0] == '-')) {
    std::fprintf(stderr, "usage: terracut_bench_bodies [TABLE.md [SCENARIO.yaml]]\n"
                         "Times the Bullet world's step over the scenario (default: scenarios/rescue.yaml).\n");
    return argc == 2 && std::string(argv[1]) == "--help" ? 0 : 2;
  }
  const std::filesystem::path scenario =
      argc > 2 ? std::filesystem::path(argv[2])
               : std::filesystem::path(TERRACUT_SOURCE_DIR) / "scenarios" / "rescue.yaml";
  const session::Scenario sc = session::load_scenario(scenario);

  std::string table =
      "| rescue bodies step (5 bodies, 100^2 cells of 2 cm) | steps | p50 | p99 | max | "
      "steps with a body awake | their p50 | their p99 | awake bodies per step |\n"
      "|---|---|---|---|---|---|---|---|---|\n";
  struct Case {
    const char* name;
    double merge_tolerance_m;
    bool cull_far_triangles;
  };
  const bullet::TerrainWorldParams defaults{};
  const Case cases[] = {
      {"Bullet's triangles (2 per square, as before)", 0.0, false},
      {"coplanar squares merged, every triangle to GJK", defaults.merge_tolerance_m, false},
      {"merged, far triangles culled (default)", defaults.merge_tolerance_m,
       defaults.cull_far_triangles}};
  char line[512];
  RunFigures last{};
  for (const Case& c : cases) {
    bullet::TerrainWorldParams params;
    params.merge_tolerance_m = c.merge_tolerance_m;
    params.cull_far_triangles = c.cull_far_triangles;
    const RunFigures f = median_of_three(sc, params);
    std::snprintf(line, sizeof line,
                  "| %s | %lld | %.1f us | %.1f us | %.1f us | %lld | %.1f us | %.1f us | %.2f |\n",
                  c.name, static_cast<long long>(f.steps), f.all.p50_us, f.all.p99_us,
                  f.all.max_us, static_cast<long long>(f.awake_steps), f.awake.p50_us,
                  f.awake.p99_us, f.body_steps_per_step);
    table += line;
    std::fputs(line, stdout);
    std::fflush(stdout);
    last = f;
  }
  // The target for the default world (the last case).
  const bool met = last.all.p50_us <= 60.0 && last.all.p99_us <= 200.0;
  std::snprintf(line, sizeof line,
                "\nTarget (default world): p50 <= 60 us, p99 <= 200 us per step: p50 %.1f us, "
                "p99 %.1f us: %s.\n",
                last.all.p50_us, last.all.p99_us, met ? "met" : "**missed**");
  table += line;
  std::fputs(line, stdout);
  if (argc > 1) std::ofstream(argv[1]) << table;
  return 0;
}
