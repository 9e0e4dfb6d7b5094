// The paper's algorithm: every column (or every surface triangle, every
// sample) is tested against the blade, every step. Deliberately simple and
// independent of the traversal code; used as the oracle in tests and as the
// baseline in benchmarks.
//
// It decides the boundary cases by the rules of docs/model.md ("Boundaries"),
// exactly wherever the inputs are exact:
//
// - contact: each point of the edge belongs to one cell, the half-open
//   [c, c+1) x [r, r+1) (node squares and the lower triangle, a + b <= 1,
//   for the surface), the grid's far edges to its last cells; so an edge
//   lying on a cell wall is counted once.
// - cut: the swept region and the cells are closed. A sample on the
//   region's boundary is lowered (a blade at rest lowers the samples its
//   edge passes exactly through), and a column whose cell the region
//   touches only at a corner or along a wall is lowered to the region's
//   lowest point there. Which side of a line a point lies on is decided by
//   an exact orientation test (a floating-point filter, then exact
//   arithmetic when the filter cannot tell), so a point exactly on a line
//   is on it.
#include "terracut/core/brute_force.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "geometry.hpp"

namespace terracut {

using detail::GridFrame;

namespace {

// ---------------------------------------------------------------------------
// The sign of orient2d(a, b, c) = (a.x - c.x)(b.z - c.z) - (a.z - c.z)(b.x - c.x),
// exactly: > 0 when c lies left of a -> b seen with x right and z up, 0 on
// the line. Floating point first; when its error bound cannot decide, the
// determinant is summed exactly as an expansion (Shewchuk's error-free
// transformations: two_sum, and fma for exact products).

void two_sum(double a, double b, double& sum, double& err) {
  sum = a + b;
  const double bv = sum - a;
  const double av = sum - bv;
  err = (a - av) + (b - bv);
}

// An exact sum of doubles as a nonoverlapping expansion of increasing
// magnitude (Shewchuk's grow-expansion); its sign is its largest component's.
struct Expansion {
  double e[20];
  int n = 0;
  void add(double b) {
    double q = b;
    for (int i = 0; i < n; ++i) two_sum(q, e[i], q, e[i]);
    e[n++] = q;
  }
  // Adds the exact product (a1 + a0)(b1 + b0) times sign.
  void add_product(double a1, double a0, double b1, double b0, double sign) {
    const double f[2] = {a1, a0}, g[2] = {b1, b0};
    for (double x : f) {
      for (double y : g) {
        const double p = x * y;
        add(sign * p);
        add(sign * std::fma(x, y, -p));
      }
    }
  }
  int sign() const {
    for (int i = n - 1; i >= 0; --i) {
      if (e[i] > 0.0) return 1;
      if (e[i] < 0.0) return -1;
    }
    return 0;
  }
};

// The exact sign, when the floating-point filter cannot tell (rare: points
// on or within rounding of the line).
[[gnu::noinline]] int orient_xz_exact(const Vec3& a, const Vec3& b, double cx, double cz) {
  double ax1, ax0, az1, az0, bx1, bx0, bz1, bz0;
  two_sum(a.x, -cx, ax1, ax0);
  two_sum(a.z, -cz, az1, az0);
  two_sum(b.x, -cx, bx1, bx0);
  two_sum(b.z, -cz, bz1, bz0);
  Expansion sum;
  sum.add_product(ax1, ax0, bz1, bz0, 1.0);
  sum.add_product(az1, az0, bx1, bx0, -1.0);
  return sum.sign();
}

inline int orient_xz(const Vec3& a, const Vec3& b, double cx, double cz) {
  const double left = (a.x - cx) * (b.z - cz);
  const double right = (a.z - cz) * (b.x - cx);
  const double det = left - right;
  // Shewchuk's bound for orient2d's first stage.
  constexpr double kEps = std::numeric_limits<double>::epsilon() / 2.0;
  const double bound = (3.0 * kEps + 16.0 * kEps * kEps) * (std::abs(left) + std::abs(right));
  if (det > bound) return 1;
  if (det < -bound) return -1;
  return orient_xz_exact(a, b, cx, cz);
}

// ---------------------------------------------------------------------------
// Contact: the half-open cells.

/// Clips the parameter range [s0, s1] of p(s) = p0 + s * dp to the cell
/// lo <= p < hi, or lo <= p <= hi for the grid's last cell (last): half-open
/// cells, so that each point of the edge belongs to one cell and an edge
/// lying on a cell wall is counted once. The closed range otherwise, since
/// its ends only matter for an edge along the axis (dp = 0), which lies in
/// the cell only when its p0 does.
bool clip_cell(double p0, double dp, double lo, double hi, bool last, double& s0, double& s1) {
  if (dp == 0.0) return p0 >= lo && (last ? p0 <= hi : p0 < hi);
  return detail::clip_axis(p0, dp, lo, hi, s0, s1);
}

// ---------------------------------------------------------------------------
// Cut: closed regions.

/// A swept triangle with what every test against it reuses.
struct Triangle {
  Vec3 v[3];
  int area = 0;  // the exact sign of its footprint's orientation; 0: no footprint area
  double min_x, max_x, min_z, max_z;
  // The plane's barycentric set-up (when its footprint is well shaped: planar).
  bool planar = false;
  double ax, az, bx, bz, det;

