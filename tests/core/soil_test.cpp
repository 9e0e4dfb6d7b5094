// Soil that flows (soil.hpp): relaxation to the angle of repose (a column of
// sand collapses into a round cone at the repose angle in every direction,
// a gentler slope stays put, the volume is conserved, the result is
// deterministic and mirror-symmetric, the work per step is capped), and
// displacement by the blade (the cut soil is pushed into a pile ahead of
// it whose size follows the bulldozing mass balance; the cut behind stays
// open). Tolerances come from the cell size and the stated tolerance of the
// relaxation (2 % of the repose slope).
#include "terracut/core/soil.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <vector>

#include "terracut/core/error.hpp"
#include "terracut/core/simulation.hpp"
#include "soil_scenes.hpp"
#include "test_terrains.hpp"

namespace terracut {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;


SoilFlowParams flow(double repose_deg, std::int64_t checks = 200000) {
  SoilFlowParams p;
  p.model = SoilModel::kFlow;
  p.material.repose_deg = repose_deg;
  p.max_pair_checks_per_step = checks;
  return p;
}

double sum_heights(const HeightGrid& g) {
  double s = 0.0;
  for (std::int64_t i = 0; i < g.spec().sample_count(); ++i) s += g.heights()[i];
  return s;
}

// Relaxes until nothing is active (or a bound on steps); returns the steps.
int settle(SoilFlow& f, HeightGrid& g, int max_steps = 100000) {
  int steps = 0;
  while (f.active_cells() > 0 && steps < max_steps) {
    f.relax(g);
    ++steps;
  }
  return steps;
}

// Bilinear height of the grid at cell coordinates (u, v) (sample centres at
// integer + 0.5 are the nodes).
double height_at(const HeightGrid& g, double u, double v) {
  const double x = u - 0.5, z = v - 0.5;
  const int c = int(std::floor(x)), r = int(std::floor(z));
  const double fx = x - c, fz = z - r;
  const auto h = [&](int cc, int rr) {
    cc = std::clamp(cc, 0, g.cols() - 1);
    rr = std::clamp(rr, 0, g.rows() - 1);
    return double(g.height(cc, rr));
  };
  return h(c, r) * (1 - fx) * (1 - fz) + h(c + 1, r) * fx * (1 - fz) + h(c, r + 1) * (1 - fx) * fz +
         h(c + 1, r + 1) * fx * fz;
}

// The cone's slope along a ray from the centre (cell coordinates), degrees:
// the mean slope between where the surface falls below 80 % and 20 % of the
// peak (away from the rounded tip and the toe).
double flank_angle_deg(const HeightGrid& g, double cu, double cv, double dir_deg, double cell_m) {
  const double a = dir_deg * kDeg;
  const double peak = height_at(g, cu, cv);
  double s80 = -1.0, s20 = -1.0;
  for (double s = 0.0; s < g.cols(); s += 0.02) {
    const double v = height_at(g, cu + s * std::cos(a), cv + s * std::sin(a));
    if (s80 < 0.0 && v < 0.8 * peak) s80 = s;
    if (v < 0.2 * peak) {
      s20 = s;
      break;
    }
  }
  const double h80 = height_at(g, cu + s80 * std::cos(a), cv + s80 * std::sin(a));
  const double h20 = height_at(g, cu + s20 * std::cos(a), cv + s20 * std::sin(a));
  return std::atan((h80 - h20) / ((s20 - s80) * cell_m)) / kDeg;
}

// A column of sand on a bare floor (the scenes library's, as `terracut
// validate` uses it).
using scenes::column;

TEST(IndexDivider, QuotientsEqualHardwareDivisionForEveryRowLength) {
  // Every row length up to 1100 and every 97th up to kMaxGridSide, at the
  // numerators where a rounded reciprocal goes wrong first: multiples of
  // the divisor and their neighbours, up to the largest 32-bit index; and
  // every numerator below 2^20 for a few small, odd and power-of-two
  // divisors. (The quotient is exact by the theorem; this checks the code.)
  std::int64_t checked = 0;
  for (std::uint32_t d = 1; d <= std::uint32_t(kMaxGridSide); d += (d < 1100 ? 1 : 97)) {
    const detail::IndexDivider div(d);
    const std::uint64_t step = std::max<std::uint64_t>(d, (std::uint64_t(1) << 32) / 4096 / d * d);
    for (std::uint64_t m = 0; m < (std::uint64_t(1) << 32); m += step)
      for (std::int64_t e : {std::int64_t(-1), std::int64_t(0), std::int64_t(1), std::int64_t(d) - 1}) {
        const std::int64_t n = std::int64_t(m) + e;
        if (n < 0 || n > 0xffffffffLL) continue;
        ASSERT_EQ(div.quotient(std::uint32_t(n)), std::uint32_t(n) / d) << n << " / " << d;
        ++checked;
      }
    ASSERT_EQ(div.quotient(0xffffffffu), 0xffffffffu / d) << d;
  }
  for (std::uint32_t d : {1u, 2u, 3u, 7u, 100u, 512u, 4096u, 4111u, 65536u}) {
    const detail::IndexDivider div(d);
    for (std::uint32_t n = 0; n < (1u << 20); ++n) ASSERT_EQ(div.quotient(n), n / d) << n << " / " << d;
  }
  EXPECT_GT(checked, 1000000);
}

TEST(SoilFlow, TheSteepestStandingPlaneIsWhereTheRelaxationStartsToMove) {
  // A plane ramp falling along theta, for theta every 0.02 degree over a
  // quadrant: 0.15 degree above steepest_standing_slope_deg every ramp has
  // active cells (a pair past its limit: nothing that steep stands), 0.15
  // degree below it some ramp has none (it stands). On square cells and on
  // cells of 2:1 and 1:3.
  for (const double aspect : {1.0, 2.0, 1.0 / 3.0}) {
    const double dx = 0.01, dz = 0.01 * aspect, repose = 34.0;
    const double steepest = steepest_standing_slope_deg(dx, dz, repose);
    EXPECT_GT(steepest, repose);
    const int n = 16;
    const auto all_active = [&](double slope_deg) {
      const double s = std::tan(slope_deg * std::numbers::pi / 180.0);
      for (int i = 0; i <= 4500; ++i) {
        const double theta = i * 0.02 * std::numbers::pi / 180.0;
        std::vector<float> h(std::size_t(n) * n);
        for (int r = 0; r < n; ++r)
          for (int c = 0; c < n; ++c)
            h[std::size_t(r) * n + c] =
                float(1.0 - s * ((c + 0.5) * dx * std::cos(theta) + (r + 0.5) * dz * std::sin(theta)));
        HeightGrid g(GridSpec{n, n, n * dx, n * dz, {}, 1.0}, h);
        if (SoilFlow(flow(repose), g).active_cells() == 0) return false;
      }
      return true;
    };
    EXPECT_TRUE(all_active(steepest + 0.15)) << "aspect " << aspect;
    EXPECT_FALSE(all_active(steepest - 0.15)) << "aspect " << aspect;
  }
  // The figures the documentation gives (34 degrees).
  EXPECT_NEAR(steepest_standing_slope_deg(0.01, 0.01, 34.0), 36.6, 0.05);
  EXPECT_NEAR(steepest_standing_slope_deg(0.01, 0.02, 34.0), 38.8, 0.05);
  EXPECT_NEAR(steepest_standing_slope_deg(0.04, 0.01, 34.0), 40.9, 0.05);
}

TEST(SoilFlow, AColumnCollapsesIntoARoundConeAtTheReposeAngle) {
  for (const double repose : {34.0, 45.0}) {
    const int n = 161;
    const double cell = 0.01;
    HeightGrid g(grid_of_cells(n, n, cell), column(n, 15.0, 0.4f));
    const double before = sum_heights(g);
    SoilFlow f(flow(repose), g);
    EXPECT_GT(f.active_cells(), 0);  // the column's walls are too steep
    settle(f, g);
    ASSERT_EQ(f.active_cells(), 0) << "did not settle";
    // Every direction, not only the grid's axes and diagonals: within the
    // 8-neighbour stencil's anisotropy (about 1.3 degrees at 22.5 degrees
    // off the axes at 34) plus the tolerance (2 % of tan, 0.5 degree) and
    // the interpolation over cells.
    for (double dir = 0.0; dir < 360.0; dir += 22.5) {
      const double angle = flank_angle_deg(g, 0.5 * n, 0.5 * n, dir, cell);
      EXPECT_NEAR(angle, repose, 2.0) << "repose " << repose << ", direction " << dir;
    }
    // Nothing is steeper than the repose angle (plus the tolerance) anywhere.
    const double limit = std::tan(repose * kDeg) * cell * 1.02 + 1e-6;
    for (int r = 0; r + 1 < n; ++r)
      for (int c = 0; c + 1 < n; ++c) {
        EXPECT_LE(std::abs(g.height(c, r) - g.height(c + 1, r)), limit) << c << "," << r;
        EXPECT_LE(std::abs(g.height(c, r) - g.height(c, r + 1)), limit) << c << "," << r;
      }
    // The volume is conserved to float rounding.
    EXPECT_NEAR(sum_heights(g), before, 1e-6 * before);
    for (std::int64_t i = 0; i < g.spec().sample_count(); ++i) EXPECT_GE(g.heights()[i], 0.0f);
  }
}

TEST(SoilFlow, ASlopeBelowTheReposeAngleNeverMoves) {
  // A ramp at 30 degrees along X, and one at 30 degrees along the diagonal,
  // with a repose angle of 34: nothing is active, nothing changes.
  const int n = 40;
  const double cell = 0.02;
  for (const bool diagonal : {false, true}) {
    const std::vector<float> h = scenes::ramp(n, cell, 0.05, 30.0, diagonal);
    HeightGrid g(grid_of_cells(n, n, cell), h);
    SoilFlow f(flow(34.0), g);
    EXPECT_EQ(f.active_cells(), 0) << diagonal;
    const SoilStepResult r = f.relax(g);
    EXPECT_EQ(r.moved_pairs, 0);
    for (std::size_t i = 0; i < h.size(); ++i) EXPECT_EQ(g.heights()[i], h[i]);
  }
}

TEST(SoilFlow, DeterministicAndMirrorSymmetric) {
  // An uneven heap: two columns of different heights, off centre.
  const int n = 61;
  std::vector<float> h(std::size_t(n) * n, 0.02f);
  for (int r = 10; r < 25; ++r)
    for (int c = 8; c < 20; ++c) h[std::size_t(r) * n + c] = 0.3f;
  for (int r = 30; r < 36; ++r)
    for (int c = 20; c < 45; ++c) h[std::size_t(r) * n + c] = 0.18f;
  std::vector<float> mirrored(h.size());
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) mirrored[std::size_t(r) * n + c] = h[std::size_t(r) * n + (n - 1 - c)];

