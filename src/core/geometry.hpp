// Internal geometry shared by the traversal code and the brute-force oracle:
// the per-piece contact measure, segment clipping, the grid frame, and small
// fixed-size polygon clipping. Not part of the public API.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "terracut/core/blade.hpp"
#include "terracut/core/contact.hpp"
#include "terracut/core/grid.hpp"

namespace terracut::detail {

/// The grid's mapping from world to continuous cell coordinates, cached for
/// the hot path: u = (x - x0) * inv_cx, v = (z - z0) * inv_cz; cell (c, r)
/// covers [c, c+1) x [r, r+1).
struct GridFrame {
  double x0, z0, ground_y;
  double cx, cz, inv_cx, inv_cz;
  int cols, rows;
  /// Float rounding of heights: 2^-20 of the full scale. The surface
  /// representation counts material only deeper than this above the blade,
  /// so a blade resting on a surface it has just cut is not in contact; the
  /// columns representation counts depths down to minus this, so a blade
  /// resting on a column's top touches it (closed boxes, as the slab method).
  double depth_epsilon_m;

  /// The smallest depth of material above the edge that counts as contact.
  double min_contact_depth_m(Representation representation) const {
    return representation == Representation::kColumns ? -depth_epsilon_m : depth_epsilon_m;
  }

  explicit GridFrame(const HeightGrid& grid)
      : x0(grid.spec().origin_m.x),
        z0(grid.spec().origin_m.z),
        ground_y(grid.spec().origin_m.y),
        cx(grid.spec().cell_x_m()),
        cz(grid.spec().cell_z_m()),
        inv_cx(1.0 / grid.spec().cell_x_m()),
        inv_cz(1.0 / grid.spec().cell_z_m()),
        cols(grid.cols()),
        rows(grid.rows()),
        depth_epsilon_m(std::ldexp(grid.spec().full_scale_m + std::abs(grid.spec().origin_m.y), -20)) {}
};

/// Pieces of an edge shorter than this (in cells along the edge's major
/// axis) add to the contact length and area but not to the largest depth:
/// where an edge crosses a cell corner, rounding of its parameter can leave
/// such a sliver in a third cell, and with columns that cell's depth (a
/// neighbour's top) would be taken as the whole edge's largest depth.
constexpr double kMinDepthPieceCells = 1e-9;

/// The edge-parameter length of a kMinDepthPieceCells piece, for an edge
/// spanning major_cells cells along its major axis (0 when it spans none).
inline double min_depth_piece(double major_cells) {
  return major_cells > 0.0 ? kMinDepthPieceCells / major_cells : 0.0;
}

/// Keeps the part of [t0, t1] where the linear function f(t) = fa + (fb - fa) t
/// is > 0 (strict) or >= 0. Returns false when nothing is left.
inline bool clip_linear(double fa, double fb, bool strict, double& t0, double& t1) {
  double f0 = fa + (fb - fa) * t0;
  double f1 = fa + (fb - fa) * t1;
  bool in0 = strict ? f0 > 0.0 : f0 >= 0.0;
  bool in1 = strict ? f1 > 0.0 : f1 >= 0.0;
  if (in0 && in1) return true;
  if (!in0 && !in1) return false;
  double root = fa / (fa - fb);
  if (in0) {
    t1 = std::min(t1, root);
  } else {
    t0 = std::max(t0, root);
  }
  return t1 > t0;
}

/// Adds the contact of one piece of the edge, [sa, sb] in edge parameter,
/// over which both the material top and the edge height are linear: inside
/// material where ground <= y and top - y > min_depth_m (see
/// GridFrame::min_contact_depth_m). seg_length_m is the edge's 3-D length;
/// min_piece (edge parameter) the shortest piece whose depth counts for the
/// largest depth (min_depth_piece).
inline void accumulate_piece(double sa, double sb, double top_a, double top_b, double y_a,
                             double y_b, const GridFrame& frame, double min_depth_m,
                             double seg_length_m, double min_piece, ContactResult& out) {
  if (!(sb > sa)) return;
  double t0 = 0.0, t1 = 1.0;
  double da = top_a - y_a, db = top_b - y_b;
  if (!clip_linear(da - min_depth_m, db - min_depth_m, true, t0, t1)) return;
  if (!clip_linear(y_a - frame.ground_y, y_b - frame.ground_y, false, t0, t1)) return;
  double d0 = da + (db - da) * t0;
  double d1 = da + (db - da) * t1;
  double len = (t1 - t0) * (sb - sa) * seg_length_m;
  out.length_m += len;
  out.section_area_m2 += len * 0.5 * (d0 + d1);
  if ((t1 - t0) * (sb - sa) >= min_piece) out.max_depth_m = std::max(out.max_depth_m, std::max(d0, d1));
}

/// Clips the parameter range [s0, s1] of p(s) = p0 + s * dp to lo <= p <= hi
/// (one axis of a Liang-Barsky clip). Returns false when nothing is left.
inline bool clip_axis(double p0, double dp, double lo, double hi, double& s0, double& s1) {
  if (dp == 0.0) return p0 >= lo && p0 <= hi;
  double a = (lo - p0) / dp;
  double b = (hi - p0) / dp;
  if (a > b) std::swap(a, b);
  s0 = std::max(s0, a);
  s1 = std::min(s1, b);
  return s1 >= s0;
}

/// Height of the surface representation inside node square (i, j) at local
/// coordinates (a, b) in [0,1]^2, from its corner heights. Split along the
/// diagonal from (1, 0) to (0, 1), as Bullet's heightfield.
inline double surface_in_square(double h00, double h10, double h01, double h11, double a,
                                double b, bool lower_triangle) {
  if (lower_triangle) return h00 + a * (h10 - h00) + b * (h01 - h00);
  return h11 + (1.0 - a) * (h01 - h11) + (1.0 - b) * (h10 - h11);
}

/// Where a point falls among the samples, found once for any layer laid out
/// as spec says: outside the terrain (height 0), a column's sample, or a
/// square of the triangulated surface (the split surface_in_square uses)
/// with the point's place in it. The terrain surface query (surface.hpp)
/// and the soil ahead of the edge (soil_ahead.cpp) read through it.
struct SurfacePoint {
  SurfacePoint() = default;
  bool outside = true;
  bool columns = false;
  bool lower = false;       // kSurface: the point lies in the square's lower triangle
  std::int64_t sample = 0;  // kColumns: the cell's sample; kSurface: the square's first node
  std::int64_t right = 0;   // kSurface: the offset of the square's next node along X
  std::int64_t up = 0;      // and along Z (0 where the grid is one sample wide)
  double a = 0.0, b = 0.0;  // kSurface: the point's offsets in the square