  explicit Triangle(const Vec3 (&t)[3]) : v{t[0], t[1], t[2]} {
    area = orient_xz(v[0], v[1], v[2].x, v[2].z);
    min_x = std::min({v[0].x, v[1].x, v[2].x});
    max_x = std::max({v[0].x, v[1].x, v[2].x});
    min_z = std::min({v[0].z, v[1].z, v[2].z});
    max_z = std::max({v[0].z, v[1].z, v[2].z});
    ax = v[1].x - v[0].x, az = v[1].z - v[0].z;
    bx = v[2].x - v[0].x, bz = v[2].z - v[0].z;
    det = ax * bz - az * bx;
    planar = area != 0 && std::abs(det) > 1e-6 * (std::abs(ax * bz) + std::abs(az * bx));
  }

  /// The height of its plane over the point (px, pz) of its footprint:
  /// barycentric; for a sliver too thin for that (standing nearly on edge),
  /// along its section z = pz, or the section's lower end where the section
  /// is a point (as the rasteriser does).
  double plane_height(double px, double pz, double cell_x) const {
    if (planar) {
      const double qx = px - v[0].x, qz = pz - v[0].z;
      const double l1 = (qx * bz - qz * bx) / det;
      const double l2 = (ax * qz - az * qx) / det;
      return v[0].y + l1 * (v[1].y - v[0].y) + l2 * (v[2].y - v[0].y);
    }
    double xa = INFINITY, ya = INFINITY, xb = -INFINITY, yb = INFINITY;  // the section's ends
    auto take = [&](double x, double y) {
      if (x < xa || (x == xa && y < ya)) xa = x, ya = y;
      if (x > xb || (x == xb && y < yb)) xb = x, yb = y;
    };
    for (int k = 0; k < 3; ++k) {
      const Vec3& p = v[k];
      const Vec3& q = v[(k + 1) % 3];
      if (pz < std::min(p.z, q.z) || pz > std::max(p.z, q.z)) continue;
      if (p.z == q.z) {
        take(p.x, p.y);
        take(q.x, q.y);
      } else {
        const double s = (pz - p.z) / (q.z - p.z);
        take(p.x + s * (q.x - p.x), p.y + s * (q.y - p.y));
      }
    }
    if (xb - xa > 1e-12 * cell_x) return ya + (px - xa) * (yb - ya) / (xb - xa);
    return std::min(ya, yb);
  }

  /// The lowest point of the closed triangle over the point (px, pz), or
  /// +inf when the point is outside its footprint. A triangle with no
  /// footprint area (standing on edge, or a blade at rest) holds the points
  /// of its edges' footprints; its lowest point over one is the lowest of
  /// its edges there.
  double lowest_over_point(double px, double pz, double cell_x) const {
    if (area != 0) {
      if (orient_xz(v[0], v[1], px, pz) == -area || orient_xz(v[1], v[2], px, pz) == -area ||
          orient_xz(v[2], v[0], px, pz) == -area)
        return INFINITY;
      return plane_height(px, pz, cell_x);
    }
    double lowest = INFINITY;
    for (int k = 0; k < 3; ++k) {
      const Vec3& p = v[k];
      const Vec3& q = v[(k + 1) % 3];
      if (px < std::min(p.x, q.x) || px > std::max(p.x, q.x) || pz < std::min(p.z, q.z) ||
          pz > std::max(p.z, q.z))
        continue;
      if (orient_xz(p, q, px, pz) != 0) continue;
      const double dx = q.x - p.x, dz = q.z - p.z;
      const double len2 = dx * dx + dz * dz;
      if (len2 > 0.0) {
        const double s = std::clamp(((px - p.x) * dx + (pz - p.z) * dz) / len2, 0.0, 1.0);
        lowest = std::min(lowest, p.y + s * (q.y - p.y));
      } else {
        lowest = std::min(lowest, std::min(p.y, q.y));  // an edge standing vertically on the point
      }
    }
    return lowest;
  }