  HeightGrid a(grid_of_cells(n, n, 0.01), h), b(grid_of_cells(n, n, 0.01), h), m(grid_of_cells(n, n, 0.01), mirrored);
  SoilFlow fa(flow(34.0), a), fb(flow(34.0), b), fm(flow(34.0), m);
  settle(fa, a);
  settle(fb, b);
  settle(fm, m);
  EXPECT_EQ(a.state_hash(), b.state_hash());  // the same inputs, the same bits
  double worst = 0.0;
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c)
      worst = std::max(worst, std::abs(double(a.height(c, r)) - double(m.height(n - 1 - c, r))));
  // The mirror differs only by float rounding (the order of additions).
  EXPECT_LT(worst, 1e-5);
}

TEST(SoilFlow, WorkPerStepIsCappedAndTheBacklogCarriedOver) {
  // A collapsing 100 x 100-cell block: more work than one step may do.
  const int n = 200;
  std::vector<float> h(std::size_t(n) * n, 0.0f);
  for (int r = 50; r < 150; ++r)
    for (int c = 50; c < 150; ++c) h[std::size_t(r) * n + c] = 0.5f;
  HeightGrid g(grid_of_cells(n, n, 0.01), h);
  const std::int64_t cap = 20000;
  SoilFlow f(flow(34.0, cap), g);
  const double before = sum_heights(g);
  int steps = 0;
  std::int64_t max_backlog = 0;
  while (f.active_cells() > 0 && steps < 200000) {
    const SoilStepResult r = f.relax(g);
    // Never more than the cap, even when one pass alone is larger (the
    // block's first passes hold thousands of cells): it is carried on.
    EXPECT_LE(r.pair_checks, cap);
    EXPECT_GT(r.pair_checks, 0);
    EXPECT_EQ(r.backlog_cells, f.active_cells());
    max_backlog = std::max(max_backlog, r.backlog_cells);
    ++steps;
  }
  EXPECT_EQ(f.active_cells(), 0);
  EXPECT_GT(steps, 10);  // the collapse was spread over many steps
  EXPECT_GT(max_backlog, 100);
  EXPECT_NEAR(sum_heights(g), before, 1e-6 * before);
}

TEST(SoilFlow, APassSpreadOverStepsGivesTheSameBitsAsWholePasses) {
  // The same collapse with a cap far below one pass's work (its passes are
  // split over many steps) and with no effective cap: each pass is
  // examined from the heights it started from and applied in the same
  // order either way, so the results are identical, not merely close.
  const int n = 120;
  std::vector<float> h(std::size_t(n) * n, 0.0f);
  for (int r = 40; r < 80; ++r)
    for (int c = 30; c < 90; ++c) h[std::size_t(r) * n + c] = 0.3f;
  HeightGrid split(grid_of_cells(n, n, 0.01), h), whole(grid_of_cells(n, n, 0.01), h);
  SoilFlow fs(flow(34.0, 1000), split), fw(flow(34.0, 1000000000), whole);
  const int split_steps = settle(fs, split, 1000000), whole_steps = settle(fw, whole);
  ASSERT_EQ(fs.active_cells(), 0);
  ASSERT_EQ(fw.active_cells(), 0);
  EXPECT_EQ(whole_steps, 1);
  EXPECT_GT(split_steps, 100);
  EXPECT_EQ(split.state_hash(), whole.state_hash());
}

TEST(SoilFlow, AnOpenEdgeLetsSoilLeaveAndCountsIt) {
  // A block of sand against the grid's edge: a wall keeps every bit of it,
  // an open edge lets what slides past it go, and counts it.
  const int n = 60;
  std::vector<float> h(std::size_t(n) * n, 0.0f);
  for (int r = 20; r < 40; ++r)
    for (int c = 0; c < 12; ++c) h[std::size_t(r) * n + c] = 0.2f;
  for (const SoilEdge edge : {SoilEdge::kWall, SoilEdge::kOpen}) {
    HeightGrid g(grid_of_cells(n, n, 0.01), h);
    SoilFlowParams p = flow(34.0);
    p.edge = edge;
    SoilFlow f(p, g);
    const double before = g.volume_m3();
    double left = 0.0;
    while (f.active_cells() > 0) left += f.relax(g).left_over_edge_m3;
    if (edge == SoilEdge::kWall) {
      EXPECT_EQ(left, 0.0);
      EXPECT_NEAR(g.volume_m3(), before, 1e-6 * before);
    } else {
      EXPECT_GT(left, 0.05 * before);  // a good part slid off
      EXPECT_NEAR(g.volume_m3() + left, before, 1e-6 * before);
      // What is left at the edge stands at the repose angle against the
      // bare ground beyond: at most tan(34) x a cell, plus the tolerance.
      for (int r = 0; r < n; ++r)
        EXPECT_LE(g.height(0, r), std::tan(34.0 * kDeg) * 0.01 * 1.02 + 1e-6) << r;
    }
  }
  EXPECT_EQ(to_string(SoilEdge::kOpen), "open");
}

