// The blade is a wall for flowing soil (soil.hpp): here the cases that
// need a scene of their own, a new stroke after a lift and the push_pile
// scenario. The measure over blades, yaws, speeds and motions (a blade that
// spans the terrain or runs in a closed channel, every sample it has passed
// watched for soil above the edge's height) is terracut::validation's
// (validation/wall.hpp), tested in tests/validation/wall_test.cpp and run
// by `terracut validate`.
#include "terracut/core/soil.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "terracut/core/simulation.hpp"

namespace terracut {
namespace {

constexpr double kLayer = 0.2;   // the soil's surface, m
constexpr double kDepth = 0.05;  // the cut, m
// A float step of heights near 0.3 m, with room for the rounding the
// relaxation gives back: far below any soil that crossed the blade.
constexpr double kFloatSlack = 1e-5;
constexpr double kDeg = std::numbers::pi / 180.0;

// A new stroke takes its way from its own motion, not from where the last
// stroke ended: after a lift, a blade set down 0.4 m short of where the
// last stroke stopped (the way from that stop to it points along -Z) and
// pushing slowly along +Z (0.05 m/s on 1 cm cells), with its edge just
// short of a row of centres, cuts that row in its first steps. Its soil goes ahead: the floor behind the blade stays
// at the edge's height. (Measured from the last stroke's end, the motion
// pointed back along -Z, and the first row's soil went behind.) The layer
// the blade cuts is 3 mm, so that its edge where the floor begins is a step
// gentler than the repose angle: nothing moves before the blade comes.
TEST(SoilWall, ANewStrokeAfterALiftPushesTheWayItMoves) {
  const int n = 100;
  const double cell = 0.01, edge_y = kLayer - kDepth, layer = 0.003;
  SimParams p;
  p.grid = grid_of_cells(n, n, cell);
  p.blade.length_m = 2.0;  // longer than the terrain is wide: no ends on it
  p.soil.model = SoilModel::kFlow;
  p.soil.material.repose_deg = 34.0;
  const double start_z = 0.5049;  // the row of centres at 0.505 is cut at once
  std::vector<float> h(std::size_t(n) * n, float(edge_y + layer));
  for (int r = 0; r < n; ++r)
    if ((r + 0.5) * cell < start_z)
      for (int c = 0; c < n; ++c) h[std::size_t(r) * n + c] = float(edge_y);
  Simulation sim(p, h);
  // The last stroke: 5 cm along +Z near the far side, at 0.5 m/s.
  for (int i = 0; i <= 100; ++i) sim.step({{0.5, edge_y, 0.85 + 0.0005 * i}, Quat{}});
  sim.lift();
  // The new one: 0.1 m along +Z from start_z at 0.05 m/s; the floor from
  // 0.2 m back to a cell and a half behind the edge.
  double worst = 0.0;
  for (int i = 0; i <= 2000; ++i) {
    const double z = start_z + 0.00005 * i;
    sim.step({{0.5, edge_y, z}, Quat{}});
    for (int r = 30; (r + 0.5) * cell < z - 1.5 * cell; ++r)
      for (int c = 0; c < n; ++c) worst = std::max(worst, double(sim.grid().height(c, r)) - edge_y);
  }
  EXPECT_LE(worst, kFloatSlack);
}

// scenarios/push_pile.yaml stepped as `terracut run` steps it: a 0.4 m blade
// along X plunges 5 cm into 0.3 m of dry sand on 1 cm cells while moving
// 0.1 m along -Z, then pushes 1 m along -Z at 0.5 m/s. Its edge stands
// exactly on a row of cell centres every 20 steps. The trench floor
// behind the middle of the blade (farther than the spill round its ends and
// the slump of the trench's walls can reach in the push: 6 cm either side of
// the centre line, from 3 cells behind the edge) stays at the edge's height.
TEST(SoilWall, ThePushPileScenariosTrenchStaysOpenBehindTheBlade) {
  for (const std::int64_t cap : {std::int64_t(50000), std::int64_t(1000000000)}) {
    SimParams p;
    p.grid = grid_of_cells(200, 200, 0.01);
    p.grid.origin_m = {-1.0, 0.0, -1.0};
    p.blade.length_m = 0.4;
    p.soil.model = SoilModel::kFlow;
    p.soil.material.repose_deg = 34.0;
    p.soil.max_pair_checks_per_step = cap;
    Simulation sim(p, std::vector<float>(200 * 200, 0.3f));
    struct Key {
      double t, y, z;
    };
    const Key keys[] = {{0.0, 0.35, 0.75}, {1.0, 0.35, 0.75}, {1.4, 0.25, 0.65}, {3.4, 0.25, -0.35}};
    double worst = 0.0;
    int worst_step = -1;
    for (int i = 0; i <= 3400; ++i) {
      const double t = i / 1000.0;
      int k = 0;
      while (k + 2 < 4 && t > keys[k + 1].t) ++k;
      const double f = (t - keys[k].t) / (keys[k + 1].t - keys[k].t);
      const double y = keys[k].y + f * (keys[k + 1].y - keys[k].y);
      const double z = keys[k].z + f * (keys[k + 1].z - keys[k].z);
      sim.step({{0.0, y, z}, Quat{}});
      if (t < 1.5) continue;  // from the push, the edge at 0.25 m
      for (int r = 0; r < 200; ++r) {
        const double zc = -1.0 + (r + 0.5) * 0.01;
        if (zc < z + 0.03 || zc > 0.6) continue;
        for (int c = 96; c < 104; ++c) {
          const double rise = double(sim.grid().height(c, r)) - 0.25;
          if (rise > worst) worst = rise, worst_step = i;
        }
      }
    }
    EXPECT_LE(worst, kFloatSlack) << "cap " << cap << ": worst at step " << worst_step;
  }
}

// A blade backing away from the pile it pushed, its line landing exactly on
// a row of cell centres every few steps (1/64 m cells, every position a
// multiple of 1/4096 m, so the ties are exact). A centre on the line once
// took soil from the side the edge came from: backing away, the pile's
// side. The next step's cut takes that centre with its swept region's first
// line (the region is closed), and the displacement pushed its soil the way
// the edge went, through the blade: 4.75 cm behind it. A centre on the line
// now takes soil from neither side (blade_blocks).
TEST(SoilWall, ABladeBackingAwayFromItsPileLeavesItThere) {
  for (const double back_m : {1.0 / 4096.0, 1.0 / 1024.0}) {
    const double cell = 1.0 / 64.0, edge = kLayer - kDepth, z_start = 0.25;
    const int n = 64;
    SimParams p;
    p.grid = grid_of_cells(n, n, cell);
    p.blade.length_m = 2.0;  // spanning the 1 m terrain: no ends to spill round
    p.soil.model = SoilModel::kFlow;
    p.soil.material.repose_deg = 34.0;
    // Behind the start the trench is already dug.
    std::vector<float> h(std::size_t(n) * n, float(kLayer));
    for (int r = 0; r < n; ++r)
      for (int c = 0; c < n; ++c)
        if ((r + 0.5) * cell < z_start) h[std::size_t(r) * n + c] = float(edge);
    Simulation sim(p, h);
    const auto pose = [&](double z) { return BladePose{{0.5, edge, z}, Quat{}}; };
    // The worst height above the trench floor more than a cell and a half
    // behind the line.
    double worst = -1.0;
    const auto watch = [&](double z_line) {
      for (int r = 0; r < n; ++r)
        for (int c = 0; c < n; ++c)
          if ((r + 0.5) * cell < z_line - 1.5 * cell) worst = std::max(worst, double(sim.grid().height(c, r)) - edge);
    };
    // Pushed 0.258 m at 0.24 m/s to a row of centres, held, then backed 0.2 m.
    const double z_far = 0.5 + 32.0 / 4096.0;  // (32 + 0.5) / 64
    double z = z_start;
    while (z < z_far) {
      z = std::min(z_far, z + 1.0 / 4096.0);
      sim.step(pose(z));
      watch(z);
    }
    for (int k = 0; k < 100; ++k) {
      sim.step(pose(z));
      watch(z);
    }
    EXPECT_LE(worst, kFloatSlack) << "pushing";
    while (z > 0.3) {
      z -= back_m;
      sim.step(pose(z));
      watch(z);
    }
    EXPECT_LE(worst, kFloatSlack) << "backing away at " << back_m << " m a step";
    // The pile followed the blade down its side: soil stands ahead of it.
    double ahead = 0.0;
    for (int r = 0; r < n; ++r)
      for (int c = 0; c < n; ++c)
        if ((r + 0.5) * cell > z) ahead = std::max(ahead, double(sim.grid().height(c, r)));
    EXPECT_GT(ahead, kLayer);
  }
}

// A 2 m blade spanning a 1 m terrain of 5 mm cells, its edge rolled 2.7
// degrees (one end lower), pushing at 0.32 m/s with a 3 mm, 10 Hz tremor
// along its travel and a 1-degree, 10.2 Hz wobble about the vertical: a
// case of a random sweep. The cut's sweep starts a millionth of a cell
// behind each step's first edge (consecutive sweeps overlap); there it cut
// a sample 6e-10 m on the pile's side of that edge, and the displacement
// pushed its column the way the edge went (that part of the blade was
// backing away), through the blade: 3.9 cm behind it. A sample the edge
// did not sweep keeps its side. Every sample the blade has
// passed, more than 1.5 cells behind its line, must stay at the height the
// edge cut it to (the edge slopes: each sample's own), to 1e-4 m (the
// height between the two steps' edges at a sample, on a sloped edge
// wobbling, differs from the edge's height at the sample's nearest point by
// up to 5e-5 m).
TEST(SoilWall, ARolledWobblingBladeKeepsThePileOnItsSide) {
  // (The case's figures to the last bit: the tie is exact.)
  const double cell = 0.005, travel = 0.3, speed = 0.32316245409807304, yaw0 = 132.10282959607562 * kDeg;
  const int n = 200;
  SimParams p;
  p.grid = grid_of_cells(n, n, cell);
  p.blade.length_m = 2.0;
  p.soil.model = SoilModel::kFlow;
  p.soil.material.repose_deg = 34.0;
  const double edge_y = kLayer - kDepth, roll = std::asin(0.035 / 0.75);
  const double nx = std::sin(yaw0), nz = std::cos(yaw0);
  const double seconds = travel / speed;
  const auto pose_at = [&](double s) {
    const double t = s * seconds;
    const double along = -0.5 * travel + travel * s + 0.003 * std::sin(2.0 * std::numbers::pi * 10.0 * t);
    const double wobble = 1.0 * kDeg * std::sin(2.0 * std::numbers::pi * 9.0 * 1.13 * t + 0.3);
    return BladePose{{0.5 + nx * along, edge_y, 0.5 + nz * along},
                     quat_from_axis_angle({0.0, 1.0, 0.0}, yaw0 + wobble) * quat_from_axis_angle({0.0, 0.0, 1.0}, roll)};
  };
  const auto edge_of = [&](const BladePose& pose) {
    const Vec3 half = rotate(pose.orientation, {1.0, 0.0, 0.0});
    return Segment{pose.position_m - half, pose.position_m + half};
  };
  // The edge's height over its nearest point to (x, z), and the signed
  // distance to its line (positive ahead).
  const auto height_at = [](const Segment& e, double x, double z) {
    const double dx = e.b.x - e.a.x, dz = e.b.z - e.a.z;
    const double t = std::clamp(((x - e.a.x) * dx + (z - e.a.z) * dz) / (dx * dx + dz * dz), 0.0, 1.0);
    return e.a.y + (e.b.y - e.a.y) * t;
  };
  const auto ahead_of = [](const Segment& e, double x, double z) {
    const double dx = e.b.x - e.a.x, dz = e.b.z - e.a.z;
    return (dx * (z - e.a.z) - dz * (x - e.a.x)) / std::hypot(dx, dz);
  };
  // Behind the start the trench is already dug, to the edge's height.
  const Segment start = edge_of(pose_at(0.0));
  std::vector<float> h(std::size_t(n) * n, float(kLayer));
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) {
      const double x = (c + 0.5) * cell, z = (r + 0.5) * cell;
      if (ahead_of(start, x, z) < 0.0) h[std::size_t(r) * n + c] = float(height_at(start, x, z));
    }
  Simulation sim(p, h);
  const int steps = int(std::lround(seconds * 1000.0));
  std::vector<double> floor(std::size_t(n) * n, NAN);  // the edge's height where it passed the sample
  double worst = -1.0;
  Segment last = start;
  for (int i = 0; i <= steps; ++i) {
    sim.step(pose_at(double(i) / steps));
    const Segment edge = sim.last().edge;
    for (int r = 0; r < n; ++r)
      for (int c = 0; c < n; ++c) {
        const std::size_t k = std::size_t(r) * n + c;
        const double x = (c + 0.5) * cell, z = (r + 0.5) * cell;
        const double d = ahead_of(edge, x, z);
        if (d >= 0.0) continue;
        if (std::isnan(floor[k])) floor[k] = std::max(height_at(edge, x, z), height_at(last, x, z));
        if (d < -1.5 * cell) worst = std::max(worst, double(sim.grid().height(c, r)) - floor[k]);
      }
    last = edge;
  }
  EXPECT_LE(worst, 1e-4);
}

}  // namespace
}  // namespace terracut
