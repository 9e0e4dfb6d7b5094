// A blade of finite height (BladeSpec::height_m) holds soil up to its top;
// what stands higher against it falls over to the other side (soil.hpp,
// soil_top.cpp; docs/soil.md "Soil over the blade's top").
#include "terracut/core/soil.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include "terracut/core/error.hpp"
#include "terracut/core/simulation.hpp"

namespace terracut {
namespace {

constexpr double kLayer = 0.2;   // the soil's surface, m
constexpr double kDepth = 0.05;  // the cut, m
constexpr double kRepose = 34.0;
constexpr double kCell = 0.01;

// The volume the float heights can drift by in a run that gives each
// step's rounding back: one float rounding (eps x the highest height) a
// sample.
double float_rounding_m3(const HeightGrid& g, double highest_m) {
  return double(g.spec().sample_count()) * double(std::numeric_limits<float>::epsilon()) * highest_m *
         g.spec().cell_area_m2();
}

SimParams flow_params(int cols, int rows, double blade_m, double height_m) {
  SimParams p;
  p.grid = grid_of_cells(cols, rows, kCell);
  p.blade.length_m = blade_m;
  p.blade.height_m = height_m;
  p.soil.model = SoilModel::kFlow;
  p.soil.material.repose_deg = kRepose;
  return p;
}

// Where cell (c, r)'s centre lies against the edge: its distance across
// the edge's line in plan (positive on the side of the normal (-ez, ex),
// the blade frame's +Z for a level blade), where along the edge (0 to 1),
// and the top's height there.
struct Against {
  double n, t, top;
};
Against against(const Segment& e, double height_m, const Quat& q, int c, int r) {
  const double ex = e.b.x - e.a.x, ez = e.b.z - e.a.z, len = std::hypot(ex, ez);
  const double x = (c + 0.5) * kCell - e.a.x, z = (r + 0.5) * kCell - e.a.z;
  const double t = (x * ex + z * ez) / (len * len);
  const double up = std::max(0.0, rotate(q, {0.0, 1.0, 0.0}).y);
  return {(ex * z - ez * x) / len, t, e.a.y + t * (e.b.y - e.a.y) + height_m * up};
}

// A 1 m blade 0.1 m tall cutting 5 cm of a 0.2 m layer and pushing it
// 1.5 m along its normal at 1 m/s on 1 cm cells, square to the grid,
// turned 30 and 90 degrees, and rolled 3 degrees (one end 5 cm deeper than
// the other): the pile ahead grows until it reaches the top, and from then
// on what the push adds falls over onto the trench behind. At the end of
// every step no cell against the blade (its centre within three halves of
// a cell's width across the edge's line, where the displacement puts its
// first soil) stands above the top there, to a float rounding, but where
// the blade is buried (soil across it at its top): the rolled blade's low
// end, where the spill round that end fills the trench behind it from the
// pile fed along the face by the higher end; the volume is kept; and the
// soil the steps report over the top lies in the trench behind the blade.
TEST(SoilTop, APushedPileNeverStandsAboveTheBladesTop) {
  const int n = 300;
  const double blade = 1.0, height = 0.1, edge_y = kLayer - kDepth, travel = 1.5;
  const double slope = std::tan(kRepose * std::numbers::pi / 180.0);
  struct Case {
    double yaw_deg, roll_deg;
  };
  for (const Case k : {Case{0.0, 0.0}, Case{30.0, 0.0}, Case{90.0, 0.0}, Case{0.0, 3.0}}) {
    SCOPED_TRACE(testing::Message() << "yaw " << k.yaw_deg << " roll " << k.roll_deg);
    SimParams p = flow_params(n, n, blade, height);
    Simulation sim(p, std::vector<float>(std::size_t(n) * n, float(kLayer)));
    const double before = sim.grid().volume_m3();
    const double yaw = k.yaw_deg * std::numbers::pi / 180.0;
    const Quat q = quat_from_axis_angle({0.0, 1.0, 0.0}, yaw) *
                   quat_from_axis_angle({0.0, 0.0, 1.0}, k.roll_deg * std::numbers::pi / 180.0);
    const double mx = std::sin(yaw), mz = std::cos(yaw);  // the push: the blade frame's +Z
    double over = 0.0, worst = -1.0, lowest_top = 1e9;
    int bare = 0;  // cells against the blade above its top with no soil across at the top
    int worst_step = -1;
    const int steps = int(std::lround(travel * 1000.0));
    Segment edge{};
    for (int i = 0; i <= steps; ++i) {
      const double along = 0.001 * i - 0.5 * travel;
      const BladePose pose{{1.5 + mx * along, edge_y, 1.5 + mz * along}, q};
      over += sim.step(pose).soil.over_top_m3;
      edge = blade_segment(p.blade, pose);
      const HeightGrid& g = sim.grid();
      const int c0 = int(std::min(edge.a.x, edge.b.x) / kCell) - 3, c1 = int(std::max(edge.a.x, edge.b.x) / kCell) + 3;
      const int r0 = int(std::min(edge.a.z, edge.b.z) / kCell) - 3, r1 = int(std::max(edge.a.z, edge.b.z) / kCell) + 3;
      const double half = 0.5 * kCell * (std::abs(mx) + std::abs(mz));
      for (int r = std::max(r0, 0); r <= std::min(r1, n - 1); ++r)
        for (int c = std::max(c0, 0); c <= std::min(c1, n - 1); ++c) {
          const Against a = against(edge, height, q, c, r);
          if (std::abs(a.n) > 3.0 * half || a.t < 0.0 || a.t > 1.0) continue;
          lowest_top = std::min(lowest_top, a.top);
          const double above = double(g.height(c, r)) - a.top;
          if (above <= 1e-6) continue;
          // Above the top: only where the blade is buried, the soil across
          // it (the first cell clear of it on the other side, at the same
          // point of the edge) at its top less a cell's repose drop or
          // higher.
          const double land = 2.0 * half + 0.01 * kCell, side = a.n > 0.0 ? -1.0 : 1.0;
          const double px = edge.a.x + a.t * (edge.b.x - edge.a.x) + side * land * mx;
          const double pz = edge.a.z + a.t * (edge.b.z - edge.a.z) + side * land * mz;
          const double across = g.height(int(px / kCell), int(pz / kCell));
          if (across < a.top - slope * kCell - 1e-6) ++bare;
          if (above > worst) worst = above, worst_step = i;
        }
    }
    EXPECT_EQ(bare, 0) << "the worst stood " << worst << " m above the top at step " << worst_step;
    // Square to the grid, turned and level, the trench behind stays open:
    // nothing stands above the top.
    if (k.roll_deg == 0.0) {
      EXPECT_LE(worst, 1e-6) << "at step " << worst_step;
    }
    EXPECT_NEAR(sim.grid().volume_m3(), before, float_rounding_m3(sim.grid(), lowest_top + 0.2));
    // The trench behind the blade, from its start line to its last edge:
    // what fell over lies there, with what the spill round the ends brought.
    const HeightGrid& g = sim.grid();
    double behind = 0.0;
    for (int r = 0; r < n; ++r)
      for (int c = 0; c < n; ++c) {
        const Against a = against(edge, height, q, c, r);
        if (a.n < 0.0 && a.n > -travel && a.t >= 0.0 && a.t <= 1.0)
          behind += std::max(0.0, double(g.height(c, r)) - (edge.a.y + a.t * (edge.b.y - edge.a.y))) * kCell * kCell;
      }
    EXPECT_GT(over, 0.01) << "little fell over: the pile never topped the blade";
    EXPECT_GE(behind, over * (1.0 - 1e-3));
  }
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
