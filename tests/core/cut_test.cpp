// Swept cutting: no tunnelling, conservation, order independence, and
// equality with the brute-force oracle.
#include "terracut/core/cut.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <random>

#include "terracut/core/brute_force.hpp"
#include "terracut/core/simulation.hpp"
#include "test_terrains.hpp"

namespace terracut {
namespace {

constexpr Representation kBoth[] = {Representation::kColumns, Representation::kSurface};

// Float rounding of one height, relative to the full scale.
constexpr double kFloatTol = 4.0 * 1.2e-7;

Segment horizontal_edge(double x0, double x1, double y, double z) { return {{x0, y, z}, {x1, y, z}}; }

// A blade moving 3.7 cells per step along +Z at height y0 cuts every sample
// it passed over down to y0, and nothing else.
TEST(Cut, FastBladeCutsEverythingItPassesThrough) {
  const int n = 60;
  GridSpec s = test::square_spec(n, n);
  const double y0 = 0.3, step = 3.7 * s.cell_z_m();
  // Ends placed off the cell boundaries (a touch exactly on a boundary is decided by rounding).
  const double x0 = 0.2 + 0.3 / n, x1 = 0.8 + 0.4 / n, z_start = 0.05 + 0.2 / n, z_end = 0.9 + 0.1 / n;
  for (Representation rep : kBoth) {
    HeightGrid grid(s, std::vector<float>(n * n, 0.7f));
    Segment previous = horizontal_edge(x0, x1, y0, z_start);
    double z = z_start;
    while (z < z_end) {
      z = std::min(z + step, z_end);
      Segment next = horizontal_edge(x0, x1, y0, z);
      cut_sweep(grid, rep, previous, next);
      previous = next;
    }
    for (int r = 0; r < n; ++r) {
      for (int c = 0; c < n; ++c) {
        double h = grid.height(c, r);
        bool swept;
        if (rep == Representation::kSurface) {
          // Sample points inside the swept rectangle.
          double x = grid.sample_x(c), zc = grid.sample_z(r);
          swept = x >= x0 && x <= x1 && zc >= z_start && zc <= z_end;
        } else {
          // Cells the swept rectangle overlaps.
          double cx0 = c * s.cell_x_m(), cz0 = r * s.cell_z_m();
          swept = cx0 + s.cell_x_m() >= x0 && cx0 <= x1 && cz0 + s.cell_z_m() >= z_start && cz0 <= z_end;
        }
        if (swept) {
          EXPECT_NEAR(h, y0, kFloatTol) << to_string(rep) << " c=" << c << " r=" << r;
        } else {
          EXPECT_EQ(h, 0.7f) << to_string(rep) << " c=" << c << " r=" << r;
        }
      }
    }
  }
}

// A blade spinning 40 degrees per step about the vertical axis through its
// centre sweeps a disc sector: sub-steps make it follow the arc, so every
// sample well inside the sector is cut and every sample well outside the
// disc is not.
TEST(Cut, FastRotationFollowsTheArc) {
  const int n = 80;
  GridSpec s = test::square_spec(n, n);
  SimParams p;
  p.grid = s;
  p.blade.length_m = 0.8;
  for (Representation rep : kBoth) {
    p.representation = rep;
    Simulation sim(p, std::vector<float>(n * n, 0.5f));
    const double y0 = 0.2, step_deg = 40.0, total_deg = 160.0;
    for (double a = 0.0; a <= total_deg + 1e-9; a += step_deg) {
      sim.step({{0.5, y0, 0.5}, quat_from_axis_angle({0, 1, 0}, a * std::numbers::pi / 180.0)});
    }
    EXPECT_GT(sim.last().substeps, 1);
    const double margin = 1.5 * s.cell_x_m();
    for (int r = 0; r < n; ++r) {
      for (int c = 0; c < n; ++c) {
        double dx = sim.grid().sample_x(c) - 0.5, dz = sim.grid().sample_z(r) - 0.5;
        double radius = std::hypot(dx, dz);
        // Blade along local X rotated about +Y by a: direction (cos a, 0, -sin a);
        // either end, so the swept angle is taken modulo 180 degrees.
        double angle = std::fmod(std::atan2(-dz, dx) * 180.0 / std::numbers::pi + 360.0, 180.0);
        double h = sim.grid().height(c, r);
        if (radius > 0.4 + margin) {
          EXPECT_EQ(h, 0.5f) << to_string(rep);
        } else if (radius < 0.4 - margin && radius > margin && angle > 3.0 && angle < 157.0) {
          EXPECT_NEAR(h, y0, kFloatTol) << to_string(rep) << " r=" << radius << " angle=" << angle;
        }
      }
    }
  }
}

// A sweep above the material changes nothing.
TEST(Cut, SweepAboveMaterialChangesNothing) {
  GridSpec s = test::square_spec(20, 20);
  for (Representation rep : kBoth) {
    HeightGrid grid(s, std::vector<float>(400, 0.3f));
    CutResult r = cut_sweep(grid, rep, horizontal_edge(0, 1, 0.5, 0.1), horizontal_edge(0, 1, 0.5, 0.9));
    EXPECT_EQ(r.removed_volume_m3, 0.0);
    EXPECT_TRUE(r.changed.empty());
    for (int i = 0; i < 400; ++i) EXPECT_EQ(grid.heights()[i], 0.3f);
  }
}

// Below the ground is a rigid floor: a blade inside it touches no material
// and cuts nothing (its contact is 0 too), and heights never go below 0.
TEST(Cut, BladeInsideTheFloorCutsNothing) {
  GridSpec s = test::square_spec(20, 20);
  for (Representation rep : kBoth) {
    HeightGrid grid(s, std::vector<float>(400, 0.3f));
    CutResult r = cut_sweep(grid, rep, horizontal_edge(0, 1, -0.5, 0.1), horizontal_edge(0, 1, -0.5, 0.9));
    EXPECT_EQ(r.removed_volume_m3, 0.0) << to_string(rep);
    for (int i = 0; i < 400; ++i) ASSERT_EQ(grid.heights()[i], 0.3f) << to_string(rep);
    EXPECT_EQ(measure_contact(grid, rep, horizontal_edge(0, 1, -0.5, 0.5)).length_m, 0.0);
  }
}

// A tilted blade half inside the floor: y = 0.2 at x = 0 down to -0.2 at
// x = 1, swept along Z. Where it is above the floor (x < 0.5) the soil is cut
// to the blade; where it is inside the floor nothing is cut; nothing goes
// below 0. Equal to the brute force.
TEST(Cut, SweepCrossingTheFloorCutsOnlyAboveIt) {
  GridSpec s = test::square_spec(40, 40);
  for (Representation rep : kBoth) {
    HeightGrid grid(s, std::vector<float>(1600, 0.3f)), oracle(s, std::vector<float>(1600, 0.3f));
    Segment from{{0.0, 0.2, 0.1}, {1.0, -0.2, 0.1}}, to{{0.0, 0.2, 0.9}, {1.0, -0.2, 0.9}};
    CutResult fast = cut_sweep(grid, rep, from, to);
    CutResult slow = cut_sweep_brute_force(oracle, rep, from, to);
    EXPECT_NEAR(fast.removed_volume_m3, slow.removed_volume_m3, 1e-9) << to_string(rep);
    for (int r = 0; r < 40; ++r) {
      for (int c = 0; c < 40; ++c) {
        const double zc = grid.sample_z(r);
        const float h = grid.height(c, r);
        ASSERT_GE(h, 0.0f);
        ASSERT_NEAR(h, oracle.height(c, r), 1e-6) << to_string(rep);
        if (zc < 0.15 || zc > 0.85) continue;  // away from the sweep's z edges
        // Blade height at the sample (surface) or the cell's lowest point (columns).
        double x = rep == Representation::kSurface ? grid.sample_x(c) : (c + 1) * s.cell_x_m();
        double y = 0.2 - 0.4 * x;
        if (x < 0.5 - s.cell_x_m()) {
          EXPECT_NEAR(h, y, 1e-6) << to_string(rep) << " c=" << c;
        } else if (rep == Representation::kSurface ? x > 0.5 : c * s.cell_x_m() > 0.5) {
          EXPECT_EQ(h, 0.3f) << to_string(rep) << " c=" << c;
        }
      }
    }
  }
}

// Random cuts on a random terrain: height + removed = initial for every sample,
// and the volume booked per cut adds up to the volume lost.
TEST(Cut, ConservationAfterRandomCuts) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (Representation rep : kBoth) {
    GridSpec s = test::square_spec(64, 48, 1.0, 1.0);
    std::vector<float> h(size_t(s.sample_count()));
    for (float& v : h) v = float(unit(rng));
    HeightGrid grid(s, h);
    double initial_volume = grid.volume_m3(), booked = 0.0;
    for (int k = 0; k < 200; ++k) {
      auto point = [&] { return Vec3{unit(rng) * 1.4 - 0.2, unit(rng), unit(rng) * 1.4 - 0.2}; };
      Segment a{point(), point()};
      Segment b{a.a + Vec3{0.05, 0.0, 0.05} * (unit(rng) - 0.5), a.b + Vec3{0.03, -0.02, 0.08} * (unit(rng) - 0.5)};
      booked += cut_sweep(grid, rep, a, b).removed_volume_m3;
    }
    EXPECT_LE(grid.conservation_error_m(), kFloatTol);
    EXPECT_NEAR(initial_volume - grid.volume_m3(), booked, 1e-9 * initial_volume + 1e-12) << to_string(rep);
    EXPECT_GT(booked, 0.0);
  }
}

// The paper's three cuts (experiment 2) applied in all six orders give the same final heights.
TEST(Cut, FinalShapeDoesNotDependOnOrder) {
  GridSpec s = test::square_spec(35, 35);
  auto keyframes = [](double y0, double y1, double z0, double z1, double rz1) {
    Motion m;
    m.keyframes = {{0.0, {{0.5, y0, z0}, Quat{}}},
                   {2.0, {{0.5, y1, z1}, quat_from_euler_deg({0, 0, rz1})}}};
    return m;
  };
  std::array<Motion, 3> cuts = {keyframes(0.75, 0.70, -0.1, 1.1, 45.0),
                                keyframes(0.5, 0.5, 1.1, -0.1, 0.0),
                                keyframes(0.75, 0.70, -0.1, 1.1, -26.57)};
  for (Representation rep : kBoth) {
    SimParams p;
    p.grid = s;
    p.representation = rep;
    p.blade.length_m = 1.6;
    std::array<int, 3> order = {0, 1, 2};
    std::vector<float> reference;
    double reference_removed = 0.0;
    do {
      Simulation sim(p, std::vector<float>(35 * 35, 1.0f));
      for (int k : order) {
        sim.lift();
        for (int i = 0; i <= 2000; ++i) sim.step(cuts[size_t(k)].sample(i / 1000.0));
      }
      std::vector<float> final(sim.grid().heights(), sim.grid().heights() + 35 * 35);
      if (reference.empty()) {
        reference = final;
        reference_removed = sim.removed_volume_m3();
        EXPECT_GT(reference_removed, 0.1);
      } else {
        EXPECT_EQ(final, reference) << to_string(rep) << " order " << order[0] << order[1] << order[2];
        EXPECT_NEAR(sim.removed_volume_m3(), reference_removed, 1e-9);
      }
    } while (std::next_permutation(order.begin(), order.end()));
  }
}

// The traversal cut equals the brute-force cut on random terrains and sweeps.
TEST(Cut, TraversalEqualsBruteForceOnRandomCases) {
  std::mt19937 rng(1234);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 150; ++trial) {
    GridSpec s;
    s.cols = 1 + int(unit(rng) * 25);
    s.rows = 1 + int(unit(rng) * 25);
    s.size_x_m = 0.5 + unit(rng);
    s.size_z_m = 0.5 + unit(rng);
    s.origin_m = {unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5};
    std::vector<float> h(size_t(s.sample_count()));
    for (float& v : h) v = float(unit(rng));
    auto point = [&] {
      return Vec3{s.origin_m.x + (unit(rng) * 1.6 - 0.3) * s.size_x_m, s.origin_m.y + unit(rng),
                  s.origin_m.z + (unit(rng) * 1.6 - 0.3) * s.size_z_m};
    };
    for (Representation rep : kBoth) {
      HeightGrid fast(s, h), slow(s, h);
      for (int k = 0; k < 5; ++k) {
        Segment from{point(), point()};
        // Small moves (a haptic step) and large jumps (tunnelling cases).
        double reach = k % 2 == 0 ? 0.05 : 0.6;
        Vec3 shift{(unit(rng) - 0.5) * reach, (unit(rng) - 0.5) * reach, (unit(rng) - 0.5) * reach};
        Segment to{from.a + shift, from.b + shift * (0.5 + unit(rng))};
        CutResult a = cut_sweep(fast, rep, from, to);
        CutResult b = cut_sweep_brute_force(slow, rep, from, to);
        ASSERT_NEAR(a.removed_volume_m3, b.removed_volume_m3, 1e-6 * s.size_x_m * s.size_z_m)
            << to_string(rep) << " trial " << trial;
        if (!b.changed.empty()) {
          Rect both = a.changed;
          both.include(b.changed);
          EXPECT_EQ(both, a.changed) << "the traversal's changed rectangle must hold every change";
        }
      }
      for (std::int64_t i = 0; i < s.sample_count(); ++i) {
        ASSERT_NEAR(fast.heights()[i], slow.heights()[i], 1e-6) << to_string(rep) << " trial " << trial;
      }
    }
  }
}

