// The optimised walks and rasterisers against the brute-force oracle on
// larger terrains and long edges, where their fast paths (column by column,
// two columns at a time, row spans, merged triangles) do most of the work,
// and in the directions that take special branches: exactly along an axis,
// exactly diagonal (both ways), nearly along an axis, steep and shallow.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "terracut/core/brute_force.hpp"
#include "terracut/core/contact.hpp"
#include "terracut/core/cut.hpp"

namespace terracut {
namespace {

constexpr Representation kBoth[] = {Representation::kColumns, Representation::kSurface};

/// A terrain of rolling hills with noise on a non-square, offset grid, so
/// that an edge at a fixed height is in and out of material many times.
struct Terrain {
  GridSpec spec;
  std::vector<float> heights;
};

Terrain make_terrain(int cols, int rows, unsigned seed) {
  Terrain t;
  t.spec.cols = cols;
  t.spec.rows = rows;
  t.spec.size_x_m = 1.3;
  t.spec.size_z_m = 0.9;
  t.spec.origin_m = {-0.4, 0.25, 0.3};
  t.spec.full_scale_m = 1.0;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> noise(-0.05, 0.05);
  t.heights.resize(size_t(cols) * size_t(rows));
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      double x = double(c) / cols, z = double(r) / rows;
      double h = 0.45 + 0.3 * std::sin(9.0 * x) * std::cos(7.0 * z) + noise(rng);
      t.heights[size_t(r) * size_t(cols) + size_t(c)] = float(std::max(0.0, h));
    }
  }
  return t;
}

/// An edge through the terrain's centre region in direction (du, dv) given
/// in cells, long enough to cross most of the terrain, with a height that
/// rises from y0 to y1 above the ground.
Segment edge_in_cells(const GridSpec& s, double cu, double cv, double du, double dv, double y0,
                      double y1) {
  double cx = s.cell_x_m(), cz = s.cell_z_m();
  Vec3 a{s.origin_m.x + (cu - du / 2) * cx, s.origin_m.y + y0, s.origin_m.z + (cv - dv / 2) * cz};
  Vec3 b{s.origin_m.x + (cu + du / 2) * cx, s.origin_m.y + y1, s.origin_m.z + (cv + dv / 2) * cz};
  return {a, b};
}

void expect_same_contact(const HeightGrid& grid, const Segment& edge, const char* what,
                         double tolerance = 1e-9, const Segment* oracle_edge = nullptr,
                         bool surface_only = false) {
  double scale = 1.0 + length(edge.b - edge.a);
  for (Representation rep : kBoth) {
    if (surface_only && rep != Representation::kSurface) continue;
    ContactResult fast = measure_contact(grid, rep, edge);
    ContactResult slow = measure_contact_brute_force(grid, rep, oracle_edge ? *oracle_edge : edge);
    EXPECT_NEAR(fast.length_m, slow.length_m, tolerance * scale) << to_string(rep) << " " << what;
    EXPECT_NEAR(fast.section_area_m2, slow.section_area_m2, tolerance * scale) << to_string(rep) << " " << what;
    EXPECT_NEAR(fast.max_depth_m, slow.max_depth_m, tolerance) << to_string(rep) << " " << what;
    // Only cells along the way: the cells between the ends, plus a few at
    // the ends and the border.
    double du = std::abs(edge.b.x - edge.a.x) / grid.spec().cell_x_m();
    double dv = std::abs(edge.b.z - edge.a.z) / grid.spec().cell_z_m();
    EXPECT_LE(double(fast.cells_visited), du + dv + 8) << to_string(rep) << " " << what;
  }
}

// Long edges in every kind of direction, at heights that go in and out of
// the hills, against the brute force.
TEST(PerfTraversal, LongEdgesEqualBruteForce) {
  Terrain t = make_terrain(240, 180, 11);
  HeightGrid grid(t.spec, t.heights);
  struct Direction {
    double du, dv;
    const char* name;
  };
  const Direction directions[] = {
      {200, 0, "along +x"},          {-200, 0, "along -x"},         {0, 150, "along +z"},
      {0, -150, "along -z"},         {140, 140, "diagonal"},        {140, -140, "anti-diagonal"},
      {-140, 140, "anti-diagonal back"}, {200, 0.7, "nearly along x"}, {0.9, 150, "nearly along z"},
      {200, 35, "shallow"},          {200, -60, "shallow down"},    {60, 150, "steep"},
      {-45, -150, "steep back"},     {180, 179, "nearly diagonal"}, {181, -180, "nearly anti-diagonal"},
  };
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (const Direction& d : directions) {
    for (int k = 0; k < 6; ++k) {
      // Centres at generic positions (edges exactly on cell walls and node
      // lines are brute_force_test.cpp's).
      double cu = 120.0123 + unit(rng) * 10.0 - 5.0;
      double cv = 90.0371 + unit(rng) * 10.0 - 5.0;
      double y0 = 0.1 + 0.6 * unit(rng), y1 = k % 3 == 0 ? y0 : 0.1 + 0.6 * unit(rng);
      Segment edge = edge_in_cells(t.spec, cu, cv, d.du, d.dv, y0, y1);
      expect_same_contact(grid, edge, d.name);
    }
  }
}

