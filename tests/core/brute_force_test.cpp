// The boundary rules (docs/model.md, "Boundaries"), where the fast paths and
// the brute-force oracle must decide alike: edges lying on cell walls and
// node lines (contact), blades at rest with their ends on samples, sweeps
// whose edges pass through cell corners and along cell walls (cut), in both
// representations.
//
// The grid is 32 x 16 cells of exactly 1/8 m, so positions given in cell
// units are exact in binary floating point and a tie is a real tie. The
// oracle's closed regions are checked against an exact integer reference
// on a lattice of points 1/den of a cell apart; the fast paths against the
// oracle wherever every edge of the swept triangles has a dx/dz that binary
// floating point represents (along a row or column, diagonal, 2:1, 3:4, ...;
// see docs/model.md for the general case).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "terracut/core/brute_force.hpp"
#include "terracut/core/contact.hpp"
#include "terracut/core/cut.hpp"
#include "../support/lattice.hpp"

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

// ---------------------------------------------------------------------------
// Cut: the closed rule, against an exact integer reference.

using test::LatticePoint;
using test::SweepTriangles;
using test::holds;
using test::on_crossing_line;
using test::representable_slope;
using test::touches;

/// Bow-ties whose fast cut expect_closed_cut checked against the closed rule.
int bow_ties_fast_checked = 0;

/// A sweep between lattice points (units of 1/den cell), heights in metres.
struct LatticeSweep {
  LatticePoint from_a, from_b, to_a, to_b;
  double y_a, y_b;  // at the blade's two ends, the same at both poses
};

/// Cuts the sweep with the fast path and the oracle on a terrain at 0.9 m
/// (above every blade height used, so a sample is lowered exactly when the
/// region covers it), checks the oracle's lowered set against the exact
/// reference and, when check_fast, the fast path against the oracle. Returns
/// whether the fast path was checked.
bool expect_closed_cut(const LatticeSweep& w, int den, bool check_fast, const std::string& what) {
  const GridSpec s = tie_spec();
  auto world = [&](LatticePoint p, double y) { return at(s, double(p.x) / den, double(p.z) / den, y); };
  const Segment from{world(w.from_a, w.y_a), world(w.from_b, w.y_b)};
  const Segment to{world(w.to_a, w.y_a), world(w.to_b, w.y_b)};
  const SweepTriangles sweep = test::sweep_triangles(w.from_a, w.from_b, w.to_a, w.to_b);
  const std::int64_t k = std::int64_t(den) * sweep.scale;  // lattice units a cell
  // The lattice doubled, so that sample centres (half cells) are points of it.
  const SweepTriangles doubled = test::doubled(sweep);
  for (Representation rep : kBoth) {
    const std::vector<float> initial(std::size_t(s.sample_count()), 0.9f);
    HeightGrid fast(s, initial), slow(s, initial);
    const CutResult a = cut_sweep(fast, rep, from, to);
    const CutResult b = cut_sweep_brute_force(slow, rep, from, to);
    int wrong_oracle = 0, wrong_fast = 0, wrong_fast_rule = 0;
    // A bow-tie's fast cut against the closed rule itself (the oracle's
    // comparison needs representable slopes, and the crossing's are not),
    // where its two sides through no crossing have representable slopes.
    const bool fast_rule = sweep.bow_tie && representable_slope(w.from_a, w.to_a) && representable_slope(w.from_b, w.to_b);
    for (int r = 0; r < s.rows; ++r) {
      for (int c = 0; c < s.cols; ++c) {
        bool covered = false;
        for (const auto& t : doubled.tri) {
          if (rep == Representation::kColumns) {
            covered |= touches(t, 2 * c * k, 2 * (c + 1) * k, 2 * r * k, 2 * (r + 1) * k);
          } else {
            covered |= holds(t, {(2 * c + 1) * k, (2 * r + 1) * k});
          }
        }
        // A bow-tie's crossing is rounded: on a line through it, either
        // side is right.
        const bool tie = rep == Representation::kColumns
                             ? on_crossing_line(doubled, 2 * c * k, 2 * (c + 1) * k, 2 * r * k, 2 * (r + 1) * k)
                             : on_crossing_line(doubled, {(2 * c + 1) * k, (2 * r + 1) * k});
        const float h_slow = slow.height(c, r), h_fast = fast.height(c, r);
        wrong_oracle += !tie && (h_slow < 0.9f) != covered;
        if (fast_rule) wrong_fast_rule += !tie && (h_fast < 0.9f) != covered;
        if (check_fast && !tie) wrong_fast += !(std::abs(h_fast - h_slow) <= 1e-6f);
      }
    }
    EXPECT_EQ(wrong_oracle, 0) << name_of(rep, what);
    EXPECT_EQ(wrong_fast_rule, 0) << name_of(rep, what);
    bow_ties_fast_checked += fast_rule;
    if (check_fast) {
      EXPECT_EQ(wrong_fast, 0) << name_of(rep, what);
      EXPECT_NEAR(a.removed_volume_m3, b.removed_volume_m3, 1e-9 + 1e-7 * b.removed_volume_m3) << name_of(rep, what);
      if (!b.changed.empty()) {
        EXPECT_EQ(a.changed, b.changed) << name_of(rep, what);
      }
    }
  }
  return check_fast;
}

