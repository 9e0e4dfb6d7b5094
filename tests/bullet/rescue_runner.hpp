// Runs a scenario with rigid bodies end to end, in memory, the way `terracut
// run` drives the Bullet world: load_scenario reads `bodies:` with the
// bodies' own reader (BodiesReader); then the bodies' listener (bullet/bodies_listener.hpp)
// on the Simulation, which lifts its plate with sim.lift(), steps the world
// at the end of each sim.step and writes DIR/bodies.csv. Used by the rescue
// test, which checks every step's body states.
#pragma once

#include <cmath>
#include <filesystem>
#include <memory>
#include <vector>

#include "terracut/bullet/bodies_listener.hpp"
#include "terracut/bullet/bodies_yaml.hpp"
#include "terracut/io/scenario.hpp"

namespace terracut::test {

/// What a run with bodies produced, kept in memory for checks.
struct BodiesRun {
  std::vector<BodySpec> bodies;
  std::int64_t steps = 0;
  std::vector<double> t_s;                   ///< steps + 1 (the initial state first)
  std::vector<int> sequence_index;           ///< per step + 1 (-1 for the initial state)
  std::vector<bullet::BodyState> states;     ///< (steps + 1) x bodies, row-major
  std::vector<Vec3> tool_force_n;            ///< per step + 1
  std::vector<double> physics_s;             ///< per step: wall time of Bullet's step, seconds
  bullet::BoundsReport bounds{};
  std::int64_t csv_rows = 0;
  GridSpec grid{};
  std::vector<float> final_heights_m;        ///< rows x cols, row-major: the terrain at the end

  /// The highest and lowest heights (metres above ground) of the samples
  /// whose centres lie under the X-Z box [x0, x1] x [z0, z1], at the end.
  std::pair<double, double> heights_under(double x0, double x1, double z0, double z1) const {
    double lo = INFINITY, hi = -INFINITY;
    for (int r = 0; r < grid.rows; ++r)
      for (int c = 0; c < grid.cols; ++c) {
        const double x = grid.origin_m.x + (c + 0.5) * grid.cell_x_m();
        const double z = grid.origin_m.z + (r + 0.5) * grid.cell_z_m();
        if (x < x0 || x > x1 || z < z0 || z > z1) continue;
        const double h = final_heights_m[std::size_t(r) * std::size_t(grid.cols) + std::size_t(c)];
        lo = std::min(lo, h);
        hi = std::max(hi, h);
      }
    return {lo, hi};
  }

  const bullet::BodyState& state(std::int64_t k, int body) const {
    return states[std::size_t(k) * bodies.size() + std::size_t(body)];
  }
};

/// A scenario and its `bodies:` list.
struct BodiesScenario {
  io::Scenario base;
  std::vector<BodySpec> bodies;
};

/// Reads a scenario file with its `bodies:` section.
inline BodiesScenario load_with_bodies(const std::filesystem::path& path) {
  bullet::BodiesReader reader;
  io::SectionReader* const sections[] = {&reader};
  BodiesScenario out;
  out.base = io::load_scenario(path, sections);
  out.bodies = std::move(reader.bodies);
  return out;
}

/// Runs the scenario's sequence with its bodies; writes out_dir/bodies.csv
/// when out_dir is not empty.
inline BodiesRun run_with_bodies(const BodiesScenario& input, const std::filesystem::path& out_dir,
                                 const bullet::TerrainWorldParams& params = {}) {
  const io::Scenario& sc = input.base;
  Simulation sim(io::sim_params(sc), io::build_initial_heights(sc));
  bullet::BodiesListenerOptions options;
  options.world = params;
  if (!out_dir.empty()) {
    std::filesystem::create_directories(out_dir);
    options.csv_path = out_dir / "bodies.csv";
  }
  bullet::BodiesListener listener(sim, input.bodies, options);
  const bullet::TerrainWorld& world = listener.world();

  BodiesRun run;
  run.bodies = input.bodies;
  auto record = [&](int sequence_index) {
    run.t_s.push_back(world.time_s());
    run.sequence_index.push_back(sequence_index);
    for (int i = 0; i < world.body_count(); ++i) run.states.push_back(world.body_state(i));
    run.tool_force_n.push_back(world.last().tool_force_n);
  };
  record(-1);
  for (std::size_t k = 0; k < sc.sequence.size(); ++k) {
    const Motion& motion = sc.cuts[std::size_t(sc.sequence[k])];
    const std::int64_t n = std::llround(motion.duration_s() * sc.rate_hz) + 1;
    // Each cut is a separate stroke: the blade and its plate jump to its start.
    sim.lift();
    for (std::int64_t i = 0; i < n; ++i) {
      sim.step(motion.sample(double(i) / sc.rate_hz));
      run.physics_s.push_back(world.last().physics_s);
      record(int(k));
      ++run.steps;
    }
  }
  run.bounds = world.bounds();
  run.csv_rows = listener.csv_rows();
  run.grid = sim.grid().spec();
  run.final_heights_m.assign(sim.grid().heights(), sim.grid().heights() + run.grid.sample_count());
  listener.finish();
  return run;
}

}  // namespace terracut::test
