// The blade is a wall for flowing soil (soil.hpp): no soil reaches the far
// side of a blade through it or under it, whatever the blade's length, yaw
// and speed, while it plunges, pushes, turns or lifts. Soil may reach the
// cut behind a blade only round its ends or down the trench's own walls, so
// the tests take both away: a blade longer than the terrain is wide (no
// ends on the grid), or a blade running in a channel closed by rigid
// obstacles beyond its ends whose cells stand at the trench floor (no walls,
// nothing to spill round). Then any soil that comes to stand above the
// trench floor behind the blade came through or under it. The floor behind
// is left by the cut at the edge's height, and where the edge moves up or
// down it is a ramp gentler than the repose angle, so nothing on it moves:
// the check is that no sample the blade has passed ever rises above the
// edge's height there (to float rounding).
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

constexpr double kDeg = std::numbers::pi / 180.0;
constexpr double kLayer = 0.2;   // the soil's surface, m
constexpr double kDepth = 0.05;  // the cut, m
// A float step of heights near 0.3 m, with room for the rounding the
// relaxation gives back: far below any soil that crossed the blade.
constexpr double kFloatSlack = 1e-5;

enum class Motion { kPush, kPlunge, kLift, kTurn };

const char* name(Motion m) {
  switch (m) {
    case Motion::kPush: return "push";
    case Motion::kPlunge: return "plunge";
    case Motion::kLift: return "lift";
    case Motion::kTurn: return "turn";
  }
  return "?";
}

struct WallCase {
  double length_m;      // the blade
  double yaw_deg;       // its yaw about +Y (0: along X, pushing along +Z)
  double speed_m_per_s; // along its travel, at 1 kHz
  Motion motion;
  bool channel;         // run between two rigid obstacles beyond its ends
  std::int64_t cap = 50000;
};

std::string describe(const WallCase& w) {
  return std::string(name(w.motion)) + ", " + std::to_string(w.length_m) + " m blade, yaw " +
         std::to_string(w.yaw_deg) + " deg, " + std::to_string(w.speed_m_per_s) + " m/s" +
         (w.channel ? ", in a channel" : ", spanning the terrain") + ", cap " + std::to_string(w.cap);
}