// The ties the review found and their kin, each with both representations:
// a blade at rest whose end is exactly on a sample (the fast path lowered
// the sample, the oracle did not), at rest through samples and along a row
// of them, at rest on a cell wall (both rows of columns are lowered), sweeps
// whose edges pass through cell corners (a column touched only at its
// corner is lowered), plunges onto samples. Coordinates in cells (den 2:
// half cells, so sample centres are lattice points).
TEST(BruteForceTies, NamedTiesFollowTheClosedRule) {
  auto p = [](double u, double v) { return LatticePoint{std::int64_t(2 * u), std::int64_t(2 * v)}; };
  const struct {
    LatticePoint fa, fb, ta, tb;
    double ya, yb;
    const char* what;
  } cases[] = {
      {p(3.5, 5.5), p(9, 8), p(3.5, 5.5), p(9, 8), 0.2, 0.2, "at rest, an end on sample (3, 5)"},
      {p(3.5, 5.5), p(9.5, 11.5), p(3.5, 5.5), p(9.5, 11.5), 0.2, 0.5, "at rest, diagonally through samples"},
      {p(3, 5.5), p(20.5, 5.5), p(3, 5.5), p(20.5, 5.5), 0.2, 0.2, "at rest along sample row 5"},
      {p(3, 5), p(20.5, 5), p(3, 5), p(20.5, 5), 0.2, 0.3, "at rest on the row wall v = 5"},
      {p(4, 2), p(12, 10), p(4, 2), p(12, 10), 0.2, 0.2, "at rest through cell corners"},
      {p(4, 2), p(20, 10), p(4, 2), p(20, 10), 0.2, 0.2, "at rest, 2:1 through cell corners"},
      {p(4, 2), p(9, 7.5), p(4, 2), p(9, 7.5), 0.2, 0.2, "at rest, an end on a cell corner"},
      {p(3.5, 5.5), p(20.5, 5.5), p(3.5, 8.5), p(20.5, 8.5), 0.2, 0.2, "3 rows, ends on samples"},
      {p(3, 5), p(20.5, 5), p(3, 6), p(20.5, 6), 0.2, 0.2, "from one row wall to the next"},
      {p(4, 2), p(12, 10), p(6, 2), p(14, 10), 0.2, 0.2, "along x, edges through cell corners"},
      {p(4.5, 2.5), p(12.5, 10.5), p(6.5, 2.5), p(14.5, 10.5), 0.2, 0.2, "along x, edges through samples"},
      {p(4, 2), p(12, 10), p(5, 1), p(13, 9), 0.2, 0.2, "diagonal step, corners"},
      {p(4, 2), p(8, 6), p(4, 2), p(8.5, 3), 0.2, 0.2, "rotation about a corner, touching corners"},
      {p(4, 2), p(12, 2), p(4, 2), p(12, 6), 0.2, 0.2, "rotation about a corner on a wall"},
      {p(3.5, 5.5), p(9.5, 5.5), p(3.5, 5.5), p(9.5, 5.5), 0.1, 0.1, "at rest on samples, low"},
      {p(0, 0), p(32, 16), p(0, 0), p(32, 16), 0.2, 0.2, "at rest corner to corner of the terrain"},
      {p(0, 16), p(32, 16), p(0, 15), p(32, 15), 0.2, 0.2, "along the far edge"},
  };
  for (const auto& c : cases) expect_closed_cut({c.fa, c.fb, c.ta, c.tb, c.ya, c.yb}, 2, true, c.what);
  // A plunge straight down onto a row of samples: the region stands on edge.
  const GridSpec s = tie_spec();
  for (Representation rep : kBoth) {
    HeightGrid fast(s, tie_heights(s)), slow(s, tie_heights(s));
    const Segment high = edge(s, 3.5, 5.5, 9.5, 5.5, 0.6, 0.6), low = edge(s, 3.5, 5.5, 9.5, 5.5, 0.1, 0.1);
    cut_sweep(fast, rep, high, low);
    cut_sweep_brute_force(slow, rep, high, low);
    for (int c = 0; c < s.cols; ++c) {
      for (int r = 0; r < s.rows; ++r) {
        EXPECT_EQ(fast.height(c, r), slow.height(c, r)) << name_of(rep, "plunge") << " c=" << c << " r=" << r;
      }
    }
    if (rep == Representation::kSurface) {
      for (int c = 3; c <= 9; ++c) EXPECT_NEAR(slow.height(c, 5), 0.1, 1e-6) << "plunge onto sample " << c;
    }
  }
}

