// A blade of finite height (BladeSpec::height_m) holds soil up to its top;
// what stands higher against it falls over to the other side (soil.hpp,
// soil_top.cpp; docs/soil.md "Soil over the blade's top"). The pushes that
// watch every cell against the blade, square, turned and rolled, are the
// validation measure's (validation/top.hpp, tests/validation/top_test.cpp,
// `terracut validate` check 3.6).
#include "terracut/core/soil.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include "terracut/core/error.hpp"
#include "terracut/core/simulation.hpp"
#include "test_terrains.hpp"

namespace terracut {
namespace {

constexpr double kLayer = 0.2;   // the soil's surface, m
constexpr double kDepth = 0.05;  // the cut, m
constexpr double kRepose = 34.0;
constexpr double kCell = 0.01;

using test::float_rounding_m3;

SimParams flow_params(int cols, int rows, double blade_m, double height_m) {
  SimParams p;
  p.grid = grid_of_cells(cols, rows, kCell);
  p.blade.length_m = blade_m;
  p.blade.height_m = height_m;
  p.soil.model = SoilModel::kFlow;
  p.soil.material.repose_deg = kRepose;
  return p;
}

// A blade taller than its pile ever gets is the unbounded wall: the same
// heights bit for bit as the default (infinite height) over the same push,
// and nothing over the top.
TEST(SoilTop, ABladeTallerThanItsPileIsTheUnboundedWall) {
  const int cols = 120, rows = 160;
  const double x = 0.6, edge_y = kLayer - kDepth;
  std::vector<std::vector<float>> ends;
  for (const double height : {std::numeric_limits<double>::infinity(), 1.0}) {
    Simulation sim(flow_params(cols, rows, 0.8, height), std::vector<float>(std::size_t(cols) * rows, float(kLayer)));
    const Quat q = quat_from_axis_angle({0.0, 1.0, 0.0}, 20.0 * std::numbers::pi / 180.0);
    double over = 0.0;
    for (int i = 0; i <= 600; ++i) over += sim.step({{x, edge_y, 0.3 + 0.001 * i}, q}).soil.over_top_m3;
    EXPECT_EQ(over, 0.0);
    ends.emplace_back(sim.grid().heights(), sim.grid().heights() + std::size_t(cols) * rows);
  }
  EXPECT_EQ(ends[0], ends[1]);
}

// A pocket: a blade longer than the terrain is wide (its ends off the
// grid, whose edges are walls) pushes its cut 0.57 m toward a static body
// across the whole width, stops 3 cm short of it, and holds there. The
// soil between them can go nowhere but up. With an unbounded wall it
// stands 1.16 m high against the blade. With a 0.1 m blade what stands
// above the top falls over it and rests down the trench behind at the
// repose slope; once that slope is full the blade is buried, as a real one
// would be (here the trench behind is long enough to take it all). Held,
// every cell ahead of the blade stands under the top's repose cone (the
// top plus the repose rise from the blade's line to the cell's centre, and
// a cell's diagonal more for the stencil), every cell behind it under the
// top, and the volume is kept.
TEST(SoilTop, SoilPushedIntoAPocketFallsOverTheTop) {
  const int n = 100;
  const double edge_y = kLayer - kDepth, height = 0.1, top = edge_y + height;
  const Rect body{0, 70, n, 80};
  const double stop_z = body.r0 * kCell - 0.03;
  const double slope = std::tan(kRepose * std::numbers::pi / 180.0);
  const double diag = kCell * std::sqrt(2.0);
  double highest[2] = {0.0, 0.0}, ahead[2] = {-1.0, -1.0}, behind[2] = {-1.0, -1.0};
  int k = 0;
  for (const double h_m : {std::numeric_limits<double>::infinity(), height}) {
    Simulation sim(flow_params(n, n, 1.5, h_m), std::vector<float>(std::size_t(n) * n, float(kLayer)));
    const SoilObstacle obstacle{body, float(kLayer)};
    sim.soil()->set_obstacles({&obstacle, 1});
    const double before = sim.grid().volume_m3();
    double z = 0.1;
    for (int i = 0; i < 800; ++i) {
      z = std::min(stop_z, 0.1 + 0.001 * i);  // 0.57 m at 1 m/s, then held
      sim.step({{0.5, edge_y, z}, Quat{}});
    }
    const HeightGrid& g = sim.grid();
    for (int r = 0; r < body.r0; ++r) {
      const double d = (r + 0.5) * kCell - z;
      for (int c = 0; c < n; ++c) {
        const double h = g.height(c, r);
        highest[k] = std::max(highest[k], h);
        if (d > 0.0) ahead[k] = std::max(ahead[k], h - (top + slope * (d + diag)));
        else behind[k] = std::max(behind[k], h - top);
      }
    }
    EXPECT_NEAR(sim.grid().volume_m3(), before, float_rounding_m3(sim.grid(), 1.0 + highest[k]));
    ++k;
  }
  // Unbounded, the soil stands far above where a 0.1 m blade's top would be.
  EXPECT_GT(highest[0], top + 0.5);
  EXPECT_GT(ahead[0], 0.5);
  // With its top, the pocket rests under the top's cone, and what fell
  // over under the top.
  EXPECT_LE(ahead[1], 1e-6);
  EXPECT_LE(behind[1], 1e-6);
}

// Under a ceiling (a Bullet heightfield's upper bound, SoilFlow::set_ceiling)
// just above the top, no cell rises past the ceiling and no soil is lost
// (the ceiling's clamp would delete it): a 1 m blade 0.1 m tall pushes 1 m
// on 1 cm cells under a ceiling 2 mm above its top, turned 30 degrees, and
// soil goes over. (The spill's receivers stand under the top, so its own
// clamp to the ceiling is not reached here: this holds the step as a whole
// to the ceiling's bound with the spill in it.)
TEST(SoilTop, SoilOverTheTopStaysUnderTheCeiling) {
  const int n = 200;
  const double edge_y = kLayer - kDepth, height = 0.1, ceiling = edge_y + height + 0.002;
  Simulation sim(flow_params(n, n, 1.0, height), std::vector<float>(std::size_t(n) * n, float(kLayer)));
  sim.soil()->set_ceiling(float(ceiling));
  const double before = sim.grid().volume_m3();
  const double yaw = 30.0 * std::numbers::pi / 180.0;
  const Quat q = quat_from_axis_angle({0.0, 1.0, 0.0}, yaw);
  double over = 0.0;
  float highest = 0.0f;
  for (int i = 0; i <= 1000; ++i) {
    const double along = 0.001 * i - 0.5;
    over += sim.step({{1.0 + std::sin(yaw) * along, edge_y, 1.0 + std::cos(yaw) * along}, q}).soil.over_top_m3;
    for (std::int64_t k = 0; k < std::int64_t(n) * n; ++k) highest = std::max(highest, sim.grid().heights()[k]);
  }
  EXPECT_GT(over, 0.005);  // (the pile reaches the top half way)
  EXPECT_LE(highest, float(ceiling));
  EXPECT_NEAR(sim.grid().volume_m3(), before, float_rounding_m3(sim.grid(), ceiling));
}

// The walks down the other side have an allowance of their own, a cap's
// worth of cells a step: a 1.9 m blade whose top is level with the layer
// (everything it cuts goes over), on 5 mm cells at the smallest cap, 1000
// visits, walks
// past 1000 cells in some steps and is stopped there (the step reported at
// the cap), never past 1001; what is left goes over in later steps, and
// the volume is kept.
TEST(SoilTop, TheWalksStopAtTheirAllowance) {
  const int n = 400;
  const double edge_y = kLayer - kDepth;
  SimParams p = flow_params(n, n, 1.9, kDepth);
  p.grid = grid_of_cells(n, n, 0.005);
  p.soil.max_pair_checks_per_step = 1000;
  Simulation sim(p, std::vector<float>(std::size_t(n) * n, float(kLayer)));
  const double before = sim.grid().volume_m3();
  std::int64_t most = 0;
  int stopped = 0;
  double over = 0.0;
  for (int i = 0; i <= 800; ++i) {
    const StepOutput& out = sim.step({{1.0, edge_y, 0.5 + 0.001 * std::min(i, 600)}, Quat{}});
    most = std::max(most, out.soil.over_top_visits);
    if (out.soil.over_top_visits > p.soil.max_pair_checks_per_step) {
      ++stopped;
      EXPECT_TRUE(out.soil.reached_cap) << "step " << i;
    }
    over += out.soil.over_top_m3;
  }
  EXPECT_GT(stopped, 0) << "the allowance was never reached: the test walks too little (most " << most << ")";
  EXPECT_LE(most, p.soil.max_pair_checks_per_step + 1);
  EXPECT_GT(over, 0.01);
  EXPECT_NEAR(sim.grid().volume_m3(), before, float_rounding_m3(sim.grid(), 1.0));
}

// At the grid's edge: a blade spanning the terrain stands still with its
// back to the edge (its line 8 mm in, its edge 2 cm up, 2 cm tall), against
// a block of sand 6 cm tall, 20 cells wide and 10 deep, on bare ground
// (the block's slump stays 10 cells from every other edge). With
// `edge: open` what falls over the top leaves the terrain, counted as soil
// over the edge, and the volume on the grid plus what left is the volume
// before; with a wall (the default) nothing leaves and what has no room
// stays against the blade.
TEST(SoilTop, OverAnOpenEdgeWhatFallsOverLeavesTheTerrain) {
  const int n = 60;
  const double edge_y = 0.02, height = 0.02, top = edge_y + height, block = 0.06;
  for (const SoilEdge edge : {SoilEdge::kOpen, SoilEdge::kWall}) {
    SimParams p = flow_params(n, n, 1.0, height);
    p.soil.edge = edge;
    std::vector<float> h(std::size_t(n) * n, 0.0f);
    for (int r = 1; r <= 10; ++r)
      for (int c = 20; c < 40; ++c) h[std::size_t(r) * n + c] = float(block);
    Simulation sim(p, h);
    const double before = sim.grid().volume_m3();
    double over = 0.0, left = 0.0;
    for (int i = 0; i < 50; ++i) {
      const StepOutput& out = sim.step({{0.3, edge_y, 0.008}, Quat{}});
      over += out.soil.over_top_m3;
      left += out.soil.left_over_edge_m3;
    }
    const double slack = float_rounding_m3(sim.grid(), block);
    if (edge == SoilEdge::kOpen) {
      // All that went over left (behind the blade is off the grid), with a
      // little the block's corners shed over the edge beside the blade.
      EXPECT_GT(over, 1e-5);
      EXPECT_GE(left, over - slack);
      EXPECT_LT(left, 1.5 * over);
      EXPECT_NEAR(sim.grid().volume_m3() + left, before, slack);
    } else {
      EXPECT_EQ(left, 0.0);
      EXPECT_EQ(over, 0.0);
      EXPECT_NEAR(sim.grid().volume_m3(), before, slack);
      EXPECT_GT(double(sim.grid().height(30, 1)), top + 0.01);  // against the blade, no room behind
    }
  }
}

// A bad height is refused, naming the field; a bucket takes none.
TEST(SoilTop, ABadHeightIsRefusedByName) {
  for (const double bad : {0.0, -0.1, std::numeric_limits<double>::quiet_NaN(), -std::numeric_limits<double>::infinity()}) {
    SimParams p = flow_params(10, 10, 0.5, bad);
    EXPECT_EQ(validate(p).rfind("blade.height_m", 0), 0u) << validate(p);
    HeightGrid grid(p.grid, std::vector<float>(100, 0.2f));
    EXPECT_THROW(SoilFlow(p.soil, grid, p.blade), InputError);
  }
  SimParams p = flow_params(10, 10, 0.5, 0.3);
  EXPECT_EQ(validate(p), "");
  p.blade.bucket = {0.2, 0.1};
  EXPECT_EQ(validate(p).rfind("blade.height_m", 0), 0u) << validate(p);
}

}  // namespace
}  // namespace terracut