  /// The lowest point of the closed triangle over the closed cell [x0, x1] x
  /// [z0, z1], or +inf when they do not meet. The part of the triangle over
  /// the cell is a convex polygon (a segment or a point where they only
  /// touch) whose lowest point is one of its vertices: a triangle vertex in
  /// the cell, a crossing of a triangle edge with a side of the cell, or a
  /// cell corner in the triangle's footprint.
  double lowest_over_cell(double x0, double x1, double z0, double z1) const {
    const double cell_x = x1 - x0;
    double lowest = INFINITY;
    for (const Vec3& p : v)
      if (p.x >= x0 && p.x <= x1 && p.z >= z0 && p.z <= z1) lowest = std::min(lowest, p.y);
    for (int k = 0; k < 3; ++k) {
      const Vec3& p = v[k];
      const Vec3& q = v[(k + 1) % 3];
      // The cell's side from (ax, az) to (bx, bz) on the line where the
      // edge's coordinate pc -> qc (x or z) equals at: crossed where p and q
      // straddle the line and the side's ends straddle the edge's line.
      auto side = [&](double pc, double qc, double at, double ax, double az, double bx, double bz) {
        if (pc == qc || at < std::min(pc, qc) || at > std::max(pc, qc)) return;
        if (orient_xz(p, q, ax, az) * orient_xz(p, q, bx, bz) > 0) return;
        const double s = (at - pc) / (qc - pc);
        lowest = std::min(lowest, p.y + s * (q.y - p.y));
      };
      side(p.x, q.x, x0, x0, z0, x0, z1);
      side(p.x, q.x, x1, x1, z0, x1, z1);
      side(p.z, q.z, z0, x0, z0, x1, z0);
      side(p.z, q.z, z1, x0, z1, x1, z1);
    }
    // Corners inside a triangle with a footprint (on a flat one they lie on
    // an edge, found above; outside its bounding box they are outside it).
    if (area != 0) {
      for (double x : {x0, x1}) {
        for (double z : {z0, z1}) {
          if (x >= min_x && x <= max_x && z >= min_z && z <= max_z)
            lowest = std::min(lowest, lowest_over_point(x, z, cell_x));
        }
      }
    }
    return lowest;
  }
};

}  // namespace

ContactResult measure_contact_brute_force(const HeightGrid& grid, Representation representation,
                                          const Segment& edge) {
  ContactResult out;
  if (!is_finite(edge.a) || !is_finite(edge.b)) return out;
  GridFrame f(grid);
  Vec3 d = edge.b - edge.a;
  double seg_len = length(d);
  const float* h = grid.heights();
  const double min_piece = detail::min_depth_piece(std::max(std::abs(d.x * f.inv_cx), std::abs(d.z * f.inv_cz)));
  if (representation == Representation::kColumns) {
    // Slab method against every box: the x and z slabs give the parameter
    // range over the column's footprint, the y range is clipped per piece.
    for (int r = 0; r < f.rows; ++r) {
      for (int c = 0; c < f.cols; ++c) {
        ++out.cells_visited;
        double s0 = 0.0, s1 = 1.0;
        if (!clip_cell(edge.a.x, d.x, f.x0 + c * f.cx, f.x0 + (c + 1) * f.cx, c == f.cols - 1, s0, s1)) continue;
        if (!clip_cell(edge.a.z, d.z, f.z0 + r * f.cz, f.z0 + (r + 1) * f.cz, r == f.rows - 1, s0, s1)) continue;
        double top = f.ground_y + h[std::int64_t(r) * f.cols + c];
        detail::accumulate_piece(s0, s1, top, top, edge.a.y + s0 * d.y, edge.a.y + s1 * d.y, f,
                                 f.min_contact_depth_m(representation), seg_len, min_piece, out);
      }
    }
    return out;
  }
  // Surface: clip the edge to every triangle's vertical prism. Node coordinates
  // as in measure_contact: node (c, r) at integer (c, r), domain [-0.5, n - 0.5].
  double u0 = (edge.a.x - f.x0) * f.inv_cx - 0.5, v0 = (edge.a.z - f.z0) * f.inv_cz - 0.5;
  double du = d.x * f.inv_cx, dv = d.z * f.inv_cz;
  for (int j = -1; j < f.rows; ++j) {
    for (int i = -1; i < f.cols; ++i) {
      ++out.cells_visited;
      double h00 = detail::clamped_height(h, f.cols, f.rows, i, j);
      double h10 = detail::clamped_height(h, f.cols, f.rows, i + 1, j);
      double h01 = detail::clamped_height(h, f.cols, f.rows, i, j + 1);
      double h11 = detail::clamped_height(h, f.cols, f.rows, i + 1, j + 1);
      for (int lower = 1; lower >= 0; --lower) {
        double s0 = 0.0, s1 = 1.0;
        // The domain and the square (half-open, the last one closed).
        if (!clip_cell(u0, du, std::max(-0.5, double(i)), std::min(f.cols - 0.5, i + 1.0), i == f.cols - 1, s0, s1))
          break;
        if (!clip_cell(v0, dv, std::max(-0.5, double(j)), std::min(f.rows - 0.5, j + 1.0), j == f.rows - 1, s0, s1))
          break;
        // The triangle: a + b <= 1 (lower) or a + b > 1 (upper).
        double w0 = (u0 - i) + (v0 - j) - 1.0, dw = du + dv;
        if (dw == 0.0) {
          if (lower ? !(w0 <= 0.0) : !(w0 > 0.0)) continue;
        } else if (lower) {
          if (!detail::clip_axis(w0, dw, -INFINITY, 0.0, s0, s1)) continue;
        } else {
          if (!detail::clip_axis(w0, dw, 0.0, INFINITY, s0, s1)) continue;
        }
        if (!(s1 > s0)) continue;
        double top0 = f.ground_y + detail::surface_in_square(h00, h10, h01, h11, u0 + s0 * du - i,
                                                            v0 + s0 * dv - j, lower);
        double top1 = f.ground_y + detail::surface_in_square(h00, h10, h01, h11, u0 + s1 * du - i,
                                                            v0 + s1 * dv - j, lower);
        detail::accumulate_piece(s0, s1, top0, top1, edge.a.y + s0 * d.y, edge.a.y + s1 * d.y, f,
                                 f.min_contact_depth_m(representation), seg_len, min_piece, out);
      }
    }
  }
  return out;
}

CutResult cut_sweep_brute_force(HeightGrid& grid, Representation representation,
                                const Segment& from, const Segment& to) {
  CutResult out;
  if (!is_finite(from.a) || !is_finite(from.b) || !is_finite(to.a) || !is_finite(to.b)) return out;
  GridFrame f(grid);
  // The part of the sweep inside the rigid floor cuts nothing.
  Vec3 corners[4][3];
  const int n_tri = detail::sweep_triangles_above_floor(from, to, f.ground_y, corners);
  std::vector<Triangle> tri;
  for (int k = 0; k < n_tri; ++k) tri.emplace_back(corners[k]);
  for (int r = 0; r < f.rows; ++r) {
    for (int c = 0; c < f.cols; ++c) {
      ++out.cells_visited;
      double lowest = INFINITY;
      for (const Triangle& t : tri) {
        if (representation == Representation::kColumns) {
          // Each closed column cell against the closed swept region (the paper's per-column test).
          lowest = std::min(lowest, t.lowest_over_cell(f.x0 + c * f.cx, f.x0 + (c + 1) * f.cx, f.z0 + r * f.cz,
                                                       f.z0 + (r + 1) * f.cz));
        } else {
          // Is the sample point inside the closed triangle's footprint?
          lowest = std::min(lowest, t.lowest_over_point(f.x0 + (c + 0.5) * f.cx, f.z0 + (r + 0.5) * f.cz, f.cx));
        }
      }
      if (lowest < INFINITY) {
        float removed = grid.lower(grid.index(c, r), float(lowest - f.ground_y));
        if (removed > 0.0f) {
          out.removed_volume_m3 += double(removed) * f.cx * f.cz;
          out.changed.include(c, r);
        }
      }
    }
  }
  return out;
}

}  // namespace terracut
