// Swept cutting, visiting only the samples under the swept triangles: each
// triangle is rasterised row by row (sample rows for the surface
// representation, cell rows for columns), so the cost follows the swept area.
#include "terracut/core/cut.hpp"

#include <cmath>

#include "geometry.hpp"

namespace terracut {

namespace {

using detail::GridFrame;

/// Lowers sample (c, r) to world height y and books the change.
inline void lower_to(HeightGrid& grid, const GridFrame& f, int c, int r, double y, CutResult& out) {
  float removed = grid.lower(grid.index(c, r), float(y - f.ground_y));
  if (removed > 0.0f) {
    out.removed_volume_m3 += double(removed) * f.cx * f.cz;
    out.changed.include(c, r);
  }
}

/// Surface representation: lowers every sample point under the triangle to
/// the triangle's height there. For each sample row, the triangle's section
/// with the plane z = row's z is a segment along which y is linear.
void cut_triangle_points(HeightGrid& grid, const GridFrame& f, const Vec3 (&p)[3],
                         CutResult& out) {
  double zmin = std::min({p[0].z, p[1].z, p[2].z});
  double zmax = std::max({p[0].z, p[1].z, p[2].z});
  int r_lo = std::max(0, int(std::ceil((zmin - f.z0) * f.inv_cz - 0.5)));
  int r_hi = std::min(f.rows - 1, int(std::floor((zmax - f.z0) * f.inv_cz - 0.5)));
  for (int r = r_lo; r <= r_hi; ++r) {
    double zr = f.z0 + (r + 0.5) * f.cz;
    // Points where the triangle's edges meet the plane z = zr.
    double xs[6], ys[6];
    int n = 0;
    for (int k = 0; k < 3; ++k) {
      const Vec3& a = p[k];
      const Vec3& b = p[(k + 1) % 3];
      if (a.z == b.z) {
        if (a.z == zr) {
          xs[n] = a.x, ys[n++] = a.y;
          xs[n] = b.x, ys[n++] = b.y;
        }
      } else if ((a.z <= zr && zr <= b.z) || (b.z <= zr && zr <= a.z)) {
        double t = (zr - a.z) / (b.z - a.z);
        xs[n] = a.x + t * (b.x - a.x);
        ys[n++] = a.y + t * (b.y - a.y);
      }
    }
    if (n == 0) continue;
    // The section's ends; where several points share an end, the lowest counts.
    int lo = 0, hi = 0;
    for (int k = 1; k < n; ++k) {
      if (xs[k] < xs[lo] || (xs[k] == xs[lo] && ys[k] < ys[lo])) lo = k;
      if (xs[k] > xs[hi] || (xs[k] == xs[hi] && ys[k] < ys[hi])) hi = k;
    }
    double x_lo = xs[lo], x_hi = xs[hi];
    int c_lo = std::max(0, int(std::ceil((x_lo - f.x0) * f.inv_cx - 0.5)));
    int c_hi = std::min(f.cols - 1, int(std::floor((x_hi - f.x0) * f.inv_cx - 0.5)));
    if (c_lo > c_hi) continue;
    double span = x_hi - x_lo;
    if (!(span > 1e-12 * f.cx)) {
      // A section that is a point or vertical: its lowest point counts.
      double y = ys[0];
      for (int k = 1; k < n; ++k) y = std::min(y, ys[k]);
      for (int c = c_lo; c <= c_hi; ++c) lower_to(grid, f, c, r, y, out);
      out.cells_visited += c_hi - c_lo + 1;
      continue;
    }
    double slope = (ys[hi] - ys[lo]) / span;
    for (int c = c_lo; c <= c_hi; ++c) {
      double xc = f.x0 + (c + 0.5) * f.cx;
      lower_to(grid, f, c, r, ys[lo] + slope * (xc - x_lo), out);
    }
    out.cells_visited += c_hi - c_lo + 1;
  }
}

/// Columns representation: lowers every column whose (closed) cell the
/// triangle touches to the triangle's lowest point inside the cell.
void cut_triangle_columns(HeightGrid& grid, const GridFrame& f, const Vec3 (&p)[3],
                          CutResult& out) {
  double zmin = std::min({p[0].z, p[1].z, p[2].z});
  double zmax = std::max({p[0].z, p[1].z, p[2].z});
  int r_lo = std::max(0, int(std::ceil((zmin - f.z0) * f.inv_cz)) - 1);
  int r_hi = std::min(f.rows - 1, int(std::floor((zmax - f.z0) * f.inv_cz)));
  for (int r = r_lo; r <= r_hi; ++r) {
    detail::Polygon strip;
    detail::clip_to_strip_z(p[0], p[1], p[2], f.z0 + r * f.cz, f.z0 + (r + 1) * f.cz, strip);
    if (strip.n == 0) continue;
    double xmin = strip.v[0].x, xmax = strip.v[0].x;
    for (int k = 1; k < strip.n; ++k) {
      xmin = std::min(xmin, strip.v[k].x);
      xmax = std::max(xmax, strip.v[k].x);
    }
    int c_lo = std::max(0, int(std::ceil((xmin - f.x0) * f.inv_cx)) - 1);
    int c_hi = std::min(f.cols - 1, int(std::floor((xmax - f.x0) * f.inv_cx)));
    for (int c = c_lo; c <= c_hi; ++c) {
      double y = detail::min_y_in_strip_x(strip, f.x0 + c * f.cx, f.x0 + (c + 1) * f.cx);
      if (y < INFINITY) lower_to(grid, f, c, r, y, out);
    }
    out.cells_visited += std::max(0, c_hi - c_lo + 1);
  }
}

}  // namespace

CutResult cut_sweep(HeightGrid& grid, Representation representation, const Segment& from,
                    const Segment& to) {
  CutResult out;
  if (!is_finite(from.a) || !is_finite(from.b) || !is_finite(to.a) || !is_finite(to.b)) return out;
  GridFrame f(grid);
  Vec3 tri[2][3];
  detail::sweep_triangles(from, to, tri);
  for (const auto& t : tri) {
    if (representation == Representation::kColumns) {
      cut_triangle_columns(grid, f, t, out);
    } else {
      cut_triangle_points(grid, f, t, out);
    }
  }
  return out;
}

}  // namespace terracut