TEST(SoilDisplacement, APilePushedOffAnOpenEdgeIsCounted) {
  // The blade pushes a 5 cm cut to within a few cells of the grid's far
  // edge (z = 2 m): with an open edge what is pushed past it leaves.
  SimParams params;
  params.grid = grid_of_cells(100, 200, 0.01);
  params.blade.length_m = 0.5;
  params.soil = flow(34.0, 400000);
  params.soil.edge = SoilEdge::kOpen;
  Simulation sim(params, std::vector<float>(std::size_t(100) * 200, 0.2f));
  const double before = sim.grid().volume_m3();
  double left = 0.0;
  const int steps = int(std::lround(0.5 / 0.0006));
  for (int i = 0; i <= steps; ++i) {
    left += sim.step({{0.5, 0.15, 1.45 + 0.5 * i / steps}, Quat{}}).soil.left_over_edge_m3;
  }
  EXPECT_GT(left, 0.0);
  EXPECT_NEAR(sim.grid().volume_m3() + left, before, 1e-6 * before);
}

TEST(SoilFlow, RefusesBadParameters) {
  HeightGrid g(grid_of_cells(4, 4, 0.1), std::vector<float>(16, 0.1f));
  SoilFlowParams p = flow(0.0);
  EXPECT_NE(validate(p).find("soil.repose_deg"), std::string::npos);
  EXPECT_THROW(SoilFlow(p, g), InputError);
  p = flow(81.0);
  EXPECT_NE(validate(p).find("[1, 80]"), std::string::npos);
  p = flow(0.5);
  EXPECT_NE(validate(p).find("[1, 80]"), std::string::npos);
  EXPECT_EQ(validate(flow(1.0)), "");
  p = flow(34.0, 10);
  EXPECT_NE(validate(p).find("soil.max_pair_checks_per_step"), std::string::npos);
  EXPECT_EQ(parse_enum<SoilModel>("flow"), SoilModel::kFlow);
  EXPECT_EQ(parse_enum<SoilModel>("vanish"), SoilModel::kVanish);
  EXPECT_FALSE(parse_enum<SoilModel>("mud"));
}

// A blade 1 m wide cutting d = 5 cm into a 20 cm layer of sand (repose 34)
// on a 1 cm grid, pushed 0.6 m along +Z at 0.6 mm per step.
struct Dozing {
  SimParams params;
  double layer_m = 0.2, depth_m = 0.05, push_m = 0.6, start_z_m = 0.4;
  std::unique_ptr<Simulation> sim;

  explicit Dozing(SoilModel model) {
    const scenes::Bulldoze scene{200, 200, 0.01, 1.0, layer_m, depth_m};
    SoilFlowParams soil = flow(34.0, 400000);
    soil.model = model;
    params = scene.params(soil);
    sim = std::make_unique<Simulation>(params, scene.heights());
    const int steps = int(std::lround(push_m / 0.0006));
    for (int i = 0; i <= steps; ++i) sim->step(scene.pose(start_z_m + push_m * i / steps));
  }
  double edge_y() const { return layer_m - depth_m; }
  double blade_z() const { return start_z_m + push_m; }
};

TEST(SoilDisplacement, VanishIsThePapersModel) {
  Dozing v(SoilModel::kVanish);
  EXPECT_EQ(v.sim->soil(), nullptr);
  // The cut soil is gone: 1 m x 5 cm x (the pushed length, to a cell).
  const HeightGrid& g = v.sim->grid();
  const double initial = 200 * 200 * 0.01 * 0.01 * v.layer_m;
  EXPECT_NEAR(initial - g.volume_m3(), 1.0 * v.depth_m * v.push_m, 1.0 * v.depth_m * 0.02);
}

TEST(SoilDisplacement, TheBladePushesAPileThatFollowsTheMassBalance) {
  Dozing d(SoilModel::kFlow);
  const HeightGrid& g = d.sim->grid();
  const double cell = 0.01;
  // Nothing vanished.
  const double initial = 200 * 200 * cell * cell * d.layer_m;
  EXPECT_NEAR(g.volume_m3(), initial, 1e-6 * initial);
  // The cut behind the blade stays open at the edge's height (the blade is
  // a wall): along the centre line, from 5 cm after the start to 5 cm
  // behind the blade, within the float step.
  for (double z = d.start_z_m + 0.05; z < d.blade_z() - 0.05; z += 0.01) {
    const int r = int(z / cell);
    EXPECT_NEAR(g.height(100, r), d.edge_y(), 1e-4) << "z = " << z;
  }
  // The pile ahead of the blade holds the pushed volume w d x, less what
  // spilled round the blade's ends into windrows (which partly slide back
  // into the cut): for a 1 m blade pushing 60 cm, most of it.
  double above = 0.0, ahead = 0.0, peak = 0.0;
  for (int r = 0; r < 200; ++r)
    for (int c = 0; c < 200; ++c) {
      const double excess = std::max(0.0, double(g.height(c, r)) - d.layer_m) * cell * cell;
      above += excess;
      if (std::abs((c + 0.5) * cell - 1.0) < 0.5 && (r + 0.5) * cell > d.blade_z()) {
        ahead += excess;
        peak = std::max(peak, double(g.height(c, r)) - d.layer_m);
      }
    }
  const double pushed = 1.0 * d.depth_m * d.push_m;
  EXPECT_GT(ahead, 0.75 * pushed);
  EXPECT_LT(ahead, pushed);
  EXPECT_GT(above, ahead);  // the windrows beside it
  // The pile's height, against the 2-D balance of a wedge at the repose
  // angle (h = sqrt(2 d x tan(theta))): the spill at the ends lowers it a
  // little; within 15 % (about two cells of the pile's slope).
  const double wedge = std::sqrt(2.0 * d.depth_m * d.push_m * std::tan(34.0 * kDeg));
  EXPECT_NEAR(peak, wedge, 0.15 * wedge);
  // Soil never stands above the blade's edge between the blade and the cut.
  for (std::int64_t i = 0; i < g.spec().sample_count(); ++i) EXPECT_GE(g.heights()[i], 0.0f);
}

TEST(SoilDisplacement, ThePushedPilesFaceFallsInOneSlopeFromTheBladeToTheToe) {
  // The cut soil lands where an avalanche down the face would leave it, so
  // along the centre line the face ahead of the blade falls from its top to
  // its toe without a second hump: no cell stands above the one before it
  // (to a float step of the heights), and no drop is steeper than the
  // repose limit plus the relaxation's 2 % tolerance.
  Dozing d(SoilModel::kFlow);
  const HeightGrid& g = d.sim->grid();
  const double cell = 0.01;
  const double limit = std::tan(34.0 * kDeg) * cell;
  const double float_step = 1e-6;  // a few float ulps at 0.5 m
  // From the first row whose centre is clear of the blade (0.5 cell ahead
  // of its edge) to the layer.
  int r = int(std::ceil(d.blade_z() / cell - 0.5)) + 1;
  const int top = r;
  for (; r + 1 < 200 && g.height(100, r + 1) > d.layer_m + float_step; ++r) {
    const double drop = double(g.height(100, r)) - double(g.height(100, r + 1));
    EXPECT_GE(drop, -float_step) << "row " << r;
    EXPECT_LE(drop, 1.02 * limit + float_step) << "row " << r;
  }
  // A face, not a flat: it spans at least the wedge's run, h / tan(repose),
  // less two cells.
  const double wedge = std::sqrt(2.0 * d.depth_m * d.push_m * std::tan(34.0 * kDeg));
  EXPECT_GE((r - top) * cell, wedge / std::tan(34.0 * kDeg) - 2.0 * cell);
}

TEST(SoilDisplacement, SoilLayersKeepTheirIdentity) {
  // removed = initial - height per sample, now signed: < 0 where the blade
  // put soil down.
  Dozing d(SoilModel::kFlow);
  const HeightGrid& g = d.sim->grid();
  EXPECT_LT(g.conservation_error_m(), 1e-6);
  int deposited = 0;
  for (std::int64_t i = 0; i < g.spec().sample_count(); ++i)
    if (g.removed_at(i) < 0.0f) ++deposited;
  EXPECT_GT(deposited, 100);
}

// --- Rigid obstacles ----------------------------------------------------------