// Long blades translated obliquely across many sample rows (the case the
// parallelogram walks of both representations handle) cut exactly what the
// brute force cuts.
TEST(Cut, ObliqueTranslationsEqualBruteForce) {
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  GridSpec s = test::square_spec(96, 80, 1.0, 1.0);
  std::vector<float> h(size_t(s.sample_count()));
  for (float& v : h) v = float(0.2 + 0.6 * unit(rng));
  for (Representation rep : kBoth) {
    HeightGrid fast(s, h), slow(s, h);
    for (int k = 0; k < 40; ++k) {
      const double yaw = 2.0 * 3.14159265358979 * unit(rng), len = 0.3 + 0.9 * unit(rng);
      const Vec3 centre{0.1 + 0.8 * unit(rng), 0.1 + 0.8 * unit(rng), 0.1 + 0.8 * unit(rng)};
      const Vec3 half{0.5 * len * std::cos(yaw), 0.1 * (unit(rng) - 0.5), 0.5 * len * std::sin(yaw)};
      // A move of a few millimetres to a few cells, in any direction.
      const double reach = k % 2 ? 0.0008 : 0.04;
      const Vec3 shift{(unit(rng) - 0.5) * reach, (unit(rng) - 0.5) * reach * 0.2, (unit(rng) - 0.5) * reach};
      const Segment from{centre - half, centre + half}, to{from.a + shift, from.b + shift};
      CutResult a = cut_sweep(fast, rep, from, to);
      CutResult b = cut_sweep_brute_force(slow, rep, from, to);
      ASSERT_NEAR(a.removed_volume_m3, b.removed_volume_m3, 1e-6) << to_string(rep) << " k=" << k;
    }
    for (std::int64_t i = 0; i < s.sample_count(); ++i)
      ASSERT_NEAR(fast.heights()[i], slow.heights()[i], 1e-6) << to_string(rep) << " sample " << i;
  }
}