// The worst height above the edge's height, m, that a sample the blade had
// passed reached at any step (the far side of the blade, more than a cell
// and a half from its line).
double worst_rise_behind(const WallCase& w) {
  const double cell = 0.01;
  const double travel = 0.3;  // m
  const double yaw = w.yaw_deg * kDeg;
  // Spanning the terrain, the blade travels along its normal; in a channel
  // (along +Z), along +Z whatever its yaw, as an angled blade does.
  const double nx = w.channel ? 0.0 : std::sin(yaw), nz = w.channel ? 1.0 : std::cos(yaw);
  // A square terrain; the blade's centre crosses its middle.
  const double side_m = w.channel ? std::max(1.0, w.length_m + 0.4) : 1.0;
  const int n = int(std::lround(side_m / cell));
  // In the channel the blade starts with its centre on a row of cell
  // centres, where a level edge stands on them again and again.
  const double cx = 0.5 * side_m, cz = 0.5 * side_m + (w.channel ? 0.5 * cell : 0.0);
  SimParams p;
  p.grid = grid_of_cells(n, n, cell);
  // Spanning the terrain: longer than its diagonal, so its ends are off it.
  p.blade.length_m = w.channel ? w.length_m : 2.0 * side_m;
  p.soil.model = SoilModel::kFlow;
  p.soil.material.repose_deg = 34.0;
  p.soil.max_pair_checks_per_step = w.cap;
  const double edge_start = kLayer - kDepth;
  std::vector<float> h(std::size_t(n) * n, float(kLayer));
  std::vector<SoilObstacle> walls;
  if (w.channel) {
    // The blade's reach across the channel at the largest yaw it takes,
    // less two cells: its ends stay over the obstacles either side, whose
    // cells stand below the floor (no soil to cut or to slide off them) and
    // are closed to soil coming in.
    const double widest_yaw = std::abs(w.yaw_deg) + (w.motion == Motion::kTurn ? 8.0 : 0.0);
    const double half_channel = 0.5 * w.length_m * std::cos(widest_yaw * kDeg) - 2.0 * cell;
    const int c0 = int(std::ceil((cx - half_channel) / cell)), c1 = int(std::floor((cx + half_channel) / cell));
    for (int r = 0; r < n; ++r)
      for (int c = 0; c < n; ++c)
        if (c < c0 || c >= c1) h[std::size_t(r) * n + c] = float(edge_start - 0.06);
    walls.push_back({{0, 0, c0, n}, 0.0f});
    walls.push_back({{c1, 0, n, n}, 0.0f});
  }
  // The pose at step s in [0, 1]. The edge's height: level, down 4 cm
  // over the first two thirds (a ramp of 0.2, gentler than tan 34 deg =
  // 0.67), or up 4 cm so. Turning, the yaw swings from -8 to +8 degrees
  // about the blade's centre while it moves on (slowly enough that every
  // point of the blade over the terrain moves forward: none backs into the
  // trench, beside the uncut soil ahead of the starting line).
  const auto pose_at = [&](double s) {
    double y = edge_start;
    if (w.motion == Motion::kPlunge) y = kLayer - 0.01 - 0.04 * std::min(1.0, 1.5 * s);
    if (w.motion == Motion::kLift) y = edge_start + 0.04 * std::min(1.0, 1.5 * s);
    const double turn = w.motion == Motion::kTurn ? (-8.0 + 16.0 * s) * kDeg : 0.0;
    const double along = -0.5 * travel + travel * s;
    return BladePose{{cx + nx * along, y, cz + nz * along}, quat_from_axis_angle({0.0, 1.0, 0.0}, yaw + turn)};
  };
  // Behind the starting line the trench is already dug, to the edge's
  // height there: no back wall at the trench's start to slump into it.
  {
    const BladePose start = pose_at(0.0);
    const Vec3 e = rotate(start.orientation, {1.0, 0.0, 0.0});
    for (int r = 0; r < n; ++r)
      for (int c = 0; c < n; ++c) {
        const double x = (c + 0.5) * cell - start.position_m.x, z = (r + 0.5) * cell - start.position_m.z;
        if (e.x * z - e.z * x < 0.0) {
          float& v = h[std::size_t(r) * n + c];
          v = std::min(v, float(start.position_m.y));
        }
      }
  }
  Simulation sim(p, h);
  if (w.channel) sim.soil()->set_obstacles(walls);
  const int steps = int(std::lround(travel / w.speed_m_per_s * 1000.0));
  // Per sample: the side of the blade's line it started on, and the edge's
  // height where it passed it (NaN: not passed yet).
  std::vector<int> side0(std::size_t(n) * n, 0);
  std::vector<double> floor(std::size_t(n) * n, NAN);
  double worst = -1.0;
  for (int i = 0; i <= steps; ++i) {
    const double s = double(i) / steps;
    sim.step(pose_at(s));
    const Segment edge = sim.last().edge;
    // The last step's edge height over (x, z), from its pose (the edge is level across the blade).
    const auto last_edge_y = [&](double, double) { return i > 0 ? pose_at(double(i - 1) / steps).position_m.y : 0.0; };
    const double dxl = edge.b.x - edge.a.x, dzl = edge.b.z - edge.a.z;
    const double len = std::hypot(dxl, dzl);
    const HeightGrid& g = sim.grid();
    for (int r = 0; r < n; ++r)
      for (int c = 0; c < n; ++c) {
        const std::size_t k = std::size_t(r) * n + c;
        const double x = (c + 0.5) * cell, z = (r + 0.5) * cell;
        const double d = (dxl * (z - edge.a.z) - dzl * (x - edge.a.x)) / len;  // signed distance to the line
        const double t = ((x - edge.a.x) * dxl + (z - edge.a.z) * dzl) / (len * len);
        // The far side at the start is the trench already dug (to the
        // first edge's height): passed before the first step.
        if (i == 0) side0[k] = d > 0.0 ? 1 : -1;
        if (t < 0.0 || t > 1.0) continue;  // beyond the blade's ends
        const bool passed = (d > 0.0 ? 1 : -1) != side0[k] || side0[k] < 0;
        if (i == 0 && side0[k] < 0) floor[k] = pose_at(0.0).position_m.y;
        // The cut left it at the edge's height where the edge crossed its
        // centre, between this step's pose and the last.
        if (passed && std::isnan(floor[k]))
          floor[k] = std::max(edge.a.y + (edge.b.y - edge.a.y) * t, last_edge_y(x, z));
        if (!passed || std::abs(d) <= 1.5 * cell) continue;
        worst = std::max(worst, double(g.height(c, r)) - floor[k]);
      }
  }
  return worst;
}