TEST(SoilObstacles, ACollapsingColumnBanksAgainstABodyInsteadOfFlowingIntoIt) {
  // A column of radius 10 cells, 0.4 m tall, collapses into a cone of about
  // 26 cells' radius; a body standing on the floor 14 to 24 cells from the
  // column's centre takes none of it, and the soil banks against its face.
  const int n = 101;
  const double cell = 0.01;
  const Rect body{64, 40, 75, 61};
  HeightGrid free_grid(grid_of_cells(n, n, cell), column(n, 10.0, 0.4f));
  HeightGrid blocked(grid_of_cells(n, n, cell), column(n, 10.0, 0.4f));
  const double before = sum_heights(blocked);
  SoilFlow free_flow(flow(34.0), free_grid), blocked_flow(flow(34.0), blocked);
  const SoilObstacle obstacle{body, 0.0f};
  blocked_flow.set_obstacles({&obstacle, 1});
  settle(free_flow, free_grid);
  settle(blocked_flow, blocked);
  ASSERT_EQ(blocked_flow.active_cells(), 0);
  double inside_free = 0.0;
  for (int r = body.r0; r < body.r1; ++r)
    for (int c = body.c0; c < body.c1; ++c) {
      EXPECT_EQ(blocked.height(c, r), 0.0f) << c << "," << r;
      inside_free += free_grid.height(c, r);
    }
  EXPECT_GT(inside_free * cell * cell, 1e-4);  // without the body, soil goes there
  // Banked against the face: higher just in front of it than without.
  EXPECT_GT(blocked.height(body.c0 - 1, 50), free_grid.height(body.c0 - 1, 50) + 0.005);
  EXPECT_NEAR(sum_heights(blocked), before, 1e-6 * before);
  // The same list again changes nothing; taken away, the banked soil flows
  // on into the cells it stood against.
  blocked_flow.set_obstacles({&obstacle, 1});
  EXPECT_EQ(blocked_flow.active_cells(), 0);
  blocked_flow.set_obstacles({});
  EXPECT_GT(blocked_flow.active_cells(), 0);
  settle(blocked_flow, blocked);
  EXPECT_GT(blocked.height(body.c0, 50), 0.005f);
  EXPECT_NEAR(sum_heights(blocked), before, 1e-6 * before);
}

// A 1 m blade over a 0.2 m layer of dry sand (repose 34) on 2 m x 2 m of
// 1 cm cells, with a body resting on the sand over `body`.
constexpr float kDozeLayer = 0.2f;
std::unique_ptr<Simulation> dozing_at(const Rect& body) {
  SimParams params;
  params.grid = grid_of_cells(200, 200, 0.01);
  params.blade.length_m = 1.0;
  params.soil = flow(34.0, 400000);
  auto sim = std::make_unique<Simulation>(params, std::vector<float>(std::size_t(200) * 200, kDozeLayer));
  const SoilObstacle obstacle{body, kDozeLayer};
  sim->soil()->set_obstacles({&obstacle, 1});
  return sim;
}

TEST(SoilObstacles, ABladePushesThePileUpToABodyAndNotThroughIt) {
  // The dozing run of TheBladePushesAPile..., with a body standing on the
  // sand 10 cm beyond the end of the push: the pile grows against it, and
  // none of it enters the body's cells above the sand.
  const float layer = kDozeLayer;
  const Rect body{60, 110, 140, 130};  // x 0.6-1.4 m, z 1.1-1.3 m
  const std::unique_ptr<Simulation> dozer = dozing_at(body);
  Simulation& sim = *dozer;
  const int steps = int(std::lround(0.6 / 0.0006));
  for (int i = 0; i <= steps; ++i) sim.step({{1.0, 0.15, 0.4 + 0.6 * i / steps}, Quat{}});
  const HeightGrid& g = sim.grid();
  for (int r = body.r0; r < body.r1; ++r)
    for (int c = body.c0; c < body.c1; ++c) EXPECT_LE(g.height(c, r), layer) << c << "," << r;
  // The pile stands against the body's face (z = 1.1 m), above the layer.
  EXPECT_GT(g.height(100, body.r0 - 1), layer + 0.05);
  EXPECT_NEAR(g.volume_m3(), 200 * 200 * 0.01 * 0.01 * layer, 1e-6);
}

using test::float_rounding_m3;

TEST(SoilObstacles, ABladeCuttingUnderABodyPutsNoSoilUnderIt) {
  // A slab resting on a 0.2 m layer (its underside at the sand's top) over
  // x 0.8-1.2 m, z 0.9-1.1 m; a 1 m blade cuts 5 cm deep along +Z from
  // z = 0.4 to 1.4 m, under the slab. Under the slab the soil may only go
  // down (cut, or sliding out): none is pushed, put down or slides in (it
  // would lift the slab from below instead of banking against its side).
  // What the blade cuts under it goes round it, beside it along the edge,
  // and is pushed on.
  const float layer = kDozeLayer;
  const Rect body{80, 90, 120, 110};
  const std::unique_ptr<Simulation> dozer = dozing_at(body);
  Simulation& sim = *dozer;
  const double before = sim.grid().volume_m3();
  std::vector<float> under(std::size_t(body.area()), layer);
  const int steps = int(std::lround(1.0 / 0.0006));
  bool rose = false;
  for (int i = 0; i <= steps; ++i) {
    sim.step({{1.0, 0.15, 0.4 + 1.0 * i / steps}, Quat{}});
    std::size_t k = 0;
    for (int r = body.r0; r < body.r1; ++r)
      for (int c = body.c0; c < body.c1; ++c, ++k) {
        const float h = sim.grid().height(c, r);
        if (h > under[k]) rose = true;
        under[k] = h;
      }
  }
  EXPECT_FALSE(rose);
  const HeightGrid& g = sim.grid();
  // The blade cut under it: its cells are at the edge's height or below.
  for (int r = body.r0; r < body.r1; ++r)
    for (int c = body.c0; c < body.c1; ++c) EXPECT_LE(g.height(c, r), 0.15f + 1e-6f) << c << "," << r;
  // It is not lost: the blade pushed it on, and the pile stands ahead of
  // the blade's last position (z = 1.4 m), above the layer.
  float highest = 0.0f, ahead = 0.0f;
  for (int r = 0; r < 200; ++r)
    for (int c = 0; c < 200; ++c) {
      highest = std::max(highest, g.height(c, r));
      if (r > 140) ahead = std::max(ahead, g.height(c, r));
    }
  EXPECT_GT(ahead, layer + 0.05f);
  EXPECT_NEAR(g.volume_m3(), before, float_rounding_m3(g, highest));
}

TEST(SoilObstacles, SoilPushedIntoAStaticBodyGoesRoundItAtRepose) {
  // A static body (a boulder the plate cannot move) 20 x 20 cells resting
  // on the sand in the path of a 1 m blade cutting 5 cm, at the default
  // work cap: centred on the path, and across the blade's end. The blade
  // is driven on through it. The soil the blade meets in front of the body
  // goes round it, put down beside it at repose: after every step no
  // sample stands above all eight of its neighbours by more than the
  // repose rise over a cell's diagonal (a single column of sand standing
  // free does not hold). Before, the cut of the row in front of the body
  // went onto the one cell beside it: 3.5 and 2.1 m above its neighbours.
  SoilFlowParams soil;
  soil.model = SoilModel::kFlow;
  soil.material.repose_deg = 34.0;
  const double cell = 0.01;
  const float rise = float(std::tan(34.0 * std::numbers::pi / 180.0) * cell * std::sqrt(2.0)) + 1e-5f;
  // (With the fans too: a fan penned between the blade and the body, with
  // no room down its fall lines, kept its soil, a column 0.16 m above its
  // neighbours, until it joined the fans beside it.)
  for (const SoilSettle settle : {SoilSettle::kPatches, SoilSettle::kFans})
  for (const Rect body : {Rect{90, 110, 110, 130}, Rect{140, 110, 160, 130}}) {
    SCOPED_TRACE(to_string(settle));
    soil.settle = settle;
    SimParams params;
    params.grid = grid_of_cells(200, 200, cell);
    params.blade.length_m = 1.0;
    params.soil = soil;
    Simulation sim(params, std::vector<float>(std::size_t(200) * 200, kDozeLayer));
    const SoilObstacle obstacle{body, kDozeLayer};
    sim.soil()->set_obstacles({&obstacle, 1});
    const double before = sim.grid().volume_m3();
    float spike = 0.0f, under = 0.0f;
    for (int i = 0; i <= 1000; ++i) {
      sim.step({{1.0, 0.15, 0.5 + 0.001 * i}, Quat{}});
      const HeightGrid& g = sim.grid();
      for (int r = 1; r < 199; ++r)
        for (int c = 1; c < 199; ++c) {
          float highest = -1e9f;
          for (int dr = -1; dr <= 1; ++dr)
            for (int dc = -1; dc <= 1; ++dc)
              if (dr != 0 || dc != 0) highest = std::max(highest, g.height(c + dc, r + dr));
          spike = std::max(spike, g.height(c, r) - highest);
        }
      for (int r = body.r0; r < body.r1; ++r)
        for (int c = body.c0; c < body.c1; ++c) under = std::max(under, g.height(c, r) - kDozeLayer);
    }
    EXPECT_LE(spike, rise) << "body from column " << body.c0;
    EXPECT_LE(under, 0.0f) << "body from column " << body.c0;
    EXPECT_NEAR(sim.grid().volume_m3(), before, float_rounding_m3(sim.grid(), 1.0)) << "body from column " << body.c0;
  }
}

