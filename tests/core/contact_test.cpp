// Contact length against exact geometry, for both representations.
#include "terracut/core/contact.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "terracut/core/brute_force.hpp"
#include "test_terrains.hpp"

namespace terracut {
namespace {

constexpr Representation kBoth[] = {Representation::kColumns, Representation::kSurface};

// Depths below 2^-20 of the full scale count as no material (see contact.hpp),
// which moves the end of a contact along a slope of dy/ds by eps / slope.
double depth_epsilon(const GridSpec& s) { return std::ldexp(s.full_scale_m, -20); }

// A full slab of material: a horizontal line inside it is in contact over its
// whole length within the terrain, in both representations, exactly.
TEST(Contact, HorizontalLineThroughFullSlab) {
  GridSpec s = test::square_spec(20, 20);
  HeightGrid grid(s, std::vector<float>(400, 0.5f));
  for (Representation rep : kBoth) {
    // Line from x = -0.3 to 1.3 at z = 0.37: 1 m of it lies over the terrain.
    ContactResult c = measure_contact(grid, rep, {{-0.3, 0.25, 0.37}, {1.3, 0.25, 0.37}});
    EXPECT_NEAR(c.length_m, 1.0, 1e-12) << to_string(rep);
    EXPECT_NEAR(c.max_depth_m, 0.25, 1e-6) << to_string(rep);
    EXPECT_NEAR(c.section_area_m2, 0.25, 1e-6) << to_string(rep);
    // Above the material, or below the ground: no contact.
    EXPECT_EQ(measure_contact(grid, rep, {{-0.3, 0.6, 0.37}, {1.3, 0.6, 0.37}}).length_m, 0.0);
    EXPECT_EQ(measure_contact(grid, rep, {{-0.3, -0.1, 0.37}, {1.3, -0.1, 0.37}}).length_m, 0.0);
  }
}

// A block of columns aligned with cells: the columns representation is exact;
// the surface ramps over one cell at each side, so at half height its section
// crosses exactly at the block's edge, and at any height it is within a cell.
TEST(Contact, HorizontalLineThroughBlock) {
  GridSpec s = test::square_spec(40, 40);
  HeightGrid grid(s, test::block(s, 10, 30, 5, 35, 0.4f));  // x in [0.25, 0.75]
  Segment edge{{-0.1, 0.2, 0.5}, {1.1, 0.2, 0.5}};
  // The surface ramp rises 0.4 m over a cell: the epsilon moves each end by eps * cell / 0.4.
  double ramp_tol = 2.0 * depth_epsilon(s) * s.cell_x_m() / 0.4 + 1e-12;
  EXPECT_NEAR(measure_contact(grid, Representation::kColumns, edge).length_m, 0.5, 1e-12);
  EXPECT_NEAR(measure_contact(grid, Representation::kSurface, edge).length_m, 0.5, ramp_tol);
  for (double y : {0.05, 0.1, 0.3, 0.39}) {
    Segment e{{-0.1, y, 0.5}, {1.1, y, 0.5}};
    EXPECT_NEAR(measure_contact(grid, Representation::kColumns, e).length_m, 0.5, 1e-12);
    EXPECT_NEAR(measure_contact(grid, Representation::kSurface, e).length_m, 0.5, s.cell_x_m() + 1e-12);
  }
}

// A line tilted in the vertical plane through a block: y = x - 0.1 from
// x = 0 to 1, block x in [0.2, 0.8], height 0.5: inside where 0.2 <= x <= 0.6.
TEST(Contact, TiltedLineThroughBlockIsExactForColumns) {
  GridSpec s = test::square_spec(50, 50);
  HeightGrid grid(s, test::block(s, 10, 40, 0, 50, 0.5f));
  Segment edge{{0.0, -0.1, 0.43}, {1.0, 0.9, 0.43}};
  double exact = 0.4 * std::sqrt(2.0);
  // The line leaves through the top (slope 1): the rounding allowance at the
  // top (columns count a blade touching the top) moves that end by at most
  // 2 eps along x, so the length by at most 2 eps * sqrt(2).
  EXPECT_NEAR(measure_contact(grid, Representation::kColumns, edge).length_m, exact,
              2.02 * depth_epsilon(s) * std::sqrt(2.0));
  // The surface's ramps shift each end by less than a cell along the line.
  EXPECT_NEAR(measure_contact(grid, Representation::kSurface, edge).length_m, exact,
              2.0 * s.cell_x_m() * std::sqrt(2.0));
}

// A horizontal line running diagonally across cells (through cell corners):
// block x, z in [0.2, 0.8]; inside for x in [0.2, 0.8], length 0.6 * sqrt(2).
// Exact for columns; the surface's corner ramps move each end by less than a
// cell diagonal.
TEST(Contact, DiagonalLineThroughCellCorners) {
  GridSpec s = test::square_spec(50, 50);
  HeightGrid grid(s, test::block(s, 10, 40, 10, 40, 0.5f));
  Segment edge{{0.0, 0.25, 0.0}, {1.0, 0.25, 1.0}};
  double exact = 0.6 * std::sqrt(2.0);
  EXPECT_NEAR(measure_contact(grid, Representation::kColumns, edge).length_m, exact, 1e-12);
  double cell_diagonal = s.cell_x_m() * std::sqrt(2.0);
  EXPECT_NEAR(measure_contact(grid, Representation::kSurface, edge).length_m, exact, cell_diagonal);
  // Reversed direction gives the same.
  Segment back{edge.b, edge.a};
  EXPECT_NEAR(measure_contact(grid, Representation::kColumns, back).length_m, exact, 1e-12);
  EXPECT_NEAR(measure_contact(grid, Representation::kSurface, back).length_m,
              measure_contact(grid, Representation::kSurface, edge).length_m, 1e-12);
}

// A vertical edge inside a column measures the material height it spans.
TEST(Contact, VerticalEdge) {
  GridSpec s = test::square_spec(10, 10);
  HeightGrid grid(s, std::vector<float>(100, 0.3f));
  for (Representation rep : kBoth) {
    ContactResult c = measure_contact(grid, rep, {{0.55, -0.2, 0.55}, {0.55, 0.8, 0.55}});
    EXPECT_NEAR(c.length_m, 0.3, 1e-6) << to_string(rep);
  }
}

// Chords of the dome: the error against the exact circle chord shrinks as the
// resolution grows, for both representations.
TEST(Contact, DomeChordsConvergeWithResolution) {
  const double radius = 0.4, height = 0.2, y = 0.1;
  for (Representation rep : kBoth) {
    double previous_rms = INFINITY;
    for (int n : {25, 50, 100, 200, 400}) {
      GridSpec s = test::square_spec(n, n);
      HeightGrid grid(s, test::dome(s, 0.5, 0.5, radius, height));
      double sum_sq = 0.0;
      int count = 0;
      for (int k = 0; k <= 200; ++k) {
        double z = 0.1 + 0.8 * k / 200.0;
        double exact = test::dome_chord(y, z, 0.5, radius, height);
        double got = measure_contact(grid, rep, {{-0.1, y, z}, {1.1, y, z}}).length_m;
        sum_sq += (got - exact) * (got - exact);
        ++count;
      }
      double rms = std::sqrt(sum_sq / count);
      // Each chord end can be off by about a cell (the samples are a cell
      // apart), plus the section's sampling in z near its tangent points.
      EXPECT_LT(rms, 2.0 * s.cell_x_m()) << to_string(rep) << " n=" << n;
      // Doubling the resolution must reduce the error clearly.
      EXPECT_LT(rms, 0.8 * previous_rms) << to_string(rep) << " n=" << n;
      previous_rms = rms;
    }
  }
}

// The traversal visits only cells under the edge.
TEST(Contact, VisitsOnlyCellsUnderTheEdge) {
  GridSpec s = test::square_spec(1000, 1000);
  HeightGrid grid(s, std::vector<float>(size_t(s.sample_count()), 0.5f));
  for (Representation rep : kBoth) {
    ContactResult c = measure_contact(grid, rep, {{0.1, 0.25, 0.1}, {0.2, 0.25, 0.15}});
    EXPECT_LE(c.cells_visited, 100 + 50 + 4) << to_string(rep);
    EXPECT_GE(c.cells_visited, 100) << to_string(rep);
  }
}

// Traversal equals the brute-force algorithm on random terrains and edges.
TEST(Contact, TraversalEqualsBruteForceOnRandomCases) {
  std::mt19937 rng(20261122);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 300; ++trial) {
    int cols = 1 + int(unit(rng) * 30), rows = 1 + int(unit(rng) * 30);
    GridSpec s;
    s.cols = cols;
    s.rows = rows;
    s.size_x_m = 0.5 + unit(rng);
    s.size_z_m = 0.5 + unit(rng);
    s.origin_m = {unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5};
    s.full_scale_m = 1.0;
    std::vector<float> h(size_t(s.sample_count()));
    for (float& v : h) v = float(unit(rng));
    HeightGrid grid(s, h);
    for (int k = 0; k < 10; ++k) {
      auto point = [&] {
        return Vec3{s.origin_m.x + (unit(rng) * 1.6 - 0.3) * s.size_x_m,
                    s.origin_m.y + unit(rng) * 1.2 - 0.1,
                    s.origin_m.z + (unit(rng) * 1.6 - 0.3) * s.size_z_m};
      };
      Segment edge{point(), point()};
      double scale = length(edge.b - edge.a);
      for (Representation rep : kBoth) {
        ContactResult fast = measure_contact(grid, rep, edge);
        ContactResult slow = measure_contact_brute_force(grid, rep, edge);
        ASSERT_NEAR(fast.length_m, slow.length_m, 1e-9 * (1.0 + scale))
            << to_string(rep) << " trial " << trial << " edge " << k;
        ASSERT_NEAR(fast.section_area_m2, slow.section_area_m2, 1e-9 * (1.0 + scale));
        ASSERT_NEAR(fast.max_depth_m, slow.max_depth_m, 1e-9);
      }
    }
  }
}

TEST(Contact, NonFiniteEdgeHasNoContact) {
  GridSpec s = test::square_spec(4, 4);
  HeightGrid grid(s, std::vector<float>(16, 0.5f));
  for (Representation rep : kBoth) {
    EXPECT_EQ(measure_contact(grid, rep, {{NAN, 0.2, 0.5}, {1, 0.2, 0.5}}).length_m, 0.0);
    EXPECT_EQ(measure_contact(grid, rep, {{0, 0.2, 0.5}, {INFINITY, 0.2, 0.5}}).length_m, 0.0);
  }
}

TEST(Contact, RepresentationNames) {
  EXPECT_EQ(parse_enum<Representation>("columns"), Representation::kColumns);
  EXPECT_EQ(parse_enum<Representation>("surface"), Representation::kSurface);
  EXPECT_FALSE(parse_enum<Representation>("voxels").has_value());
  EXPECT_EQ(to_string(Representation::kSurface), "surface");
}

}  // namespace
}  // namespace terracut
