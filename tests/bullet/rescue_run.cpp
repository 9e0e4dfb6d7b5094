// bullet_rescue_run SCENARIO OUT_DIR: runs a scenario with `bodies:` (e.g.
// scenarios/rescue.yaml): first the usual `terracut run` outputs
// (io::run_scenario: contact.csv, heights, summary.json), then the same
// sequence through the Simulation and the Bullet world, writing
// OUT_DIR/bodies.csv; prints each body's start and end pose. A stand-in for
// `terracut run` until the lead wires bodies into it.
#include <algorithm>
#include <cstdio>
#include <exception>

#include "rescue_runner.hpp"

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: %s SCENARIO OUT_DIR\n", argv[0]);
    return 2;
  }
  try {
    const terracut::io::Scenario scenario = terracut::io::load_scenario(argv[1]);
    terracut::io::RunOptions options;
    options.out_dir = argv[2];
    terracut::io::run_scenario(scenario, options);
    const terracut::test::BodiesRun run = terracut::test::run_with_bodies(scenario, argv[2]);
    std::printf("%lld steps, %lld rows in %s/bodies.csv, %lld heights clamped\n",
                static_cast<long long>(run.steps), static_cast<long long>(run.csv_rows), argv[2],
                static_cast<long long>(run.bounds.clamped_total));
    std::vector<double> t = run.physics_s;
    std::sort(t.begin(), t.end());
    auto pct = [&](double p) { return t[std::size_t(p * double(t.size() - 1))] * 1e6; };
    std::printf("Bullet step wall time: p50 %.0f us, p90 %.0f us, p99 %.0f us, max %.0f us\n",
                pct(0.5), pct(0.9), pct(0.99), pct(1.0));
    for (std::size_t i = 0; i < run.bodies.size(); ++i) {
      const auto& a = run.state(0, int(i));
      const auto& b = run.state(run.steps, int(i));
      std::printf("%-10s start (%.4f, %.4f, %.4f)  end (%.4f, %.4f, %.4f)  q_end (%.4f, %.4f, %.4f, %.4f)\n",
                  run.bodies[i].name.c_str(), a.position_m.x, a.position_m.y, a.position_m.z,
                  b.position_m.x, b.position_m.y, b.position_m.z, b.orientation.w,
                  b.orientation.x, b.orientation.y, b.orientation.z);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