// Edges lying exactly on the surface's node lines and diagonals, and
// through nodes: the surface is continuous there, so the contact equals the
// brute force's for the edge moved off the line by a hair (1e-7 cell).
TEST(PerfTraversal, EdgesOnNodeLinesMatchNearbyEdges) {
  Terrain t = make_terrain(240, 180, 14);
  HeightGrid grid(t.spec, t.heights);
  // Node (c, r) sits at cell coordinates (c + 0.5, r + 0.5).
  const double cases[][4] = {
      {120.5, 90.5, 200, 0},   {120.5, 90.5, 0, 150},  {120.5, 90.5, 140, 140},
      {120.5, 90.5, 140, -140}, {120.5, 90.5, -140, 140}, {120.5, 90.2, 0, -150},
      {120.3, 90.5, -200, 0},  {119.5, 90.5, 150, 75},
  };
  const double hair = 1e-7;
  for (const auto& c : cases) {
    for (double y : {0.25, 0.45}) {
      Segment edge = edge_in_cells(t.spec, c[0], c[1], c[2], c[3], y, y + 0.1);
      // Off the line, perpendicular to it.
      double norm = std::hypot(c[2], c[3]);
      Segment off = edge_in_cells(t.spec, c[0] - hair * c[3] / norm, c[1] + hair * c[2] / norm, c[2], c[3], y,
                                  y + 0.1);
      expect_same_contact(grid, edge, "on a node line", 1e-6, &off, /*surface_only=*/true);
    }
  }
}

// Edges running out of the terrain, along its border rows and columns, and
// dipping below the ground.
TEST(PerfTraversal, EdgesAtTheBorderEqualBruteForce) {
  Terrain t = make_terrain(160, 120, 12);
  HeightGrid grid(t.spec, t.heights);
  const double cases[][6] = {
      // cu, cv, du, dv, y0, y1 (cells, cells, cells, cells, m, m)
      {80.01, 0.2, 400, 0, 0.3, 0.3},      {80.01, 119.8, 400, 3, 0.2, 0.5},
      {0.3, 60.01, 2, 300, 0.3, 0.2},      {159.7, 60.01, -1, 300, 0.4, 0.4},
      {80.01, 60.03, 400, 300, -0.3, 0.9}, {80.01, 60.03, 400, 100, 0.5, -0.5},
      {10.01, 10.03, 60, 60, 0.3, 0.3},    {150.01, 110.03, 60, -60, 0.35, 0.2},
      {80.01, -5, 300, 30, 0.3, 0.4},
  };
  for (const auto& c : cases) {
    expect_same_contact(grid, edge_in_cells(t.spec, c[0], c[1], c[2], c[3], c[4], c[5]), "border");
  }
}

/// Heights after the same sweep by the fast cut and the brute force, and
/// their bookkeeping.
void expect_same_cut(const Terrain& t, const Segment& from, const Segment& to, const char* what) {
  for (Representation rep : kBoth) {
    HeightGrid fast(t.spec, t.heights), slow(t.spec, t.heights);
    CutResult a = cut_sweep(fast, rep, from, to);
    CutResult b = cut_sweep_brute_force(slow, rep, from, to);
    double area = t.spec.size_x_m * t.spec.size_z_m;
    EXPECT_NEAR(a.removed_volume_m3, b.removed_volume_m3, 1e-9 * area + 1e-7 * b.removed_volume_m3)
        << to_string(rep) << " " << what;
    int differing = 0;
    for (std::int64_t i = 0; i < t.spec.sample_count(); ++i) {
      differing += std::abs(fast.heights()[i] - slow.heights()[i]) > 1e-6;
    }
    EXPECT_EQ(differing, 0) << to_string(rep) << " " << what;
    if (!b.changed.empty()) {
      Rect both = a.changed;
      both.include(b.changed);
      EXPECT_EQ(both, a.changed) << to_string(rep) << " " << what;
    }
    // The changed rectangle is tight: its border rows and columns hold changes.
    if (!a.changed.empty()) {
      auto changed = [&](int c, int r) { return fast.height(c, r) != fast.initial()[fast.index(c, r)]; };
      bool top = false, bottom = false, left = false, right = false;
      for (int c = a.changed.c0; c < a.changed.c1; ++c) {
        bottom |= changed(c, a.changed.r0);
        top |= changed(c, a.changed.r1 - 1);
      }
      for (int r = a.changed.r0; r < a.changed.r1; ++r) {
        left |= changed(a.changed.c0, r);
        right |= changed(a.changed.c1 - 1, r);
      }
      EXPECT_TRUE(top && bottom && left && right) << to_string(rep) << " " << what;
    }
  }
}