  /// At world (x, z).
  SurfacePoint(const GridSpec& spec, Representation representation, double x, double z)
      : SurfacePoint(spec.cols, spec.rows, representation, (x - spec.origin_m.x) / spec.cell_x_m(),
                     (z - spec.origin_m.z) / spec.cell_z_m()) {}

  /// At continuous cell coordinates (u, v) (cell (c, r) covers [c, c+1) x
  /// [r, r+1)) of a grid of cols x rows samples.
  SurfacePoint(int cols, int rows, Representation representation, double u, double v) {
    if (!(u >= 0.0 && u <= cols && v >= 0.0 && v <= rows)) return;
    outside = false;
    if (representation == Representation::kColumns) {
      columns = true;
      const int c = std::min(int(u), cols - 1), r = std::min(int(v), rows - 1);
      sample = std::int64_t(r) * cols + c;
      return;
    }
    // Node coordinates (sample (c, r) at integer (c, r)), clamped to the
    // outer samples: the half-cell border is flat.
    const double us = std::clamp(u - 0.5, 0.0, double(cols - 1));
    const double vs = std::clamp(v - 0.5, 0.0, double(rows - 1));
    const int i = std::clamp(int(us), 0, std::max(cols - 2, 0));
    const int j = std::clamp(int(vs), 0, std::max(rows - 2, 0));
    a = us - i;
    b = vs - j;
    lower = a + b <= 1.0;
    // (i + 1 and j + 1 are within the grid unless it is one sample wide,
    // where the next node is the node itself, as clamped_height gives.)
    sample = std::int64_t(j) * cols + i;
    right = i + 1 < cols ? 1 : 0;
    up = j + 1 < rows ? std::int64_t(cols) : 0;
  }

