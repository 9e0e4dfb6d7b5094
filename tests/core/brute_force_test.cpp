// The boundary rules, where the fast paths and the brute-force oracle must
// decide alike: edges lying on cell walls and node lines (contact), in both
// representations.
//
// The grid is 32 x 16 cells of exactly 1/8 m, so positions given in cell
// units are exact in binary floating point and a tie is a real tie.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "terracut/core/brute_force.hpp"
#include "terracut/core/contact.hpp"
#include "terracut/core/cut.hpp"

namespace terracut {
namespace {

constexpr Representation kBoth[] = {Representation::kColumns, Representation::kSurface};

GridSpec tie_spec() {
  GridSpec s;
  s.cols = 32;
  s.rows = 16;
  s.size_x_m = 4.0;  // cells of 0.125 m: exact
  s.size_z_m = 2.0;
  s.origin_m = {-2.0, 0.5, -1.0};
  s.full_scale_m = 1.0;
  return s;
}

/// Heights k/64 (exact), different from cell to cell, so that counting the
/// wrong column or both shows.
std::vector<float> tie_heights(const GridSpec& s) {
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> level(8, 56);
  std::vector<float> h(std::size_t(s.sample_count()));
  for (float& v : h) v = float(level(rng)) / 64.0f;
  return h;
}

/// The world point at (u, v) in cell units (cell (c, r) covers u in [c, c+1),
/// v in [r, r+1); sample (c, r) sits at (c + 0.5, r + 0.5)), y above the ground.
Vec3 at(const GridSpec& s, double u, double v, double y) {
  return {s.origin_m.x + u * s.cell_x_m(), s.origin_m.y + y, s.origin_m.z + v * s.cell_z_m()};
}

Segment edge(const GridSpec& s, double u0, double v0, double u1, double v1, double y0, double y1) {
  return {at(s, u0, v0, y0), at(s, u1, v1, y1)};
}

std::string name_of(Representation rep, const std::string& what) { return std::string(to_string(rep)) + ", " + what; }

// ---------------------------------------------------------------------------
// Contact

/// The fast path and the oracle agree, and the contact is no longer than the
/// edge (a tie counted twice would exceed it).
ContactResult expect_same_contact(const HeightGrid& grid, Representation rep, const Segment& e, const std::string& what) {
  const ContactResult fast = measure_contact(grid, rep, e);
  const ContactResult slow = measure_contact_brute_force(grid, rep, e);
  EXPECT_NEAR(fast.length_m, slow.length_m, 1e-12) << name_of(rep, what);
  EXPECT_NEAR(fast.section_area_m2, slow.section_area_m2, 1e-12) << name_of(rep, what);
  EXPECT_NEAR(fast.max_depth_m, slow.max_depth_m, 1e-12) << name_of(rep, what);
  EXPECT_LE(slow.length_m, length(e.b - e.a) + 1e-12) << name_of(rep, what);
  return slow;
}

// The tie grid and its heights, for the contact tests.
class TieContact : public ::testing::Test {
 protected:
  const GridSpec s = tie_spec();
  const HeightGrid grid{s, tie_heights(s)};
  static constexpr double hair = 1e-9;  // off a line, but not past the next one
};

// An edge lying exactly on a wall between two rows (or columns) of columns
// belongs to the cell on the wall's + side (half-open cells), at the grid's
// far edge to the last cell: counted once, with that cell's top. The
// review's case: the oracle summed both rows (2 m of contact on a 2 m
// edge's 1 m over the terrain).
TEST_F(TieContact, ContactOnCellWallsIsCountedOnce) {
  const struct {
    double u0, v0, u1, v1;
    double nudge_u, nudge_v;  // into the cell the edge belongs to
    const char* what;
  } cases[] = {
      {3.3, 5, 20.7, 5, 0, hair, "along the row wall v = 5"},
      {3.3, 0, 20.7, 0, 0, hair, "along the near edge v = 0"},
      {3.3, 16, 20.7, 16, 0, -hair, "along the far edge v = 16"},
      {7, 1.3, 7, 14.6, hair, 0, "along the column wall u = 7"},
      {32, 1.3, 32, 14.6, -hair, 0, "along the far edge u = 32"},
      {0, 1.3, 0, 14.6, hair, 0, "along the near edge u = 0"},
      {-2, 5, 34, 5, 0, hair, "across the whole terrain on v = 5"},
      {20.7, 9, 3.3, 9, 0, hair, "backwards along v = 9"},
  };
  for (const auto& c : cases) {
    for (const auto& [y0, y1] : {std::pair{0.3, 0.3}, std::pair{0.1, 0.8}}) {
      const Segment e = edge(s, c.u0, c.v0, c.u1, c.v1, y0, y1);
      const ContactResult on = expect_same_contact(grid, Representation::kColumns, e, c.what);
      // The same as the edge moved a hair into its own cell.
      const Segment in = edge(s, c.u0 + c.nudge_u, c.v0 + c.nudge_v, c.u1 + c.nudge_u, c.v1 + c.nudge_v, y0, y1);
      const ContactResult inside = measure_contact_brute_force(grid, Representation::kColumns, in);
      EXPECT_NEAR(on.length_m, inside.length_m, 1e-9) << c.what;
      EXPECT_NEAR(on.section_area_m2, inside.section_area_m2, 1e-9) << c.what;
      EXPECT_GT(on.length_m, 0.0) << c.what;
    }
  }
}

// The surface is continuous, so an edge on a node line or a square's
// diagonal has the contact of the edge moved off it by a hair; the oracle
// used to count it in both squares (or both triangles).
TEST_F(TieContact, SurfaceContactOnNodeLinesIsCountedOnce) {
  const struct {
    double u0, v0, u1, v1;
    const char* what;
  } cases[] = {
      {3.3, 5.5, 20.7, 5.5, "along node row 5"},       {3.3, 0.5, 20.7, 0.5, "along node row 0"},
      {3.3, 15.5, 20.7, 15.5, "along the last node row"}, {3.3, 16, 20.7, 16, "along the far edge"},
      {3.3, 0, 20.7, 0, "along the near edge"},        {7.5, 1.3, 7.5, 14.6, "along node column 7"},
      {4.5, 10.5, 12.5, 2.5, "along square diagonals"}, {4.5, 2.5, 12.5, 10.5, "(1, 1) through nodes"},
      {4, 2, 12, 10, "(1, 1) through cell corners"},    {-2, 5.5, 34, 5.5, "across the terrain on node row 5"},
  };
  for (const auto& c : cases) {
    for (const auto& [y0, y1] : {std::pair{0.3, 0.3}, std::pair{0.1, 0.8}}) {
      const Segment e = edge(s, c.u0, c.v0, c.u1, c.v1, y0, y1);
      const ContactResult on = expect_same_contact(grid, Representation::kSurface, e, c.what);
      // Off the line, perpendicular to it, towards the inside.
      const double du = c.u1 - c.u0, dv = c.v1 - c.v0, norm = std::hypot(du, dv);
      double nu = -dv / norm * hair, nv = du / norm * hair;
      if (c.v0 == 16 && c.v1 == 16) nv = -std::abs(nv);
      const Segment off = edge(s, c.u0 + nu, c.v0 + nv, c.u1 + nu, c.v1 + nv, y0, y1);
      const ContactResult near = measure_contact_brute_force(grid, Representation::kSurface, off);
      EXPECT_NEAR(on.length_m, near.length_m, 1e-6) << c.what;
      EXPECT_NEAR(on.section_area_m2, near.section_area_m2, 1e-6) << c.what;
    }
  }
}

// Edges between lattice points (many along walls and node lines, many
// ending exactly on them): the fast path and the oracle agree.
TEST(BruteForceTies, LatticeContactEqualsOracle) {
  const GridSpec s = tie_spec();
  const HeightGrid grid(s, tie_heights(s));
  std::mt19937 rng(21);
  for (int den : {1, 2, 4}) {
    std::uniform_int_distribution<int> u(-2 * den, 34 * den), v(-2 * den, 18 * den), y(1, 12);
    for (int k = 0; k < 1500; ++k) {
      double u0 = double(u(rng)) / den, v0 = double(v(rng)) / den, u1 = double(u(rng)) / den, v1 = double(v(rng)) / den;
      if (k % 3 == 0) v1 = v0;  // along a row line or node line
      if (k % 3 == 1) u1 = u0;
      const Segment e = edge(s, u0, v0, u1, v1, y(rng) / 16.0, y(rng) / 16.0);
      for (Representation rep : kBoth) expect_same_contact(grid, rep, e, "lattice edge " + std::to_string(k));
    }
  }
}

}  // namespace
}  // namespace terracut