// Full-width and oblique sweeps, small and large moves, rotations, a plunge
// straight down and a blade at rest, against the brute force.
TEST(PerfTraversal, SweepsEqualBruteForce) {
  Terrain t = make_terrain(150, 110, 13);
  const GridSpec& s = t.spec;
  auto at = [&](double cu, double cv, double du, double dv, double y0, double y1) {
    return edge_in_cells(s, cu, cv, du, dv, y0, y1);
  };
  auto shifted = [](Segment e, Vec3 d) { return Segment{e.a + d, e.b + d}; };
  double cz = s.cell_z_m(), cx = s.cell_x_m();
  // Generic positions: no sample exactly on an edge of the swept region
  // (ties are brute_force_test.cpp's).
  Segment level = at(75.3123, 40.2371, 170, 0, 0.3, 0.3);  // wider than the terrain
  Segment tilted = at(75.3123, 40.2371, 120, 0, 0.1, 0.6);
  Segment yawed = at(75.3123, 55.1371, 140, 80.0173, 0.35, 0.35);
  Segment steep = at(70.7123, 55.1371, 30.0119, 100, 0.2, 0.45);
  expect_same_cut(t, level, shifted(level, {0, 0, 0.6 * cz}), "level, 0.6 cell");
  expect_same_cut(t, level, shifted(level, {0, -0.05, 3.7 * cz}), "level, 3.7 cells, descending");
  expect_same_cut(t, tilted, shifted(tilted, {0, 0, 0.6 * cz}), "tilted");
  expect_same_cut(t, yawed, shifted(yawed, {0, 0, 0.6 * cz}), "yawed, along z");
  expect_same_cut(t, yawed, shifted(yawed, {0.4 * cx, 0.0, -0.9 * cz}), "yawed, sideways");
  expect_same_cut(t, steep, shifted(steep, {0.7 * cx, 0.0, 0.0}), "steep, along x");
  expect_same_cut(t, level, shifted(level, {0, -0.4, 0}), "plunge");
  expect_same_cut(t, yawed, shifted(yawed, {0, -0.3, 0}), "yawed plunge");
  expect_same_cut(t, tilted, tilted, "at rest");
  // A rotation about the vertical through the centre (the quad twists).
  Vec3 centre{s.origin_m.x + 75.0123 * cx, s.origin_m.y + 0.3, s.origin_m.z + 55.0371 * cz};
  auto rotated = [&](double deg) {
    double a = deg * std::numbers::pi / 180.0;
    Vec3 half{0.45 * std::cos(a), 0.0, -0.45 * std::sin(a)};
    return Segment{centre - half, centre + half};
  };
  expect_same_cut(t, rotated(0.0), rotated(2.0), "rotation 2 degrees");
  expect_same_cut(t, rotated(10.0), rotated(25.0), "rotation 15 degrees");
  expect_same_cut(t, rotated(80.0), rotated(100.0), "rotation through the vertical axis");
}

// A blade crossing the rows at the benchmark's yaws (a transverse one
// through a rotation, as a quaternion leaves cos(pi/2) ~ 6e-17 in it),
// moving along its normal a fraction of a cell per step: the rows of each
// sweep are the parallelogram walks' straight bands, and after the first
// step most of a row's cells are already at or below the next target (the
// walks lower without branching on that), so the run is compared with the
// brute force step by step.
TEST(PerfTraversal, BladeRunsAcrossTheRowsEqualBruteForce) {
  Terrain t = make_terrain(150, 110, 29);
  const GridSpec& s = t.spec;
  const double cx = s.cell_x_m(), cz = s.cell_z_m();
  const Vec3 centre{s.origin_m.x + 70.3123 * cx, s.origin_m.y + 0.32, s.origin_m.z + 50.2371 * cz};
  for (double yaw_deg : {10.0, 30.0, 45.0, 60.0, 90.0}) {
    const double a = yaw_deg * std::numbers::pi / 180.0;
    const Vec3 along{std::cos(a), 0.0, std::sin(a)};  // the blade's edge
    const Vec3 normal{-std::sin(a), -0.002, std::cos(a)};  // its travel, slightly down
    const Vec3 half = along * (0.3 * s.size_z_m);
    for (Representation rep : kBoth) {
      HeightGrid fast(s, t.heights), slow(s, t.heights);
      Segment from{centre - half, centre + half};
      for (int step = 0; step < 12; ++step) {
        const double move = (0.37 + 0.11 * (step % 3)) * std::min(cx, cz);
        const Segment to{from.a + normal * move, from.b + normal * move};
        const CutResult got = cut_sweep(fast, rep, from, to);
        const CutResult want = cut_sweep_brute_force(slow, rep, from, to);
        const std::string what = std::string(to_string(rep)) + " yaw " + std::to_string(int(yaw_deg)) + " step " +
                                 std::to_string(step);
        EXPECT_NEAR(got.removed_volume_m3, want.removed_volume_m3,
                    1e-9 * s.size_x_m * s.size_z_m + 1e-7 * want.removed_volume_m3)
            << what;
        int differing = 0;
        for (std::int64_t i = 0; i < s.sample_count(); ++i) {
          differing += std::abs(fast.heights()[i] - slow.heights()[i]) > 1e-6;
        }
        EXPECT_EQ(differing, 0) << what;
        if (!want.changed.empty()) {
          Rect both = got.changed;
          both.include(want.changed);
          EXPECT_EQ(both, got.changed) << what;
        }
        from = to;
      }
    }
  }
}

}  // namespace
}  // namespace terracut