  /// On the triangulated surface at (u, v) known to lie where no clamp
  /// applies (u in [0.5, cols - 0.5), v in [0.5, rows - 0.5)): the same
  /// square and offsets as the constructor above, without its tests.
  static SurfacePoint interior(int cols, double u, double v) {
    SurfacePoint p;
    const double us = u - 0.5, vs = v - 0.5;
    const int i = int(us), j = int(vs);
    p.outside = false;
    p.a = us - i;
    p.b = vs - j;
    p.lower = p.a + p.b <= 1.0;
    p.sample = std::int64_t(j) * cols + i;
    p.right = 1;
    p.up = cols;
    return p;
  }

  /// The surface's height over the layer h at the point, metres above the
  /// ground level.
  double height(const float* h) const {
    if (outside) return 0.0;
    if (columns) return h[sample];
    const float* s = h + sample;
    return surface_in_square(s[0], s[right], s[up], s[up + right], a, b, lower);
  }
};

/// Height of sample (c, r) with indices clamped to the grid (the surface's
/// flat extension over the half-cell border).
inline double clamped_height(const float* h, int cols, int rows, int c, int r) {
  c = std::clamp(c, 0, cols - 1);
  r = std::clamp(r, 0, rows - 1);
  return h[std::int64_t(r) * cols + c];
}

/// A convex polygon of at most kMax vertices in 3-D (a triangle clipped by up
/// to four axis-aligned planes).
struct Polygon {
  static constexpr int kMax = 8;
  Vec3 v[kMax];
  int n = 0;
};

/// Keeps the part of poly with sign * (coordinate axis - bound) >= 0, axis 0 = x, 2 = z.
inline void clip_polygon(const Polygon& in, int axis, double bound, double sign, Polygon& out) {
  out.n = 0;
  if (in.n == 0) return;
  auto dist = [&](const Vec3& p) { return sign * ((axis == 0 ? p.x : p.z) - bound); };
  for (int k = 0; k < in.n; ++k) {
    const Vec3& p = in.v[k];
    const Vec3& q = in.v[(k + 1) % in.n];
    double dp = dist(p), dq = dist(q);
    if (dp >= 0.0 && out.n < Polygon::kMax) out.v[out.n++] = p;
    if ((dp >= 0.0) != (dq >= 0.0) && out.n < Polygon::kMax) {
      double t = dp / (dp - dq);
      out.v[out.n++] = lerp(p, q, t);
    }
  }
}

/// Clips a triangle to the closed strip z0 <= z <= z1.
inline void clip_to_strip_z(const Vec3& a, const Vec3& b, const Vec3& c, double z0, double z1,
                            Polygon& out) {
  Polygon tri, tmp;
  tri.v[0] = a;
  tri.v[1] = b;
  tri.v[2] = c;
  tri.n = 3;
  clip_polygon(tri, 2, z0, 1.0, tmp);
  clip_polygon(tmp, 2, z1, -1.0, out);
}

/// Lowest y of the part of poly with x0 <= x <= x1; +inf when none.
inline double min_y_in_strip_x(const Polygon& poly, double x0, double x1) {
  Polygon a, b;
  clip_polygon(poly, 0, x0, 1.0, a);
  clip_polygon(a, 0, x1, -1.0, b);
  double lowest = INFINITY;
  for (int k = 0; k < b.n; ++k) lowest = std::min(lowest, b.v[k].y);
  return lowest;
}

/// The swept triangles of one sub-step: the quad from.a, from.b, to.b,
/// to.a split along a diagonal. When the two edges cross in plan (the blade
/// turned about a point of its edge in the step: a turn in place, or a
/// hand's wobble about the vertical), that quad is a bow-tie whose lobes are
/// the triangles (from.a, to.a, P) and (P, from.b, to.b), P the crossing,
/// and those are the triangles. (Split along the diagonal, the triangle
/// from.a, from.b, to.b reaches ahead of the part of the edge on from.a's
/// side of P, which moved the other way: a 2 m blade wobbling 1.5 degrees
/// about its centre cut soil 0.5 mm ahead of itself, step after step, on a
/// sample its edge never reached.) P's height is the lower of the two
/// edges' there: the region is the ruled surface between them to within
/// the distance between their parameters at P, which is zero for a rigid
/// turn about P.
inline void sweep_triangles(const Segment& from, const Segment& to, Vec3 tri[2][3]) {
  const double ex = from.b.x - from.a.x, ez = from.b.z - from.a.z;
  const double fx = to.b.x - to.a.x, fz = to.b.z - to.a.z;
  const double den = ex * fz - ez * fx;  // e x f in plan
  // Edges crossing at an angle above rounding (a translation's are parallel
  // to rounding, and its quad is no bow-tie).
  if (std::abs(den) > 1e-12 * std::hypot(ex, ez) * std::hypot(fx, fz)) {
    const double gx = to.a.x - from.a.x, gz = to.a.z - from.a.z;
    const double s = (gx * fz - gz * fx) / den;  // P along from
    const double u = (gx * ez - gz * ex) / den;  // P along to
    if (s > 0.0 && s < 1.0 && u > 0.0 && u < 1.0) {
      Vec3 p = lerp(from.a, from.b, s);
      p.y = std::min(p.y, lerp(to.a, to.b, u).y);
      tri[0][0] = from.a;
      tri[0][1] = to.a;
      tri[0][2] = p;
      tri[1][0] = p;
      tri[1][1] = from.b;
      tri[1][2] = to.b;
      return;
    }
  }
  tri[0][0] = from.a;
  tri[0][1] = from.b;
  tri[0][2] = to.b;
  tri[1][0] = from.a;
  tri[1][1] = to.b;
  tri[1][2] = to.a;
}

/// True when the whole sweep lies at or above the ground (the usual case).
inline bool sweep_above_floor(const Segment& from, const Segment& to, double ground_y) {
  return from.a.y >= ground_y && from.b.y >= ground_y && to.a.y >= ground_y && to.b.y >= ground_y;
}

/// The swept triangles with their parts below the ground removed: the blade
/// inside the rigid floor touches no material and cuts nothing. Writes 0 to 4
/// triangles (each clipped triangle is a triangle or a quad split in two)
/// and returns how many.
inline int sweep_triangles_above_floor(const Segment& from, const Segment& to, double ground_y,
                                       Vec3 out[4][3]) {
  Vec3 tri[2][3];
  sweep_triangles(from, to, tri);
  int n = 0;
  for (const auto& t : tri) {
    // Sutherland-Hodgman against y >= ground_y.
    Vec3 poly[4];
    int m = 0;
    for (int k = 0; k < 3; ++k) {
      const Vec3& p = t[k];
      const Vec3& q = t[(k + 1) % 3];
      double dp = p.y - ground_y, dq = q.y - ground_y;
      if (dp >= 0.0) poly[m++] = p;
      if ((dp >= 0.0) != (dq >= 0.0)) {
        Vec3 c = lerp(p, q, dp / (dp - dq));
        c.y = ground_y;  // exactly on the floor despite rounding
        poly[m++] = c;
      }
    }
    for (int k = 1; k + 1 < m; ++k) {
      out[n][0] = poly[0];
      out[n][1] = poly[k];
      out[n][2] = poly[k + 1];
      ++n;
    }
  }
  return n;
}

/// A hint to fetch the cache line at p, for reading or (kWrite) writing,
/// with GCC's temporal locality (3: into every cache level, 2: not into L1).
/// No effect on results: prefetches never fault.
template <bool kWrite = false, int kLocality = 3>
inline void prefetch(const float* p) {
#if defined(__GNUC__)
  __builtin_prefetch(p, kWrite ? 1 : 0, kLocality);
#else
  (void)p;
#endif
}

}  // namespace terracut::detail