// Each blade along X pushes along +Z; the blade spans the terrain.
TEST(SoilWall, NoSoilCrossesABladeSpanningTheTerrain) {
  const double speeds[] = {0.25, 1.0, 2.0};
  int k = 0;
  for (const Motion motion : {Motion::kPush, Motion::kPlunge, Motion::kLift, Motion::kTurn})
    for (const double yaw : {0.0, 17.0, 30.0, 45.0, 60.0, 90.0, 135.0}) {
      const WallCase w{1.0, yaw, speeds[k++ % 3], motion, false};
      EXPECT_LE(worst_rise_behind(w), kFloatSlack) << describe(w);
    }
}

TEST(SoilWall, NoSoilCrossesShortBladesInAChannel) {
  const double speeds[] = {2.0, 0.25, 1.0};
  int k = 0;
  for (const Motion motion : {Motion::kPush, Motion::kPlunge, Motion::kLift, Motion::kTurn})
    for (const double length : {0.2, 0.5, 1.0, 2.0})
      for (const double yaw : {0.0, 30.0}) {
        const WallCase w{length, yaw, speeds[k++ % 3], motion, true};
        EXPECT_LE(worst_rise_behind(w), kFloatSlack) << describe(w);
      }
}

TEST(SoilWall, NoSoilCrossesTheBladeWithTheWorkCapLifted) {
  for (const Motion motion : {Motion::kPush, Motion::kTurn})
    for (const double yaw : {0.0, 45.0}) {
      const WallCase w{1.0, yaw, 1.0, motion, false, 1000000000};
      EXPECT_LE(worst_rise_behind(w), kFloatSlack) << describe(w);
    }
}

// A slow blade: 0.05 to 0.1 m/s on 1 cm cells moves 0.05 to 0.1 mm a step,
// at most a hundredth of a cell. The tests of which way the blade goes once
// looked at one step's motion and took such a blade for one at rest: the
// displacement put the soil of each centre the edge had just passed on that
// centre's own side, behind the blade, and the settle walled off only the
// cells the edge passes through, so a diagonal pair stepped over it (on this
// code before it 3.7 to 5.8 cm of soil stood behind every one of them). The motion is now
// measured since the blade last moved a fiftieth of a cell.
TEST(SoilWall, NoSoilCrossesASlowBlade) {
  int k = 0;
  for (const Motion motion : {Motion::kPush, Motion::kPlunge, Motion::kLift, Motion::kTurn})
    for (const double yaw : {0.0, 197.0}) {
      const WallCase w{1.0, yaw, k++ % 2 == 0 ? 0.1 : 0.05, motion, false};
      EXPECT_LE(worst_rise_behind(w), kFloatSlack) << describe(w);
    }
  for (const Motion motion : {Motion::kPush, Motion::kTurn}) {
    const WallCase w{1.2, 19.0, 0.08, motion, true};
    EXPECT_LE(worst_rise_behind(w), kFloatSlack) << describe(w);
  }
}

// A new stroke takes its way from its own motion, not from where the last
// stroke ended: after a lift, a blade set down 0.35 m back from where the
// last stroke stopped and pushing slowly the other way (+Z, 0.05 m/s on
// 1 cm cells), with its edge just short of a row of centres, cuts that row
// in its first steps. Its soil goes ahead: the floor behind the blade stays
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

}  // namespace
}  // namespace terracut