// Gently waving ground, 0.35 to 0.45 m, so that every cut removes soil.
std::vector<float> wavy_heights(const GridSpec& s) {
  std::vector<float> h(size_t(s.sample_count()));
  for (int r = 0; r < s.rows; ++r)
    for (int c = 0; c < s.cols; ++c) h[size_t(r * s.cols + c)] = float(0.4 + 0.05 * std::sin(0.3 * c + 0.2 * r));
  return h;
}

// Blades turned by a quaternion to the grid's axes and diagonals (yaw 90
// degrees leaves cos(pi/2) ~ 6e-17 in the edge, a side "nearly along a
// row"), moving along their normal a fraction of a cell per step as a
// haptic hand does: the parallelogram walks take them and cut what the
// brute force cuts, step after step.
TEST(Cut, AxisAndDiagonalTranslationsEqualBruteForce) {
  GridSpec s = test::square_spec(64, 64, 1.0, 1.0);
  const std::vector<float> h = wavy_heights(s);
  for (Representation rep : kBoth) {
    for (double yaw_deg : {90.0, 270.0, 45.0, 135.0, 180.0}) {
      HeightGrid fast(s, h), slow(s, h);
      const Quat q = quat_from_axis_angle({0.0, 1.0, 0.0}, yaw_deg * std::numbers::pi / 180.0);
      const Vec3 half = rotate(q, {0.3, 0.0, 0.0}), normal = rotate(q, {0.0, 0.0, 1.0});
      Vec3 centre{0.5, 0.38, 0.5};
      centre = centre - normal * 0.1;
      Segment from{centre - half, centre + half};
      for (int k = 0; k < 60; ++k) {
        // 0.37 cells per step, slightly descending: a plane, not a level cut.
        const Vec3 shift = normal * (0.37 / 64.0) + Vec3{0.0, -0.0004, 0.0};
        const Segment to{from.a + shift, from.b + shift};
        CutResult a = cut_sweep(fast, rep, from, to);
        CutResult b = cut_sweep_brute_force(slow, rep, from, to);
        ASSERT_NEAR(a.removed_volume_m3, b.removed_volume_m3, 1e-7) << to_string(rep) << " yaw " << yaw_deg << " k " << k;
        from = to;
      }
      for (std::int64_t i = 0; i < s.sample_count(); ++i)
        ASSERT_NEAR(fast.heights()[i], slow.heights()[i], kFloatTol) << to_string(rep) << " yaw " << yaw_deg << " sample " << i;
      EXPECT_LE(fast.conservation_error_m(), 1e-6);
    }
  }
}