TEST(SoilObstacles, ABladeSweepingAlongABodyAtASlantStandsNoColumnBesideIt) {
  // A 1.25 m blade cutting 5 cm at a slant, at the default work cap, sweeps
  // along a static body 4 cells wide lying across its path (a strip along
  // Z), on 1 cm cells. The push's walk from the cut meets the body's side;
  // the soil slides along its face. After every step no sample beside the
  // body stands above all of its neighbours not under the body by more than
  // the repose rise over a cell's diagonal (a single column of sand standing
  // free does not hold), and the volume is kept. Before, the fill ended at
  // the body, and each crossing's cut between the edge and the body went
  // onto the one or two cells there, whose whole column the next crossing
  // cut and pushed on: 0.32 to 0.37 m above its free neighbours at -45,
  // -26.6 and 15 degrees, 3.2 cm at 30 (7.9 m at -26.6 on 5 mm cells).
  SoilFlowParams soil;
  soil.model = SoilModel::kFlow;
  soil.material.repose_deg = 34.0;
  const double cell = 0.01, layer = 0.2, depth = 0.05, travel = 0.7;
  const int n = 160;
  const float rise = float(std::tan(34.0 * std::numbers::pi / 180.0) * cell * std::sqrt(2.0)) + 1e-5f;
  const Rect body{75, 90, 79, 130};
  const auto in_body = [&](int c, int r) { return c >= body.c0 && c < body.c1 && r >= body.r0 && r < body.r1; };
  struct Sweep {
    double yaw_deg, speed_m_per_s;
  };
  for (const Sweep sweep : {Sweep{-26.5651, 0.7}, Sweep{30.0, 1.0}, Sweep{-45.0, 0.5}, Sweep{15.0, 1.0}}) {
    SCOPED_TRACE(sweep.yaw_deg);
    SimParams params;
    params.grid = grid_of_cells(n, n, cell);
    params.blade.length_m = 1.25;
    params.soil = soil;
    Simulation sim(params, std::vector<float>(std::size_t(n) * n, float(layer)));
    const SoilObstacle obstacle{body, float(layer)};
    sim.soil()->set_obstacles({&obstacle, 1});
    const double before = sim.grid().volume_m3();
    const double yaw = sweep.yaw_deg * std::numbers::pi / 180.0;
    const Quat q = quat_from_axis_angle({0.0, 1.0, 0.0}, yaw);
    const int steps = int(std::lround(travel / sweep.speed_m_per_s * 1000.0));
    float column = 0.0f;
    int column_step = -1;
    for (int i = 0; i <= steps; ++i) {
      const double f = double(i) / steps, along = (f - 0.5) * travel;
      const double y = layer + 0.01 - (0.01 + depth) * std::min(1.0, f / 0.2);
      sim.step({{0.8 + std::sin(yaw) * along, y, 0.8 + std::cos(yaw) * along}, q});
      const HeightGrid& g = sim.grid();
      for (int r = body.r0 - 1; r <= body.r1; ++r)
        for (int c = body.c0 - 1; c <= body.c1; ++c) {
          if (in_body(c, r)) continue;
          float highest = -1e9f;
          for (int dr = -1; dr <= 1; ++dr)
            for (int dc = -1; dc <= 1; ++dc)
              if ((dr != 0 || dc != 0) && !in_body(c + dc, r + dr)) highest = std::max(highest, g.height(c + dc, r + dr));
          if (g.height(c, r) - highest > column) column = g.height(c, r) - highest, column_step = i;
        }
    }
    EXPECT_LE(column, rise) << "at step " << column_step;
    EXPECT_NEAR(sim.grid().volume_m3(), before, float_rounding_m3(sim.grid(), 1.0));
  }
}

// Drives the blade `travel` metres at `speed` along its normal, turned
// `yaw` radians about +Y, centred on `centre` (x, z): from 1 cm above the
// layer, down to `depth` into it over the first fifth, at 1 kHz. Returns the
// steps taken after the first; `highest` is the highest sample seen.
int push_at_a_slant(Simulation& sim, Vec3 centre, double yaw, double layer, double depth, double travel,
                    double speed, float& highest) {
  const Quat q = quat_from_axis_angle({0.0, 1.0, 0.0}, yaw);
  const int steps = int(std::lround(travel / speed * 1000.0));
  const std::int64_t samples = sim.grid().spec().sample_count();
  for (int i = 0; i <= steps; ++i) {
    const double f = double(i) / steps, along = (f - 0.5) * travel;
    const double y = layer + 0.01 - (0.01 + depth) * std::min(1.0, f / 0.2);
    sim.step({{centre.x + std::sin(yaw) * along, y, centre.z + std::cos(yaw) * along}, q});
    for (std::int64_t k = 0; k < samples; ++k) highest = std::max(highest, sim.grid().heights()[k]);
  }
  return steps;
}

TEST(SoilObstacles, SoilPushedIntoAPocketAtTheCeilingKeepsItsVolume) {
  // A 1.25 m blade cutting 5 cm of a 0.2 m layer on 5 mm cells, driven at
  // 26.6 degrees through a static body 0.1 m wide, under a ceiling 0.2 m
  // above the layer (the rigid bodies' heightfield's bound, 2 full scales):
  // soil pushed into the pocket between the blade and the body stands at
  // the ceiling. Each step gives its writes' rounding back on one cell, so
  // the volume drifts by at most one float rounding of the ceiling a step.
  // Before, the settle gave its rounding back on a cell at the ceiling, and
  // the ceiling's clamp deleted it: 1.2e-8 m^3 over the push, ten times
  // that bound.
  SoilFlowParams soil;
  soil.model = SoilModel::kFlow;
  soil.material.repose_deg = 34.0;
  const double cell = 0.005, layer = 0.2, depth = 0.05, travel = 0.7, speed = 0.7;
  const float ceiling = 0.4f;
  const int n = 320;
  SimParams params;
  params.grid = grid_of_cells(n, n, cell);
  params.blade.length_m = 1.25;
  params.soil = soil;
  Simulation sim(params, std::vector<float>(std::size_t(n) * n, float(layer)));
  const SoilObstacle obstacle{Rect{150, 180, 170, 260}, float(layer)};
  sim.soil()->set_obstacles({&obstacle, 1});
  sim.soil()->set_ceiling(ceiling);
  const double before = sim.grid().volume_m3();
  const double yaw = -26.5651 * std::numbers::pi / 180.0;
  float highest = 0.0f;
  const int steps = push_at_a_slant(sim, {0.8, 0.0, 0.8}, yaw, layer, depth, travel, speed, highest);
  EXPECT_EQ(highest, ceiling);  // the pocket filled to it
  const double per_step = double(std::numeric_limits<float>::epsilon()) * ceiling * cell * cell;
  EXPECT_NEAR(sim.grid().volume_m3(), before, (steps + 1) * per_step);
}

