// scenarios/rescue.yaml with soil that flows (soil: {model: flow}): the
// Bullet bodies are obstacles for the soil, and nothing leaves the books.
// The volume of soil is kept to float rounding over the whole sequence (the
// blade cutting under and beside bodies, piles banking against them), no
// pile rises past the heightfield's upper bound (which would clamp, and so
// delete, soil), and no soil is put down under a body resting on the sand.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "rescue_runner.hpp"

namespace terracut::test {
namespace {

TEST(FlowWithBodies, TheRescueKeepsItsSoilToFloatRounding) {
  BodiesScenario input =
      load_with_bodies(std::filesystem::path(TERRACUT_SOURCE_DIR) / "scenarios/rescue.yaml");
  input.base.soil.model = SoilModel::kFlow;
  const io::Scenario& sc = input.base;
  Simulation sim(io::sim_params(sc), io::build_initial_heights(sc));
  bullet::BodiesListener listener(sim, input.bodies, {});
  const double before = sim.grid().volume_m3();
  for (int s : sc.sequence) {
    const Motion& motion = sc.cuts[std::size_t(s)];
    const std::int64_t n = std::llround(motion.duration_s() * sc.rate_hz) + 1;
    sim.lift();
    for (std::int64_t i = 0; i < n; ++i) sim.step(motion.sample(double(i) / sc.rate_hz));
  }
  const HeightGrid& g = sim.grid();
  const bullet::BoundsReport& bounds = listener.world().bounds();
  EXPECT_EQ(bounds.clamped_total, 0);
  float highest = 0.0f;
  for (std::int64_t i = 0; i < g.spec().sample_count(); ++i) highest = std::max(highest, g.heights()[i]);
  EXPECT_LE(double(highest), bounds.max_height_m);
  EXPECT_GT(double(highest), double(sc.generator->plane.height_m));  // piles stand above the layer
  // One float rounding (eps x the highest height) per sample: 3.8e-7 m^3 here.
  const double tolerance = double(g.spec().sample_count()) *
                           double(std::numeric_limits<float>::epsilon()) * double(highest) *
                           g.spec().cell_area_m2();
  EXPECT_NEAR(g.volume_m3(), before, tolerance);
}

}  // namespace
}  // namespace terracut::test