// A grid turned a quarter turn: sample (c, r) of the original is sample
// (r, n - 1 - c) of the turned one, and a point (x, y, z) is (z, y, size - x)
// (the grid's origin at 0, square). Exact for dyadic coordinates.
std::vector<float> quarter_turn(const std::vector<float>& h, int n) {
  std::vector<float> out(h.size());
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) out[size_t((n - 1 - c) * n + r)] = h[size_t(r * n + c)];
  return out;
}
Vec3 quarter_turn(const Vec3& p, double size) { return {p.z, p.y, size - p.x}; }

// The same cut at yaw theta and at theta + 90 degrees on the grid turned to
// match lowers the same samples to the same heights, bit for bit. The
// geometry is exact (cells of 1/64 m, the blade's ends, its run along the
// grid and its step dyadic, the plane's slopes dyadic), so no rounding can
// tell the two apart: a blade a few degrees off the rows (the row walk, long
// spans) against the same blade a few degrees off the columns (the column
// walk of the steep band), the closed boundary included (the edge passes
// through sample centres). Several steps, the blade descending.
TEST(Cut, QuarterTurnCutsTheSameSamples) {
  const int n = 128;
  const double size = 2.0, cell = size / n;  // 1/64 m
  GridSpec s = test::square_spec(n, n, size, 1.0);
  std::mt19937 rng(77);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<float> h(size_t(n) * n);
  for (float& v : h) v = float(0.45 + 0.1 * unit(rng));
  // The edge's run along x and z in cells (k:1 is a yaw of atan(1/k); 1:0
  // along the rows), and the step along z in cells.
  struct Run {
    double dx, dz, step;
  };
  const Run runs[] = {{64, 8, 2.0}, {64, -8, 2.0}, {64, 4, 1.0}, {64, 2, 1.5}, {64, 0, 1.5}, {64, 16, 0.5}, {32, -1, 0.75}};
  for (const Run& run : runs) {
    for (Representation rep : {Representation::kSurface}) {
      HeightGrid a(s, h), b(s, quarter_turn(h, n));
      // From sample (20, 30)'s centre, under the material (at least 0.45 m)
      // everywhere: rising 1/32 m along the edge, descending 1/128 m a step.
      Vec3 p0{20.5 * cell, 0.40625, 30.5 * cell}, p1 = p0 + Vec3{run.dx * cell, 0.03125, run.dz * cell};
      const Vec3 shift{0.0, -1.0 / 128.0, run.step * cell};
      for (int k = 0; k < 12; ++k) {
        const Segment from{p0, p1}, to{p0 + shift, p1 + shift};
        const CutResult ra = cut_sweep(a, rep, from, to);
        const CutResult rb = cut_sweep(b, rep, {quarter_turn(from.a, size), quarter_turn(from.b, size)},
                                       {quarter_turn(to.a, size), quarter_turn(to.b, size)});
        // The removed sums add the same drops, maybe in another order.
        ASSERT_NEAR(ra.removed_volume_m3, rb.removed_volume_m3, 1e-12) << "run " << run.dx << ":" << run.dz << " k " << k;
        ASSERT_EQ(ra.cells_visited, rb.cells_visited) << "run " << run.dx << ":" << run.dz << " k " << k;
        p0 = to.a, p1 = to.b;
      }
      const std::vector<float> turned = quarter_turn(std::vector<float>(a.heights(), a.heights() + n * n), n);
      int changed = 0;
      for (int i = 0; i < n * n; ++i) {
        ASSERT_EQ(turned[size_t(i)], b.heights()[i]) << "run " << run.dx << ":" << run.dz << " sample " << i;
        changed += a.heights()[i] != h[size_t(i)];
      }
      // Every sample swept is lowered (the blade is under the material):
      // the 12 steps' parallelogram, |dx| x 12 step cells, give or take
      // its boundary (two samples a row at most, plus the ends).
      const double area = std::abs(run.dx) * 12.0 * run.step, rows_crossed = std::abs(run.dz) + 12.0 * run.step;
      EXPECT_NEAR(changed, area, 2.0 * rows_crossed + 2.0 * std::abs(run.dx) / std::max(1.0, std::abs(run.dz)) + 2.0)
          << "run " << run.dx << ":" << run.dz;
    }
  }
}