TEST(SoilObstacles, TheSpillRoundTheEndsKeepsItsVolumeAtTheCeiling) {
  // A 0.65 m blade cutting 6 cm of a 0.2 m layer (columns, 1 cm cells, a
  // kilometre from the origin), pushed 0.7 m at 1.06 m/s along a 1:3
  // lattice direction past a static body, under a ceiling 0.1 m above the
  // layer (a case of the body sweep in docs/soil.md, "Soil slides along a
  // body's face"): what the spill round the blade's ends would stand above
  // the ceiling stays with the cells it came from, and the volume drifts by
  // at most one float rounding of the ceiling a step. Before, the spill's
  // receivers were held at the ceiling and the rest, given back on a cell
  // at the ceiling, was deleted: 4.5e-7 m^3.
  const double cell = 0.01, layer = 0.2, depth = 0.0594, travel = 0.7, speed = 1.0609;
  const float ceiling = 0.3f;
  const int n = 160;
  SimParams params;
  params.grid = grid_of_cells(n, n, cell);
  params.grid.origin_m = {1000.0, 0.0, 1000.0};
  params.representation = Representation::kColumns;
  params.blade.length_m = 0.6463;
  params.soil.model = SoilModel::kFlow;
  params.soil.material.repose_deg = 34.0;
  Simulation sim(params, std::vector<float>(std::size_t(n) * n, float(layer)));
  const SoilObstacle obstacle{Rect{106, 10, 110, 32}, 0.2075f};
  sim.soil()->set_obstacles({&obstacle, 1});
  sim.soil()->set_ceiling(ceiling);
  const double before = sim.grid().volume_m3();
  const double yaw = (180.0 + std::atan(1.0 / 3.0) * 180.0 / std::numbers::pi) * std::numbers::pi / 180.0;
  float highest = 0.0f;
  const int steps = push_at_a_slant(sim, {1000.8, 0.0, 1000.8}, yaw, layer, depth, travel, speed, highest);
  // The pile reached the ceiling and, but for a float rounding or two of
  // it, no further: the passes' sources keep what would rise past it
  // (before, the passes raised cells to 0.48 m).
  EXPECT_GE(highest, ceiling);
  EXPECT_LE(highest, ceiling * (1.0f + 4.0f * std::numeric_limits<float>::epsilon()));
  const double per_step = double(std::numeric_limits<float>::epsilon()) * ceiling * cell * cell;
  EXPECT_NEAR(sim.grid().volume_m3(), before, (steps + 1) * per_step);
}

TEST(SoilObstacles, TheDisplacementNeverPilesAboveTheCeiling) {
  // The Bullet world's heightfield has an upper bound; soil above it would
  // be clamped (deleted). A push against a body with the ceiling 6 cm above
  // the layer: no sample ever rises past it, and the volume is kept.
  const float layer = kDozeLayer, ceiling = layer + 0.06f;
  const Rect body{60, 110, 140, 130};
  const std::unique_ptr<Simulation> dozer = dozing_at(body);
  Simulation& sim = *dozer;
  sim.soil()->set_ceiling(ceiling);
  const double before = sim.grid().volume_m3();
  const int steps = int(std::lround(0.6 / 0.0006));
  // The same push twice: the ceiling also holds after Simulation::reset(),
  // which rebuilds the soil state.
  for (int pass = 0; pass < 2; ++pass) {
    if (pass == 1) sim.reset();
    float highest = 0.0f;
    for (int i = 0; i <= steps; ++i) {
      sim.step({{1.0, 0.15, 0.4 + 0.6 * i / steps}, Quat{}});
      const float* h = sim.grid().heights();
      for (std::int64_t j = 0; j < sim.grid().spec().sample_count(); ++j) highest = std::max(highest, h[j]);
    }
    EXPECT_LE(highest, ceiling) << "pass " << pass;
    EXPECT_GT(highest, ceiling - 0.01f) << "pass " << pass;  // the pile did reach it
    EXPECT_NEAR(sim.grid().volume_m3(), before, float_rounding_m3(sim.grid(), ceiling)) << "pass " << pass;
  }
}

// --- The bucket -------------------------------------------------------------

BladeSpec test_bucket(double length_m = 0.4, double depth_m = 0.3, double height_m = 0.15) {
  BladeSpec b;
  b.length_m = length_m;
  b.bucket.depth_m = depth_m;
  b.bucket.height_m = height_m;
  return b;
}

// Rotation about the blade's X (the lip): a negative angle raises the back.
Quat pitch(double deg) { return quat_from_axis_angle({1.0, 0.0, 0.0}, deg * kDeg); }

TEST(Bucket, HoldsItsStruckCapacityLevelAndNothingPastTheReposeAngle) {
  const double repose = 34.0, slope = std::tan(repose * kDeg);
  // Level, with height <= depth tan(repose): the whole triangle, L D H / 2.
  const BladeSpec b = test_bucket(0.4, 0.3, 0.15);
  const double struck = 0.4 * 0.3 * 0.15 / 2.0;
  EXPECT_NEAR(bucket_retained_m3(b, Quat{}, repose), struck, 1e-15);
  // Yaw does not matter, and nor does a curl (back lowered): still full.
  EXPECT_NEAR(bucket_retained_m3(b, quat_from_axis_angle({0.0, 1.0, 0.0}, 1.1), repose), struck, 1e-15);
  EXPECT_NEAR(bucket_retained_m3(b, pitch(40.0), repose), struck, 1e-15);
  // A tall back: the soil stands at the repose angle from the lip, the
  // triangle under y = z tan(repose): L D (D tan) / 2.
  const BladeSpec tall = test_bucket(0.4, 0.3, 0.5);
  EXPECT_NEAR(bucket_retained_m3(tall, Quat{}, repose), 0.4 * 0.3 * 0.3 * slope / 2.0, 1e-15);
  // Tilting the back up: less and less, and nothing once the floor is
  // steeper than the repose angle.
  double last = struck;
  for (double tilt = 1.0; tilt < repose; tilt += 1.0) {
    const double held = bucket_retained_m3(b, pitch(-tilt), repose);
    EXPECT_LE(held, last + 1e-15) << tilt;
    EXPECT_GT(held, 0.0) << tilt;
    last = held;
  }
  EXPECT_LT(last, 0.1 * struck);
  EXPECT_EQ(bucket_retained_m3(b, pitch(-(repose + 0.5)), repose), 0.0);
  EXPECT_EQ(bucket_retained_m3(b, pitch(-90.0), repose), 0.0);
  // Curled past a right angle, the back wall is below and carries it all.
  EXPECT_NEAR(bucket_retained_m3(b, pitch(100.0), repose), struck, 1e-15);
  // Upside down it holds nothing.
  EXPECT_NEAR(bucket_retained_m3(b, pitch(180.0), repose), 0.0, 1e-15);
  // No bucket, nothing.
  EXPECT_EQ(bucket_retained_m3(BladeSpec{}, Quat{}, repose), 0.0);
}

// A bucket on a flat layer of sand: digs along its opening (-Z), lifts,
// moves sideways and dumps by raising its back.
struct BucketCycle {
  static constexpr double kLayer = 0.2, kCell = 0.01;
  SimParams params;
  std::unique_ptr<Simulation> sim;
  double initial_m3 = 0.0;
  double worst_conservation_m3 = 0.0;  // |grid + load - initial| over every step

  BucketCycle() {
    params.grid = grid_of_cells(200, 200, kCell);
    params.blade = test_bucket();
    params.soil = flow(34.0, 400000);
    sim = std::make_unique<Simulation>(params, std::vector<float>(std::size_t(200) * 200, float(kLayer)));
    initial_m3 = sim->grid().volume_m3();
  }
  double load() const { return sim->last().soil.bucket_load_m3; }
  void step(const Vec3& p, const Quat& q) {
    sim->step({p, q});
    worst_conservation_m3 =
        std::max(worst_conservation_m3, std::abs(sim->grid().volume_m3() + load() - initial_m3));
  }
  /// Moves from a to b (and turns from qa to qb) in n steps.
  void move(const Vec3& a, const Vec3& b, int n, const Quat& qa = {}, const Quat& qb = {}) {
    for (int i = 1; i <= n; ++i) step(lerp(a, b, double(i) / n), slerp(qa, qb, double(i) / n));
  }
  double max_height() const {
    const HeightGrid& g = sim->grid();
    return *std::max_element(g.heights(), g.heights() + g.spec().sample_count());
  }
};