// Random sweeps between lattice points (general, at rest, translations),
// dense in ties: the oracle's lowered set is exactly the closed rule's, and
// the fast path equals the oracle wherever the swept edges' slopes are
// representable.
TEST(BruteForceTies, LatticeSweepsFollowTheClosedRule) {
  std::mt19937 rng(17);
  int fast_checked = 0, bow_ties = 0;
  for (int den : {1, 2, 4}) {
    std::uniform_int_distribution<int> u(2 * den, 30 * den), v(1 * den, 15 * den), y(1, 12);
    for (int mode = 0; mode < 3; ++mode) {
      for (int k = 0; k < 400; ++k) {
        LatticeSweep w;
        w.from_a = {u(rng), v(rng)};
        w.from_b = {u(rng), v(rng)};
        if (mode == 0) {
          w.to_a = {u(rng), v(rng)};
          w.to_b = {u(rng), v(rng)};
        } else if (mode == 1) {
          w.to_a = w.from_a;
          w.to_b = w.from_b;
        } else {
          const LatticePoint d{u(rng) / 4, v(rng) / 4};
          w.to_a = {w.from_a.x + d.x, w.from_a.z + d.z};
          w.to_b = {w.from_b.x + d.x, w.from_b.z + d.z};
        }
        w.y_a = y(rng) / 16.0;
        w.y_b = y(rng) / 16.0;
        // A bow-tie (the edges crossing: the blade turned about a point of
        // its edge) has its crossing rounded, so the fast path and the
        // oracle are compared on the diagonal splits only.
        const SweepTriangles sweep = test::sweep_triangles(w.from_a, w.from_b, w.to_a, w.to_b);
        bool representable = !sweep.bow_tie;
        for (const auto& t : sweep.tri)
          for (int e = 0; e < 3; ++e) representable = representable && representable_slope(t[e], t[(e + 1) % 3]);
        bow_ties += sweep.bow_tie;
        std::ostringstream what;
        what << "den " << den << " mode " << mode << " sweep " << k << ": ";
        for (const LatticePoint& p : {w.from_a, w.from_b, w.to_a, w.to_b}) {
          what << "(" << double(p.x) / den << ", " << double(p.z) / den << ") ";
        }
        what << "y " << w.y_a << " to " << w.y_b;
        fast_checked += expect_closed_cut(w, den, representable, what.str());
      }
    }
  }
  EXPECT_GT(fast_checked, 500);  // the fast path was compared on many of them
  EXPECT_GT(bow_ties, 100);      // and the oracle checked against the lobes of many bow-ties,
  EXPECT_GT(bow_ties_fast_checked, 20);  // the fast path too on some
}

}  // namespace
}  // namespace terracut
