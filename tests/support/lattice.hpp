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

/// Whether dx/dz of the segment is exact in binary floating point.
inline bool representable_slope(LatticePoint a, LatticePoint b) {
  const std::int64_t dx = std::abs(b.x - a.x), dz = std::abs(b.z - a.z);
  if (dx == 0 || dz == 0) return true;
  const std::int64_t q = dz / std::gcd(dx, dz);
  return (q & (q - 1)) == 0;
}

}  // namespace terracut::test