TEST(Bucket, ScoopsCarriesAndDumpsWithoutLosingAnything) {
  BucketCycle b;
  const double depth = 0.03, lip_y = BucketCycle::kLayer - depth;
  // The floor is a solid, so the bucket goes in as a real one does: heel
  // up, the lip plunging 3 cm while it moves 0.2 m forward (a ramp of
  // slope 0.15), the floor tilted 10 degrees (tan 0.18) so that it stays
  // above the ramp the lip cut. Then it scoops 0.5 m along -Z, 3 cm deep,
  // 0.6 mm per step. It takes in the ramp, 0.4 x 0.03 x 0.2 / 2, and the
  // scoop, 0.4 x 0.03 x 0.5: 0.0072 m^3, under what it holds tilted so
  // (0.008 m^3): all of it goes in.
  const Quat heel_up = pitch(-10.0);
  b.step({1.0, BucketCycle::kLayer, 1.8}, heel_up);
  b.move({1.0, BucketCycle::kLayer, 1.8}, {1.0, lip_y, 1.6}, 333, heel_up, heel_up);
  b.move({1.0, lip_y, 1.6}, {1.0, lip_y, 1.1}, 833, heel_up, heel_up);
  const double scooped = b.load();
  ASSERT_LT(0.4 * depth * 0.6, bucket_retained_m3(b.params.blade, heel_up, 34.0));
  EXPECT_NEAR(scooped, 0.4 * depth * (0.5 + 0.1), 0.4 * depth * 2.0 * BucketCycle::kCell);
  // The floor stayed in the lip's cut: nothing shouldered, and no pile
  // ahead of the lip: nothing stands above the layer.
  EXPECT_LE(b.max_height(), BucketCycle::kLayer + 1e-6);
  // Lift out and carry it 0.6 m sideways, above the sand: the load stays.
  b.move({1.0, lip_y, 1.1}, {1.0, 0.5, 1.1}, 300, heel_up, heel_up);
  const double carried = b.load();
  EXPECT_NEAR(carried, scooped, 0.02 * scooped);  // the lift cuts the slumped walls aside
  b.move({1.0, 0.5, 1.1}, {0.4, 0.5, 1.1}, 600, heel_up, heel_up);
  EXPECT_EQ(b.load(), carried);
  // Dump: raise the back past the repose angle (to 70 degrees over 0.5 s).
  b.move({0.4, 0.5, 1.1}, {0.4, 0.5, 1.1}, 500, heel_up, pitch(-70.0));
  EXPECT_EQ(b.load(), 0.0);
  for (int i = 0; i < 2000; ++i) b.step({0.4, 0.5, 1.1}, pitch(-70.0));  // let the dump settle
  // Everything is back on the ground, and the dump lies under the lip: the
  // soil above the layer within 0.35 m of the lip's line holds what was
  // carried.
  const HeightGrid& g = b.sim->grid();
  double dumped = 0.0;
  for (int r = 0; r < 200; ++r)
    for (int c = 0; c < 200; ++c) {
      const double x = (c + 0.5) * BucketCycle::kCell, z = (r + 0.5) * BucketCycle::kCell;
      if (std::abs(x - 0.4) < 0.2 + 0.35 && std::abs(z - 1.1) < 0.35)
        dumped += std::max(0.0, double(g.height(c, r)) - BucketCycle::kLayer) * BucketCycle::kCell * BucketCycle::kCell;
    }
  EXPECT_NEAR(dumped, carried, 0.05 * carried);
  // Conserved at every step, to float rounding of the cells' heights.
  const double rounding = 200.0 * 200.0 * 0.3 * 1.2e-7 * BucketCycle::kCell * BucketCycle::kCell;
  EXPECT_LT(b.worst_conservation_m3, 4.0 * rounding + 1e-9);
  EXPECT_NEAR(g.volume_m3(), b.initial_m3, 4.0 * rounding + 1e-9);
}

TEST(Bucket, AFullBucketSpillsAheadLikeABlade) {
  BucketCycle b;
  const double lip_y = BucketCycle::kLayer - 0.03;
  // 1.5 m at 3 cm: 0.018 m^3 cut, twice the struck capacity.
  b.step({1.0, lip_y, 1.8}, Quat{});
  b.move({1.0, lip_y, 1.8}, {1.0, lip_y, 0.3}, 2500);
  const double struck = 0.4 * 0.3 * 0.15 / 2.0;
  EXPECT_NEAR(b.load(), struck, 1e-12);
  // The rest went ahead into a pile above the layer.
  EXPECT_GT(b.max_height(), BucketCycle::kLayer + 0.02);
  EXPECT_NEAR(b.sim->grid().volume_m3() + b.load(), b.initial_m3, 1e-6);
}

// The bucket's body is a solid: a cell whose centre lies under the floor
// keeps no soil above the floor's height there. Float rounding of a height
// near 1 m: the shoulder leaves at most 4 float epsilons of excess.
constexpr double kUnderHullSlack = 8.0 * 1.2e-7;

// |grid + load - initial| allowed: the float rounding of every cell's height.
double bucket_rounding_m3() {
  return 4.0 * 200.0 * 200.0 * 0.3 * 1.2e-7 * BucketCycle::kCell * BucketCycle::kCell + 1e-9;
}

// Highest soil above the floor plate of a bucket whose lip (centre at x, z,
// height lip_y, 0.4 m long along X) slopes down toward +Z at `heel_down`
// metres of height per metre of plan (the floor's plan length is plan_m).
double worst_above_floor(const HeightGrid& g, double x, double z, double lip_y, double heel_down, double plan_m) {
  double worst = -1e9;
  for (int r = 0; r < g.rows(); ++r)
    for (int c = 0; c < g.cols(); ++c) {
      const double cx = (c + 0.5) * BucketCycle::kCell, cz = (r + 0.5) * BucketCycle::kCell;
      if (std::abs(cx - x) >= 0.2 || cz <= z || cz >= z + plan_m) continue;
      const double under = std::max(0.0, lip_y - (cz - z) * heel_down);
      worst = std::max(worst, double(g.height(c, r)) - under);
    }
  return worst;
}

TEST(Bucket, LoweredLevelIntoSoilLeavesNoneAboveItsFloor) {
  // Lowered straight down, level, 5 cm into the 0.2 m layer: the floor
  // behind the lip goes below the surface, and shoulders the soil aside.
  BucketCycle b;
  b.step({1.0, 0.25, 1.0}, Quat{});
  b.move({1.0, 0.25, 1.0}, {1.0, 0.15, 1.0}, 200);
  EXPECT_LE(worst_above_floor(b.sim->grid(), 1.0, 1.0, 0.15, 0.0, 0.3), kUnderHullSlack);
  EXPECT_GT(b.sim->last().soil.shouldered_m3 + b.sim->last().soil.displaced_volume_m3, 0.0);
  EXPECT_EQ(b.load(), 0.0);  // it did not dig toward its opening
  EXPECT_LT(b.worst_conservation_m3, bucket_rounding_m3());
  // Lifted away, the hole it left relaxes to the repose angle: no pair
  // steeper than the repose limit plus the relaxation's 2 % tolerance.
  b.move({1.0, 0.15, 1.0}, {1.0, 0.6, 1.0}, 300);
  for (int i = 0; i < 20000 && b.sim->last().soil.backlog_cells > 0; ++i) b.step({1.0, 0.6, 1.0}, Quat{});
  EXPECT_EQ(b.sim->last().soil.backlog_cells, 0);
  const HeightGrid& g = b.sim->grid();
  const double limit = std::tan(34.0 * kDeg) * BucketCycle::kCell * 1.02 + 1e-6;
  double steepest = 0.0;
  for (int r = 0; r + 1 < g.rows(); ++r)
    for (int c = 0; c + 1 < g.cols(); ++c) {
      steepest = std::max(steepest, std::abs(double(g.height(c, r)) - g.height(c + 1, r)));
      steepest = std::max(steepest, std::abs(double(g.height(c, r)) - g.height(c, r + 1)));
    }
  EXPECT_LE(steepest, limit);
  EXPECT_LT(b.worst_conservation_m3, bucket_rounding_m3());
}

