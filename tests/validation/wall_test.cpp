// The blade is a wall (validation/wall.hpp): no soil that came through or
// under the blade stands behind it, for blades of 0.2 to 2 m, yaws round the
// compass, level and rolled, speeds of 0.05 to 2 m/s, pushing, plunging,
// lifting and turning, at the work cap and with it lifted, steadily and with
// a hand's tremor and wobble.
#include "terracut/validation/wall.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "test_env.hpp"

namespace terracut::validation {
namespace {

// Each blade along X pushes along +Z; the blade spans the terrain.
TEST(SoilWall, NoSoilCrossesABladeSpanningTheTerrain) {
  const double speeds[] = {0.25, 1.0, 2.0};
  int k = 0;
  for (const WallMotion motion : {WallMotion::kPush, WallMotion::kPlunge, WallMotion::kLift, WallMotion::kTurn})
    for (const double yaw : {0.0, 17.0, 30.0, 45.0, 60.0, 90.0, 135.0}) {
      const WallCase w{1.0, yaw, speeds[k++ % 3], motion, false};
      EXPECT_LE(worst_rise_behind(w), kWallSlack_m) << describe(w);
    }
}

TEST(SoilWall, NoSoilCrossesShortBladesInAChannel) {
  const double speeds[] = {2.0, 0.25, 1.0};
  int k = 0;
  for (const WallMotion motion : {WallMotion::kPush, WallMotion::kPlunge, WallMotion::kLift, WallMotion::kTurn})
    for (const double length : {0.2, 0.5, 1.0, 2.0})
      for (const double yaw : {0.0, 30.0}) {
        const WallCase w{length, yaw, speeds[k++ % 3], motion, true};
        EXPECT_LE(worst_rise_behind(w), kWallSlack_m) << describe(w);
      }
}

TEST(SoilWall, NoSoilCrossesTheBladeWithTheWorkCapLifted) {
  for (const WallMotion motion : {WallMotion::kPush, WallMotion::kTurn})
    for (const double yaw : {0.0, 45.0}) {
      const WallCase w{1.0, yaw, 1.0, motion, false, 1000000000};
      EXPECT_LE(worst_rise_behind(w), kWallSlack_m) << describe(w);
    }
}

// A slow blade: 0.05 to 0.1 m/s on 1 cm cells moves 0.05 to 0.1 mm a step,
// at most a hundredth of a cell. The tests of which way the blade goes once
// looked at one step's motion and took such a blade for one at rest: the
// displacement put the soil of each centre the edge had just passed on that
// centre's own side, behind the blade, and the settle walled off only the
// cells the edge passes through, so a diagonal pair stepped over it (on the
// code before SoilFlow::motion_origin, 3.7 to 5.8 cm of soil stood behind
// every one of these). The motion is now measured since the blade last
// moved a fiftieth of a cell.
TEST(SoilWall, NoSoilCrossesASlowBlade) {
  int k = 0;
  for (const WallMotion motion : {WallMotion::kPush, WallMotion::kPlunge, WallMotion::kLift, WallMotion::kTurn})
    for (const double yaw : {0.0, 197.0}) {
      const WallCase w{1.0, yaw, k++ % 2 == 0 ? 0.1 : 0.05, motion, false};
      EXPECT_LE(worst_rise_behind(w), kWallSlack_m) << describe(w);
    }
  for (const WallMotion motion : {WallMotion::kPush, WallMotion::kTurn}) {
    const WallCase w{1.2, 19.0, 0.08, motion, true};
    EXPECT_LE(worst_rise_behind(w), kWallSlack_m) << describe(w);
  }
}

// A hand's tremor (kWallTremor_hz, 4 mm) takes the blade back and forth in
// every cycle at 0.1 and 0.2 m/s. While it turns, the blade's midpoint goes
// back while part of the edge still goes forward: the displacement once
// pushed the whole edge's cut the way the midpoint went, so the part going
// forward put what it cut behind itself (on the code before the way was
// taken point by point along the edge, the turning cases here left 1.2 to
// 2.0 cm of soil behind the blade).
TEST(SoilWall, NoSoilCrossesATremblingBlade) {
  int k = 0;
  for (const WallMotion motion : {WallMotion::kPush, WallMotion::kPlunge, WallMotion::kLift, WallMotion::kTurn})
    for (const double yaw : {10.0, 100.0}) {
      WallCase w{1.0, yaw, k++ % 2 == 0 ? 0.1 : 0.2, motion, false};
      w.tremor_m = 0.004;
      EXPECT_LE(worst_rise_behind(w), kWallSlack_m) << describe(w);
    }
  for (const double length : {0.5, 1.0}) {
    WallCase w{length, 10.0, 0.2, WallMotion::kTurn, true};
    w.tremor_m = 0.004;
    EXPECT_LE(worst_rise_behind(w), kWallSlack_m) << describe(w);
  }
}

// A hand's wobble about the vertical (kWallWobble_hz, 1.5 degrees) with a
// 2 mm tremor: the blade turns about its centre every cycle, its halves
// going opposite ways. The cut once split each step's swept quad along a
// diagonal; when the blade turns about a point of its edge the quad is a
// bow-tie, and the diagonal's triangle reached up to half a millimetre
// ahead of the half going back, so the cut took soil its edge never reached
// and the displacement pushed it behind that half, step after step (on the
// code before, these cases left 4.0, 13.4, 4.5 and 7.5 cm behind the blade:
// random cases of a throwaway sweep). Now the cut takes the bow-tie's two
// lobes (geometry.hpp, sweep_triangles).
TEST(SoilWall, NoSoilCrossesAWobblingBlade) {
  struct Case {
    WallCase w;
    double cell_m;
  };
  const Case cases[] = {{{1.0, 173.1, 0.6, WallMotion::kPush, false}, 0.01},
                        {{1.0, 226.7, 0.12, WallMotion::kTurn, false}, 0.005},
                        {{0.8, -29.6, 0.25, WallMotion::kTurn, true}, 0.005},
                        {{1.0, 262.4, 0.1, WallMotion::kTurn, false}, 0.02}};
  for (const Case& c : cases) {
    WallCase w = c.w;
    w.cell_m = c.cell_m;
    w.tremor_m = 0.002;
    w.wobble_deg = 1.5;
    EXPECT_LE(worst_rise_behind(w), kWallSlack_m) << describe(w);
  }
}

// A rolled blade (one end lower), in every motion, steadily and with a
// hand's tremor and wobble: the edge stays in its cutting plane, which
// slopes across the travel by the roll, and the trench behind it stays at
// that plane. Cases of a random sweep of the measure; on the code of
// 7c9d797 (before the way was taken point by point along the edge, the
// bow-tie's lobes, and a centre under the blade taking no soil) the first
// five left 2.4 to 9.6 cm of soil behind the blade (2.0 to 6.5 cm level).
TEST(SoilWall, NoSoilCrossesARolledBlade) {
  const WallCase cases[] = {
      {.length_m = 1.0, .yaw_deg = 97.7, .speed_m_per_s = 0.186, .motion = WallMotion::kPlunge,
       .cell_m = 0.02, .roll_deg = -1.8},
      {.length_m = 1.9, .yaw_deg = -6.3, .speed_m_per_s = 0.198, .motion = WallMotion::kPush, .channel = true,
       .cell_m = 0.02, .roll_deg = -1.35},
      {.length_m = 1.0, .yaw_deg = 202.5, .speed_m_per_s = 0.311, .motion = WallMotion::kTurn,
       .cell_m = 0.02, .tremor_m = 0.0035, .roll_deg = 2.15},
      {.length_m = 1.0, .yaw_deg = 272.0, .speed_m_per_s = 0.151, .motion = WallMotion::kPush,
       .cell_m = 0.02, .wobble_deg = 2.0, .roll_deg = -3.57},
      {.length_m = 1.7, .yaw_deg = 22.1, .speed_m_per_s = 0.301, .motion = WallMotion::kPush, .channel = true,
       .cell_m = 0.01, .tremor_m = 0.0039, .roll_deg = 0.69},
      {.length_m = 1.0, .yaw_deg = 289.4, .speed_m_per_s = 1.716, .motion = WallMotion::kLift,
       .cell_m = 0.005, .tremor_m = 0.0025, .wobble_deg = 1.49, .roll_deg = -1.85},
      {.length_m = 1.3, .yaw_deg = 0.1, .speed_m_per_s = 1.09, .motion = WallMotion::kLift, .channel = true,
       .cell_m = 0.02, .wobble_deg = 1.67, .roll_deg = -2.93},
      {.length_m = 0.8, .yaw_deg = 25.1, .speed_m_per_s = 0.835, .motion = WallMotion::kTurn, .channel = true,
       .cell_m = 0.005, .tremor_m = 0.0021, .roll_deg = -3.59},
  };
  for (const WallCase& w : cases) EXPECT_LE(worst_rise_behind(w), kWallSlack_m) << describe(w);
}

// Oblong cells (1 x 1.7 and 1 x 0.45 of the side along X): the passes'
// limits, the displacement's step along the push and the half cell the
// edge's line passes through differ along X and Z. A throwaway random sweep
// of the measure on such cells (80 cases, every motion, rolled, trembling
// and wobbling) found none failing; these four take each motion.
TEST(SoilWall, NoSoilCrossesABladeOnOblongCells) {
  const WallCase cases[] = {
      {.length_m = 1.0, .yaw_deg = 37.0, .speed_m_per_s = 0.3, .motion = WallMotion::kPush,
       .cell_m = 0.01, .cell_aspect = 1.7, .tremor_m = 0.003, .wobble_deg = 1.5, .roll_deg = 2.0},
      {.length_m = 1.2, .yaw_deg = 15.0, .speed_m_per_s = 0.8, .motion = WallMotion::kTurn, .channel = true,
       .cell_m = 0.01, .cell_aspect = 0.45, .tremor_m = 0.002, .roll_deg = -2.5},
      {.length_m = 1.0, .yaw_deg = 120.0, .speed_m_per_s = 0.15, .motion = WallMotion::kPlunge,
       .cell_m = 0.02, .cell_aspect = 1.7, .wobble_deg = 1.0},
      {.length_m = 0.8, .yaw_deg = -20.0, .speed_m_per_s = 1.5, .motion = WallMotion::kLift, .channel = true,
       .cell_m = 0.02, .cell_aspect = 0.45, .tremor_m = 0.004, .wobble_deg = 1.0, .roll_deg = 3.0},
  };
  for (const WallCase& w : cases) EXPECT_LE(worst_rise_behind(w), kWallSlack_m) << describe(w);
}

// A terrain far from the origin, as a georeferenced one lies (UTM eastings
// and northings run to hundreds of kilometres): the tests of a centre on
// the edge's line and of the way the edge went round at 1e-9 of a cell
// where coordinates carry 1e-10 m of rounding at 500 km. These take each
// motion, rolled, trembling and wobbling. The last is a 1.1 m blade in a
// channel on 2 cm cells that starts at rest with its midpoint exactly on a
// cell centre: the first step, with no way known yet, once put that
// centre's cut on the side its rounding gave, which the origin changed
// (behind the blade from 1 km out, 1.7 cm); a centre on the line within
// the coordinates' rounding now goes to the side the edge's normal faces.
TEST(SoilWall, NoSoilCrossesABladeFarFromTheOrigin) {
  WallCase cases[] = {
      {.length_m = 1.0, .yaw_deg = 17.0, .speed_m_per_s = 0.25, .motion = WallMotion::kPush,
       .cell_m = 0.01, .tremor_m = 0.003, .wobble_deg = 1.5, .roll_deg = 2.0},
      {.length_m = 1.2, .yaw_deg = -12.0, .speed_m_per_s = 0.6, .motion = WallMotion::kTurn, .channel = true,
       .cell_m = 0.02, .tremor_m = 0.002, .roll_deg = -1.5},
      {.length_m = 1.0, .yaw_deg = 200.0, .speed_m_per_s = 0.4, .motion = WallMotion::kPlunge,
       .cell_m = 0.02, .tremor_m = 0.004, .wobble_deg = 1.0},
      {.length_m = 0.9, .yaw_deg = 25.0, .speed_m_per_s = 1.2, .motion = WallMotion::kLift, .channel = true,
       .cell_m = 0.01, .wobble_deg = 1.0, .roll_deg = 3.0},
      {.length_m = 1.1, .yaw_deg = -12.0, .speed_m_per_s = 0.6, .motion = WallMotion::kLift, .channel = true,
       .cell_m = 0.02, .tremor_m = 0.002, .roll_deg = -1.5},
  };
  for (WallCase& w : cases) {
    for (const double origin : {1000.0, 500000.0}) {
      w.origin_m = origin;
      EXPECT_LE(worst_rise_behind(w), kWallSlack_m) << describe(w);
    }
  }
}

// At the pivot of a turning, wobbling blade a point of the edge moves by no
// more than the coordinates' rounding in a step, and the way its cut goes
// is then its motion since the blade last moved. That could be a backing
// of 1e-5 m, and the columns cut, which lowers every column whose square
// the edge crosses, sent a column standing 0.53 cells ahead of the edge
// 1.5 cells back, through the blade: 1.3 cm of pile behind a 0.87 m blade
// on 2 cm cells 1e7 m out (2 cm at its worst), where the rounding is
// 1.4e-7 m. A cut column behind the line the way was measured from keeps
// its side now, as for this step's motion. (Columns; the surface's cut
// reaches no such sample.)
TEST(SoilWall, NoSoilCrossesAColumnAtTheTurnsPivotFarFromTheOrigin) {
  WallCase w{.length_m = 0.865, .yaw_deg = -26.56505117707799, .speed_m_per_s = 0.21638210608936198,
             .motion = WallMotion::kTurn, .channel = true, .cell_m = 0.02, .wobble_deg = 0.29164612608868484,
             .origin_m = 1e7, .columns = true};
  EXPECT_LE(worst_rise_behind(w), kWallSlack_m) << describe(w);
  w.columns = false;
  EXPECT_LE(worst_rise_behind(w), kWallSlack_m) << describe(w);
  // A 2 m blade lifting, trembling and wobbling along a lattice direction,
  // whose pivot had backed 1.5 cm since it last moved: 1.9 cm behind it.
  // The columns' rolled cases still leave a fraction of a millimetre
  // (docs/soil.md, "Not done yet"; this one 8.7e-5 m, at the origin too):
  // the bound is that, not the surface's float slack.
  WallCase lift{.length_m = 2.0, .yaw_deg = 225.0, .speed_m_per_s = 0.10546482181442485,
                .motion = WallMotion::kLift, .cell_m = 0.01, .cell_aspect = 2.0, .tremor_m = 0.0024757430289126825,
                .wobble_deg = 1.1767700921250166, .roll_deg = -0.33779048196996975, .origin_m = 1e7, .columns = true};
  EXPECT_LE(worst_rise_behind(lift), 1e-3) << describe(lift);
}

// The blade along a lattice direction (its line through a row of cell
// centres every few cells: yaws whose tangent is 0, 1/3, 1/2, 1, ...), where
// its line lands exactly on centres, step after step, and the terrain at
// the origin and up to 1e7 m from it. Every case failed before 2026-12-07:
// - turning about a point of the edge (the first: one end going back), the
//   sweeps missed the centres on the line two steps shared and the soil on
//   them slid into the trench, 2 cm (Simulation's reach_back);
// - far from the origin, a centre on the line was taken for one the edge had
//   passed, and the pile on it for the trench's (the blade's wall and the
//   displacement told the side at 1e-9 of a cell, under the coordinates'
//   rounding from 100 km out): 1.1 to 2.7 cm.
TEST(SoilWall, NoSoilCrossesABladeAlongALatticeDirection) {
  const WallCase cases[] = {
      {.length_m = 2.0, .yaw_deg = 198.43494882292202, .speed_m_per_s = 0.3, .motion = WallMotion::kTurn,
       .cell_m = 0.02, .tremor_m = 0.002},
      {.length_m = 0.515, .yaw_deg = -18.43494882292201, .speed_m_per_s = 0.3, .motion = WallMotion::kPlunge,
       .channel = true, .cell_m = 0.02, .tremor_m = 0.002, .roll_deg = 2.0},
      {.length_m = 0.3775, .yaw_deg = -18.43494882292201, .speed_m_per_s = 0.6, .motion = WallMotion::kLift,
       .channel = true, .cell_m = 0.01, .roll_deg = 2.0, .origin_m = 1e5},
      {.length_m = 2.0, .yaw_deg = 71.56505117707799, .speed_m_per_s = 0.2, .motion = WallMotion::kPush,
       .cell_m = 0.02, .origin_m = 1e6},
      {.length_m = 2.0, .yaw_deg = 108.43494882292201, .speed_m_per_s = 0.4, .motion = WallMotion::kTurn,
       .cell_m = 0.01, .roll_deg = 2.0, .origin_m = 1e7},
      {.length_m = 0.62, .yaw_deg = 26.56505117707799, .speed_m_per_s = 0.6, .motion = WallMotion::kPlunge,
       .channel = true, .cell_m = 0.02, .roll_deg = 2.0, .origin_m = 1e7},
  };
  for (const WallCase& w : cases) EXPECT_LE(worst_rise_behind(w), kWallSlack_m) << describe(w);
}

// Random cases: blades of 0.2 to 2 m at any yaw, every motion, spanning the
// terrain or in a channel, 0.2 to 2 m/s on 1 and 2 cm cells, a tremor up to
// 4 mm, a wobble up to 2 degrees, a roll up to 4 degrees either way, oblong
// cells, the cap lifted in some. Seeded, so each run draws the same cases;
// TERRACUT_WALL_SEED and TERRACUT_WALL_CASES draw others, or more (the
// sweeps of docs/soil.md, "Rolled, turning, plunging", ran hundreds). On
// the code of 7c9d797 one of these 32 fails (a lifting rolled blade, 6 cm
// behind it), and 3 of the first 100.
TEST(SoilWall, RandomCasesHold) {
  const unsigned seed = unsigned(whole_from_env("TERRACUT_WALL_SEED", 2026, 4294967295L));
  const int count = int(whole_from_env("TERRACUT_WALL_CASES", 32, 100000));
  std::mt19937 rng(seed);
  const auto uni = [&](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
  const auto pick = [&](int n) { return int(std::uniform_int_distribution<int>(0, n - 1)(rng)); };
  const WallMotion motions[] = {WallMotion::kPush, WallMotion::kPlunge, WallMotion::kLift, WallMotion::kTurn};
  int run = 0;
  for (int i = 0; i < count; ++i) {
    WallCase w{uni(0.2, 2.0), uni(0.0, 360.0), uni(0.2, 2.0), motions[pick(4)], pick(2) == 0};
    if (w.channel) w.yaw_deg = uni(-35.0, 35.0);
    w.cell_m = pick(2) == 0 ? 0.01 : 0.02;
    w.cell_aspect = pick(3) == 0 ? uni(0.5, 2.0) : 1.0;
    w.tremor_m = pick(3) < 2 ? uni(0.0, 0.004) : 0.0;
    w.wobble_deg = pick(2) == 0 ? uni(0.0, 2.0) : 0.0;
    w.roll_deg = uni(-4.0, 4.0);
    if (pick(6) == 0) w.cap = 1000000000;
    double worst = 0.0;
    try {
      worst = worst_rise_behind(w);
    } catch (const std::invalid_argument&) {
      continue;  // a case the measure cannot set up (a channel too narrow at its yaw, a plane too low)
    }
    ++run;
    EXPECT_LE(worst, kWallSlack_m) << describe(w) << " (seed " << seed << ", case " << i << ")";
  }
  EXPECT_GE(run, count / 2) << "most random cases should be ones the measure can set up";
}

// Random cases along lattice directions: the blade's line through a cell
// centre every one to four cells (its direction (1, 0), (3, 1), (2, 1),
// (1, 1), (1, 2), (1, 3), (4, 1), (3, -1), (2, -1) or (1, -1) in cells, on
// cells square or twice or half as long along Z, turned by quarter turns
// when the blade spans the terrain), blades a whole or half number of
// cells long or a quarter cell off, 5, 10 and 20 mm cells, speeds of 0.03
// to 2 m/s, a tremor, a wobble and a roll in half the cases each, the cap
// lifted in a sixth, the terrain at the origin or 1 km to 1e7 m from it.
// Seeded like RandomCasesHold, with TERRACUT_WALL_SEED; the count is
// TERRACUT_WALL_LATTICE_CASES. The throwaway sweeps that found the faults
// of 2026-12-07 (docs/soil.md, "Along a lattice direction, far from the
// origin") drew cases of this kind; on the code before them (7fe7f74) 1 of
// these 24 fails (21 run), and 2 of the first 100 (93 run).
TEST(SoilWall, RandomLatticeCasesHold) {
  const unsigned seed = unsigned(whole_from_env("TERRACUT_WALL_SEED", 2026, 4294967295L));
  const int count = int(whole_from_env("TERRACUT_WALL_LATTICE_CASES", 24, 100000));
  std::mt19937 rng(seed);
  const auto pick = [&](int n) { return int(std::uniform_int_distribution<int>(0, n - 1)(rng)); };
  const auto uni = [&](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
  const WallMotion motions[] = {WallMotion::kPush, WallMotion::kPlunge, WallMotion::kLift, WallMotion::kTurn};
  const int directions[][2] = {{1, 0}, {3, 1}, {2, 1}, {1, 1}, {1, 2}, {1, 3}, {4, 1}, {3, -1}, {2, -1}, {1, -1}};
  const double origins[] = {0.0, 1000.0, 1e5, 1e6, 1e7};
  int run = 0;
  for (int i = 0; i < count; ++i) {
    WallCase w;
    w.channel = pick(2) == 0;
    w.cell_m = pick(3) == 0 ? 0.005 : pick(2) == 1 ? 0.01 : 0.02;
    w.cell_aspect = pick(3) == 0 ? (pick(2) == 1 ? 0.5 : 2.0) : 1.0;
    const int* d = directions[pick(10)];
    // Local +X goes to (cos yaw, -sin yaw): along (d[0] cells, d[1] cells).
    w.yaw_deg = -std::atan2(d[1] * w.cell_aspect, double(d[0])) * 180.0 / std::numbers::pi;
    if (!w.channel) w.yaw_deg += 90.0 * pick(4);
    w.length_m = w.cell_m * (20 + pick(100)) * 0.5 + (pick(2) == 1 ? 0.0 : 0.25 * w.cell_m);
    w.motion = motions[pick(4)];
    w.speed_m_per_s = pick(4) == 0 ? uni(0.03, 0.15) : uni(0.2, 2.0);
    w.tremor_m = pick(2) == 1 ? 0.0 : uni(0.0, 0.004);
    w.wobble_deg = pick(2) == 1 ? 0.0 : uni(0.0, 2.0);
    w.roll_deg = pick(2) == 1 ? 0.0 : uni(-3.0, 3.0);
    if (pick(6) == 0) w.cap = 1000000000;
    w.origin_m = origins[pick(5)];
    double worst = 0.0;
    try {
      worst = worst_rise_behind(w);
    } catch (const std::invalid_argument&) {
      continue;  // a channel too narrow at its yaw, a plane too low
    }
    ++run;
    EXPECT_LE(worst, kWallSlack_m) << describe(w) << " (seed " << seed << ", case " << i << ")";
  }
  EXPECT_GE(run, count / 2) << "most random cases should be ones the measure can set up";
}

// Three faults the lattice sweeps found (docs/soil.md, "Along a lattice
// direction, far from the origin"), each case failing before its fix:
// - a blade set down with its line on a row of centres left some of them
//   uncut, and backing a little as it wobbled, pushed their soil behind it
//   (1.6 cm, 1 km out; Simulation's band for a sweep with no motion across
//   the line);
// - a wobbling blade came forward across cells a settle started in between
//   had taken for the pile's, and the settle, written steps later, stood
//   the pile behind it (21 cm; SoilFlow::settle_follow);
// - pushing into the terrain's walled corner, the cut's way ahead left the
//   grid and, clamped, landed on a cell behind the blade (1.25 cm; the
//   displacement's walk now goes along the wall to a cell ahead).
TEST(SoilWall, NoSoilCrossesABladeSetDownWobblingOrInACorner) {
  const WallCase cases[] = {
      {.length_m = 0.88, .yaw_deg = -71.56505117707799, .speed_m_per_s = 0.1164368145393743,
       .motion = WallMotion::kLift, .channel = true, .cap = 1000000000, .cell_m = 0.02,
       .tremor_m = 0.0017530556614767396, .wobble_deg = 0.6656938944305918, .roll_deg = 1.2170158847974495,
       .origin_m = 1000.0},
      {.length_m = 1.0, .yaw_deg = 189.46232220802563, .speed_m_per_s = 0.5367851407733206,
       .motion = WallMotion::kTurn, .cell_m = 0.005, .cell_aspect = 0.5, .wobble_deg = 1.9439170436742912},
      {.length_m = 1.0, .yaw_deg = 146.30993247402023, .speed_m_per_s = 1.97603516598515, .motion = WallMotion::kPush,
       .cell_m = 0.005, .cell_aspect = 2.0, .tremor_m = 0.0017478198015144635, .wobble_deg = 1.6264301854264582,
       .roll_deg = -0.07884240867101955},
  };
  for (const WallCase& w : cases) EXPECT_LE(worst_rise_behind(w), kWallSlack_m) << describe(w);
}

// The cases `terracut validate` runs hold too (its check 3.3).
TEST(SoilWall, TheValidationCasesHold) {
  const std::vector<WallCase> cases = validation_wall_cases();
  EXPECT_GE(cases.size(), 20u);
  for (const WallCase& w : cases) EXPECT_LE(worst_rise_behind(w), kWallSlack_m) << describe(w);
}

// A case the measure cannot set up is refused with the case named.
TEST(SoilWall, ACaseItCannotSetUpIsRefused) {
  const auto message = [](const WallCase& w) {
    try {
      worst_rise_behind(w);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(message({0.0, 0.0, 1.0, WallMotion::kPush, false}).find("length_m"), std::string::npos);
  EXPECT_NE(message({1.0, 0.0, -1.0, WallMotion::kPush, false}).find("speed_m_per_s"), std::string::npos);
  WallCase shaking{1.0, 0.0, 1.0, WallMotion::kPush, false};
  shaking.tremor_m = -0.001;
  EXPECT_NE(message(shaking).find("tremor_m"), std::string::npos);
  shaking.tremor_m = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(message(shaking).find("tremor_m"), std::string::npos);
  WallCase wobbling{1.0, 0.0, 1.0, WallMotion::kPush, false};
  wobbling.wobble_deg = 6.0;
  EXPECT_NE(message(wobbling).find("wobble_deg"), std::string::npos);
  WallCase rolled{1.0, 0.0, 1.0, WallMotion::kPush, false};
  rolled.roll_deg = std::numeric_limits<double>::infinity();
  EXPECT_NE(message(rolled).find("roll_deg"), std::string::npos);
  rolled.roll_deg = -5.5;
  EXPECT_NE(message(rolled).find("roll_deg"), std::string::npos);
  WallCase oblong{1.0, 0.0, 1.0, WallMotion::kPush, false};
  oblong.cell_aspect = 0.2;
  EXPECT_NE(message(oblong).find("cell_aspect"), std::string::npos);
  oblong.cell_aspect = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(message(oblong).find("cell_aspect"), std::string::npos);
  WallCase far{1.0, 0.0, 1.0, WallMotion::kPush, false};
  far.origin_m = 2e7;
  EXPECT_NE(message(far).find("origin_m"), std::string::npos);
  // Rolled 5 degrees, a 2 m blade yawed 30 degrees lifting in a channel,
  // wobbling 5 degrees: the cutting plane runs 10.5 cm below the middle's
  // at the channel's side and 7.9 cm lower where the ramp starts (the
  // edge's reach behind the start): below the terrain's bottom.
  rolled = WallCase{2.0, 30.0, 1.0, WallMotion::kLift, true};
  rolled.wobble_deg = 5.0;
  rolled.roll_deg = 5.0;
  EXPECT_NE(message(rolled).find("cutting plane"), std::string::npos);
  // A blade turned along the channel does not reach across it.
  EXPECT_NE(message({1.0, 89.0, 1.0, WallMotion::kPush, true}).find("channel"), std::string::npos);
}

}  // namespace
}  // namespace terracut::validation
