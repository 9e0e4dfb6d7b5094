// Exact integer geometry on a lattice of points 1/den of a cell apart: the
// reference the cut's closed rule (docs/model.md, "Boundaries") is checked
// against, by the tie tests (tests/core/brute_force_test.cpp) and the
// differential fuzz target (tests/fuzz/fuzz_differential.cpp).
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <numeric>

namespace terracut::test {

/// A point of the lattice in units of 1/den of a cell.
struct LatticePoint {
  std::int64_t x, z;
};

inline std::int64_t orient(LatticePoint a, LatticePoint b, LatticePoint p) {
  return (b.x - a.x) * (p.z - a.z) - (b.z - a.z) * (p.x - a.x);
}

/// Whether the closed triangle t (possibly with no area) meets the closed
/// box [x0, x1] x [z0, z1]: separating axes (the box's, then each edge's).
inline bool touches(const LatticePoint (&t)[3], std::int64_t x0, std::int64_t x1, std::int64_t z0, std::int64_t z1) {
  auto [mnx, mxx] = std::minmax({t[0].x, t[1].x, t[2].x});
  auto [mnz, mxz] = std::minmax({t[0].z, t[1].z, t[2].z});
  if (mxx < x0 || mnx > x1 || mxz < z0 || mnz > z1) return false;
  const LatticePoint box[4] = {{x0, z0}, {x1, z0}, {x1, z1}, {x0, z1}};
  for (int e = 0; e < 3; ++e) {
    const LatticePoint a = t[e], b = t[(e + 1) % 3];
    if (a.x == b.x && a.z == b.z) continue;
    std::int64_t side = 0;  // the triangle's side of the edge (0: it has no area)
    for (const LatticePoint& p : t)
      if (std::int64_t o = orient(a, b, p); o != 0) side = o;
    int pos = 0, neg = 0;
    for (const LatticePoint& p : box) {
      const std::int64_t o = orient(a, b, p);
      pos += o > 0;
      neg += o < 0;
    }
    if (side == 0 ? (pos == 4 || neg == 4) : (side > 0 ? neg == 4 : pos == 4)) return false;
  }
  return true;
}

/// Whether the closed triangle t (possibly with no area) holds point p.
inline bool holds(const LatticePoint (&t)[3], LatticePoint p) {
  auto [mnx, mxx] = std::minmax({t[0].x, t[1].x, t[2].x});
  auto [mnz, mxz] = std::minmax({t[0].z, t[1].z, t[2].z});
  if (p.x < mnx || p.x > mxx || p.z < mnz || p.z > mxz) return false;
  const std::int64_t area = orient(t[0], t[1], t[2]);
  for (int e = 0; e < 3; ++e) {
    const LatticePoint a = t[e], b = t[(e + 1) % 3];
    const std::int64_t o = orient(a, b, p);
    if (area != 0 && (area > 0 ? o < 0 : o > 0)) return false;
    if (area == 0 && o == 0 && p.x >= std::min(a.x, b.x) && p.x <= std::max(a.x, b.x) &&
        p.z >= std::min(a.z, b.z) && p.z <= std::max(a.z, b.z))
      return true;
  }
  return area != 0;
}

/// The swept region of an edge moving from (fa, fb) to (ta, tb) as the cut
/// builds it (src/core/geometry.hpp, sweep_triangles), in exact integers:
/// the quad split along its diagonal fa-tb, or, where the two edges cross at
/// a point P strictly inside both (a bow-tie: the blade turned about a point
/// of its edge), the lobes (fa, ta, P) and (P, fb, tb). P = fa + (fb - fa) s
/// with s = (g x f) / (e x f) is rational, so a bow-tie's points are given
/// on a lattice `scale` = |e x f| times finer, where P's coordinates are
/// integers (scale 1 for the diagonal split).
struct SweepTriangles {
  LatticePoint tri[2][3];
  std::int64_t scale = 1;
  bool bow_tie = false;
};

inline SweepTriangles sweep_triangles(LatticePoint fa, LatticePoint fb, LatticePoint ta, LatticePoint tb) {
  SweepTriangles w{{{fa, fb, tb}, {fa, tb, ta}}};
  const std::int64_t ex = fb.x - fa.x, ez = fb.z - fa.z, fx = tb.x - ta.x, fz = tb.z - ta.z;
  const std::int64_t gx = ta.x - fa.x, gz = ta.z - fa.z;
  std::int64_t d = ex * fz - ez * fx, sn = gx * fz - gz * fx, un = gx * ez - gz * ex;
  if (d == 0) return w;
  if (d < 0) d = -d, sn = -sn, un = -un;
  if (!(sn > 0 && sn < d && un > 0 && un < d)) return w;
  const auto up = [d](LatticePoint q) { return LatticePoint{q.x * d, q.z * d}; };
  const LatticePoint p{fa.x * d + ex * sn, fa.z * d + ez * sn};
  const LatticePoint lobes[2][3] = {{up(fa), up(ta), p}, {p, up(fb), up(tb)}};
  for (int t = 0; t < 2; ++t)
    for (int v = 0; v < 3; ++v) w.tri[t][v] = lobes[t][v];
  w.scale = d;
  w.bow_tie = true;
  return w;
}

/// w on the lattice twice as fine, where the sample centres (half cells)
/// are points.
inline SweepTriangles doubled(SweepTriangles w) {
  for (auto& t : w.tri)
    for (auto& v : t) v = {2 * v.x, 2 * v.z};
  return w;
}

/// For a bow-tie, whether point q (on its scaled lattice) lies on a line
/// through the crossing P and another vertex of a lobe, or is P: the cut
/// computes P in double, rounded, so which side of such a line q falls on
/// is rounding's, not the closed rule's. False for the diagonal split.
inline bool on_crossing_line(const SweepTriangles& w, LatticePoint q) {
  if (!w.bow_tie) return false;
  const LatticePoint p = w.tri[0][2];
  for (const LatticePoint& v : {w.tri[0][0], w.tri[0][1], w.tri[1][1], w.tri[1][2]})
    if (orient(p, v, q) == 0) return true;
  return false;
}

/// on_crossing_line for a closed box [x0, x1] x [z0, z1]: a corner on such
/// a line, or P on the box's boundary.
inline bool on_crossing_line(const SweepTriangles& w, std::int64_t x0, std::int64_t x1, std::int64_t z0,
                             std::int64_t z1) {
  if (!w.bow_tie) return false;
  for (const LatticePoint& q : {LatticePoint{x0, z0}, LatticePoint{x1, z0}, LatticePoint{x1, z1}, LatticePoint{x0, z1}})
    if (on_crossing_line(w, q)) return true;
  const LatticePoint p = w.tri[0][2];
  const bool in_x = p.x >= x0 && p.x <= x1, in_z = p.z >= z0 && p.z <= z1;
  return (in_z && (p.x == x0 || p.x == x1)) || (in_x && (p.z == z0 || p.z == z1));
}

/// Whether dx/dz of the segment is exact in binary floating point.
inline bool representable_slope(LatticePoint a, LatticePoint b) {
  const std::int64_t dx = std::abs(b.x - a.x), dz = std::abs(b.z - a.z);
  if (dx == 0 || dz == 0) return true;
  const std::int64_t q = dz / std::gcd(dx, dz);
  return (q & (q - 1)) == 0;
}

}  // namespace terracut::test