TEST(Bucket, AYawedBucketLoweredIntoSoilLeavesNoneAboveItsFloor) {
  // The same lowering with the bucket turned about the vertical (37 and
  // 90 + 23 degrees): the floor's plan is a rotated rectangle that crosses
  // rows and columns obliquely, and no cell centre inside it (in the
  // bucket's frame: |u| < half the lip, 0 < w < the floor's depth) keeps
  // soil above the floor. Centres within a millionth of a cell of the
  // rectangle's edge are left out (either side is right for them).
  for (const double yaw_deg : {37.0, 113.0}) {
    BucketCycle b;
    const Quat yaw = quat_from_axis_angle({0.0, 1.0, 0.0}, yaw_deg * kDeg);
    b.step({1.0, 0.25, 1.0}, yaw);
    b.move({1.0, 0.25, 1.0}, {1.0, 0.15, 1.0}, 200, yaw, yaw);
    const Quat inverse{yaw.w, -yaw.x, -yaw.y, -yaw.z};
    const HeightGrid& g = b.sim->grid();
    const double edge = 1e-6 * BucketCycle::kCell;
    double worst = -1e9;
    int inside = 0;
    for (int r = 0; r < g.rows(); ++r)
      for (int c = 0; c < g.cols(); ++c) {
        const Vec3 d{(c + 0.5) * BucketCycle::kCell - 1.0, 0.0, (r + 0.5) * BucketCycle::kCell - 1.0};
        const Vec3 local = rotate(inverse, d);
        if (std::abs(local.x) >= 0.2 - edge || local.z <= edge || local.z >= 0.3 - edge) continue;
        ++inside;
        worst = std::max(worst, double(g.height(c, r)) - 0.15);
      }
    // The plan holds 0.4 x 0.3 m: 1200 cells, to a row of cells round its edge.
    EXPECT_NEAR(inside, 1200, 2.0 * (0.4 + 0.3) / BucketCycle::kCell) << "yaw " << yaw_deg;
    EXPECT_LE(worst, kUnderHullSlack) << "yaw " << yaw_deg;
    EXPECT_GT(b.sim->last().soil.shouldered_m3 + b.sim->last().soil.displaced_volume_m3, 0.0);
    EXPECT_LT(b.worst_conservation_m3, bucket_rounding_m3()) << "yaw " << yaw_deg;
  }
}

TEST(Bucket, PushedDownHeelFirstShouldersTheSoilAsideAndKeepsItAll) {
  // Curled 30 degrees (the back lowered), lip above the sand: only the
  // heel and the floor go in, 10 cm deep at the heel.
  BucketCycle b;
  const Quat curl = pitch(30.0);
  const double tan30 = std::tan(30.0 * kDeg), plan = 0.3 * std::cos(30.0 * kDeg);
  b.step({1.0, 0.35, 1.0}, curl);
  b.move({1.0, 0.35, 1.0}, {1.0, 0.25, 1.0}, 300, curl, curl);
  EXPECT_LE(worst_above_floor(b.sim->grid(), 1.0, 1.0, 0.25, tan30, plan), kUnderHullSlack);
  EXPECT_EQ(b.load(), 0.0);
  EXPECT_LT(b.worst_conservation_m3, bucket_rounding_m3());
  // The soil went beside and behind it: above the layer around the hull.
  EXPECT_GT(b.max_height(), BucketCycle::kLayer + 0.005);
}

TEST(Bucket, SoilPiledAgainstTheBackDoesNotFlowThroughIt) {
  // The bucket rests level on the sand (floor at the surface, heel at
  // z = 1.3); a ridge 13 cm tall (below the back's top, 15 cm) stands just
  // behind the back wall, outside.
  BucketCycle b;
  std::vector<float> h(std::size_t(200) * 200, float(BucketCycle::kLayer));
  for (int r = 130; r < 136; ++r)
    for (int c = 85; c < 115; ++c) h[std::size_t(r) * 200 + c] = float(BucketCycle::kLayer + 0.13);
  b.sim = std::make_unique<Simulation>(b.params, h);
  b.initial_m3 = b.sim->grid().volume_m3();
  for (int i = 0; i < 3000; ++i) b.step({1.0, BucketCycle::kLayer, 1.0}, Quat{});
  EXPECT_LE(worst_above_floor(b.sim->grid(), 1.0, 1.0, BucketCycle::kLayer, 0.0, 0.3), kUnderHullSlack);
  // The ridge did slump, outward and around the bucket.
  EXPECT_LT(b.max_height(), BucketCycle::kLayer + 0.12);
  EXPECT_LT(b.worst_conservation_m3, bucket_rounding_m3());
}

TEST(Bucket, SoilFlowingInFromSeveralSidesStopsAtItsFloor) {
  // The bucket held level with its floor at 0.3 m, over ground whose cells
  // under the floor alternate between pits (0.05 m) and mounds (0.29 m,
  // below the floor): each mound may shed into the pits beside it, and
  // each pit has up to four mounds beside it. One mound's fall line ends
  // below its own height; several filling one pit in the same pass raised
  // it 11.5 cm through the floor. No cell under the floor may end above
  // it, at any step.
  BucketCycle b;
  std::vector<float> h(std::size_t(200) * 200, float(BucketCycle::kLayer));
  for (int r = 102; r < 128; ++r)
    for (int c = 82; c < 118; ++c) h[std::size_t(r) * 200 + c] = (r + c) % 2 == 0 ? 0.05f : 0.29f;
  b.sim = std::make_unique<Simulation>(b.params, h);
  b.initial_m3 = b.sim->grid().volume_m3();
  double worst = -1.0;
  for (int i = 0; i < 200; ++i) {
    b.step({1.0, 0.3, 1.0}, Quat{});
    worst = std::max(worst, worst_above_floor(b.sim->grid(), 1.0, 1.0, 0.3, 0.0, 0.3));
  }
  EXPECT_LE(worst, kUnderHullSlack);
  // The mounds did fill the pits: once at rest, no pair of neighbours in
  // the patch is steeper than the repose angle (plus the relaxation's 2 %
  // tolerance).
  EXPECT_EQ(b.sim->last().soil.backlog_cells, 0);
  const HeightGrid& g = b.sim->grid();
  const double limit = std::tan(34.0 * kDeg) * BucketCycle::kCell * 1.02 + 1e-6;
  double steepest = 0.0;
  for (int r = 102; r < 128; ++r)
    for (int c = 82; c < 118; ++c) {
      steepest = std::max(steepest, std::abs(double(g.height(c, r)) - g.height(c + 1, r)));
      steepest = std::max(steepest, std::abs(double(g.height(c, r)) - g.height(c, r + 1)));
    }
  EXPECT_LE(steepest, limit);
  EXPECT_LT(b.worst_conservation_m3, bucket_rounding_m3());
}

TEST(Bucket, NeedsSoilThatFlowsAndAShape) {
  SimParams p;
  p.grid = grid_of_cells(20, 20, 0.01);
  p.blade = test_bucket();
  try {
    Simulation s(p, std::vector<float>(400, 0.1f));
    ADD_FAILURE() << "a bucket with soil that vanishes must be refused";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("blade.bucket"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("flow"), std::string::npos) << e.what();
  }
  p.soil = flow(34.0);
  p.blade.bucket.height_m = 0.0;
  EXPECT_THROW(Simulation(p, std::vector<float>(400, 0.1f)), InputError);
  p.blade.bucket.height_m = std::nan("");
  EXPECT_THROW(Simulation(p, std::vector<float>(400, 0.1f)), InputError);
  p.blade.bucket.height_m = 0.1;
  p.blade.bucket.depth_m = -0.1;
  EXPECT_THROW(Simulation(p, std::vector<float>(400, 0.1f)), InputError);
}

}  // namespace
}  // namespace terracut
