// The paper's algorithm: every column (or every surface triangle, every
// sample) is tested against the blade, every step. Deliberately simple and
// independent of the traversal code; used as the oracle in tests and as the
// baseline in benchmarks.
#include "terracut/core/brute_force.hpp"

#include <algorithm>
#include <cmath>

#include "geometry.hpp"

namespace terracut {

using detail::GridFrame;

namespace {

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
  Vec3 tri[4][3];
  const int n_tri = detail::sweep_triangles_above_floor(from, to, f.ground_y, tri);
  for (int r = 0; r < f.rows; ++r) {
    for (int c = 0; c < f.cols; ++c) {
      ++out.cells_visited;
      double lowest = INFINITY;
      for (int k = 0; k < n_tri; ++k) {
        const auto& t = tri[k];
        if (representation == Representation::kColumns) {
          // Each column box against the swept region (the paper's per-column test).
          detail::Polygon strip;
          detail::clip_to_strip_z(t[0], t[1], t[2], f.z0 + r * f.cz, f.z0 + (r + 1) * f.cz, strip);
          lowest = std::min(lowest, detail::min_y_in_strip_x(strip, f.x0 + c * f.cx, f.x0 + (c + 1) * f.cx));
        } else {
          // Is the sample point inside the triangle's footprint? Barycentric test.
          double px = f.x0 + (c + 0.5) * f.cx, pz = f.z0 + (r + 0.5) * f.cz;
          double ax = t[1].x - t[0].x, az = t[1].z - t[0].z;
          double bx = t[2].x - t[0].x, bz = t[2].z - t[0].z;
          double det = ax * bz - az * bx;
          if (!(std::abs(det) > 1e-18 * f.cx * f.cz)) continue;  // no footprint area
          double qx = px - t[0].x, qz = pz - t[0].z;
          double l1 = (qx * bz - qz * bx) / det;
          double l2 = (ax * qz - az * qx) / det;
          if (l1 < 0.0 || l2 < 0.0 || l1 + l2 > 1.0) continue;
          lowest = std::min(lowest, t[0].y + l1 * (t[1].y - t[0].y) + l2 * (t[2].y - t[0].y));
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