// Blades within 15 degrees of the columns (the column walk's yaws and the
// row walk's beyond them) moving along their normal a fraction of a cell per
// step, both representations: the same cut as the brute force, and the
// volume the cuts report is the volume the grid lost, at 48 yaws.
TEST(Cut, SteepYawsEqualBruteForceAndConserveVolume) {
  GridSpec s = test::square_spec(96, 96, 1.0, 1.0);
  const std::vector<float> h = wavy_heights(s);
  for (Representation rep : kBoth) {
    for (int k = 0; k < 48; ++k) {
      // 75 to 105 degrees and the same about 270, and a few in between.
      const double yaw_deg = k < 20 ? 75.0 + 1.5 * k + 0.37 : k < 40 ? 255.0 + 1.5 * (k - 20) + 0.61 : 7.5 * (k - 40) + 1.3;
      HeightGrid fast(s, h), slow(s, h);
      const double volume0 = fast.volume_m3();
      const Quat q = quat_from_axis_angle({0.0, 1.0, 0.0}, yaw_deg * std::numbers::pi / 180.0);
      const Vec3 half = rotate(q, {0.35, 0.0, 0.0}), normal = rotate(q, {0.0, 0.0, 1.0});
      Vec3 centre = Vec3{0.5, 0.39, 0.5} - normal * 0.1;
      Segment from{centre - half, centre + half};
      double removed = 0.0;
      for (int step = 0; step < 40; ++step) {
        const Vec3 shift = normal * (0.53 / 96.0) + Vec3{0.0, -0.0003, 0.0};
        const Segment to{from.a + shift, from.b + shift};
        const CutResult a = cut_sweep(fast, rep, from, to);
        const CutResult b = cut_sweep_brute_force(slow, rep, from, to);
        ASSERT_NEAR(a.removed_volume_m3, b.removed_volume_m3, 1e-7) << to_string(rep) << " yaw " << yaw_deg;
        removed += a.removed_volume_m3;
        from = to;
      }
      for (std::int64_t i = 0; i < s.sample_count(); ++i)
        ASSERT_NEAR(fast.heights()[i], slow.heights()[i], kFloatTol) << to_string(rep) << " yaw " << yaw_deg << " sample " << i;
      EXPECT_LE(fast.conservation_error_m(), 1e-6);
      // Each drop is a float difference (rounded to half an ulp of 0.5 m at
      // most, 3e-8 m) over a cell of 1/96^2 m^2; the blade lowers fewer
      // than 96 x 40 samples.
      EXPECT_GT(removed, 0.0) << to_string(rep) << " yaw " << yaw_deg;
      EXPECT_NEAR(volume0 - fast.volume_m3(), removed, 96.0 * 40.0 * 3e-8 / (96.0 * 96.0))
          << to_string(rep) << " yaw " << yaw_deg;
    }
  }
}

// The columns cut with the blade at rest is the paper's rule: each column the
// line passes through is lowered until its top is at the line.
TEST(Cut, ColumnsAtRestLowerToTheLine) {
  GridSpec s = test::square_spec(10, 10);
  HeightGrid grid(s, std::vector<float>(100, 1.0f));
  // A line along X tilted from y = 0.2 at x = 0 to y = 0.7 at x = 1, at z = 0.55 (row 5).
  Segment edge{{0.0, 0.2, 0.55}, {1.0, 0.7, 0.55}};
  cut_sweep(grid, Representation::kColumns, edge, edge);
  for (int c = 0; c < 10; ++c) {
    EXPECT_NEAR(grid.height(c, 5), 0.2 + 0.05 * c, 1e-6) << "column " << c;  // lowest point in the cell
    EXPECT_EQ(grid.height(c, 4), 1.0f);
    EXPECT_EQ(grid.height(c, 6), 1.0f);
  }
}

}  // namespace
}  // namespace terracut
