// Contact length by walking only the cells under the edge: the edge's
// footprint on the ground plane is traversed cell by cell (Amanatides-Woo), and
// inside each cell the material top and the edge height are both linear in the
// edge parameter, so the inside length is exact for the representation.
#include "terracut/core/contact.hpp"

#include <cmath>
#include <limits>

#include "geometry.hpp"

namespace terracut {

std::string_view to_string(Representation representation) {
  return representation == Representation::kColumns ? "columns" : "surface";
}

std::optional<Representation> parse_representation(std::string_view name) {
  if (name == "columns") return Representation::kColumns;
  if (name == "surface") return Representation::kSurface;
  return std::nullopt;
}

namespace {

using detail::GridFrame;

/// Walks the cells [imin, imax] x [jmin, jmax] (cell i covers [i, i+1)) that
/// the line (u0 + s du, v0 + s dv) crosses for s in [s_lo, s_hi], calling
/// visit(i, j, sa, sb) for each cell with its parameter range, in order.
template <class Visit>
inline std::int64_t traverse(double u0, double v0, double du, double dv, double s_lo, double s_hi,
                             int imin, int imax, int jmin, int jmax, Visit&& visit) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  double us = u0 + s_lo * du, vs = v0 + s_lo * dv;
  int i = std::clamp(int(std::floor(us)), imin, imax);
  int j = std::clamp(int(std::floor(vs)), jmin, jmax);
  int step_i = du > 0.0 ? 1 : -1;
  int step_j = dv > 0.0 ? 1 : -1;
  double next_u = du != 0.0 ? ((du > 0.0 ? i + 1 : i) - u0) / du : kInf;
  double next_v = dv != 0.0 ? ((dv > 0.0 ? j + 1 : j) - v0) / dv : kInf;
  double delta_u = du != 0.0 ? std::abs(1.0 / du) : kInf;
  double delta_v = dv != 0.0 ? std::abs(1.0 / dv) : kInf;
  double s = s_lo;
  std::int64_t visited = 0;
  // Bounded by the number of cells on the way (plus slack for boundary starts).
  std::int64_t max_cells = std::int64_t(imax - imin) + (jmax - jmin) + 4;
  while (visited < max_cells) {
    double s_next = std::min(std::min(next_u, next_v), s_hi);
    visit(i, j, s, std::max(s, s_next));
    ++visited;
    if (s_next >= s_hi) break;
    s = std::max(s, s_next);
    if (next_u < next_v) {
      i += step_i;
      next_u += delta_u;
      if (i < imin || i > imax) break;
    } else {
      j += step_j;
      next_v += delta_v;
      if (j < jmin || j > jmax) break;
    }
  }
  return visited;
}

ContactResult contact_columns(const HeightGrid& grid, const Segment& edge) {
  GridFrame f(grid);
  ContactResult out;
  Vec3 d = edge.b - edge.a;
  double seg_len = length(d);
  double u0 = (edge.a.x - f.x0) * f.inv_cx, v0 = (edge.a.z - f.z0) * f.inv_cz;
  double du = d.x * f.inv_cx, dv = d.z * f.inv_cz;
  double s0 = 0.0, s1 = 1.0;
  if (!detail::clip_axis(u0, du, 0.0, f.cols, s0, s1)) return out;
  if (!detail::clip_axis(v0, dv, 0.0, f.rows, s0, s1)) return out;
  const float* h = grid.heights();
  out.cells_visited = traverse(u0, v0, du, dv, s0, s1, 0, f.cols - 1, 0, f.rows - 1,
                               [&](int c, int r, double sa, double sb) {
                                 double top = f.ground_y + h[std::int64_t(r) * f.cols + c];
                                 double ya = edge.a.y + sa * d.y, yb = edge.a.y + sb * d.y;
                                 detail::accumulate_piece(sa, sb, top, top, ya, yb, f, seg_len, out);
                               });
  return out;
}

ContactResult contact_surface(const HeightGrid& grid, const Segment& edge) {
  GridFrame f(grid);
  ContactResult out;
  Vec3 d = edge.b - edge.a;
  double seg_len = length(d);
  // Node coordinates: sample (c, r) sits at integer (c, r); the surface spans
  // [-0.5, cols - 0.5] x [-0.5, rows - 0.5] (the half-cell border is flat).
  double u0 = (edge.a.x - f.x0) * f.inv_cx - 0.5, v0 = (edge.a.z - f.z0) * f.inv_cz - 0.5;
  double du = d.x * f.inv_cx, dv = d.z * f.inv_cz;
  double s0 = 0.0, s1 = 1.0;
  if (!detail::clip_axis(u0, du, -0.5, f.cols - 0.5, s0, s1)) return out;
  if (!detail::clip_axis(v0, dv, -0.5, f.rows - 0.5, s0, s1)) return out;
  const float* h = grid.heights();
  const int cols = f.cols, rows = f.rows;
  double duv = du + dv;
  out.cells_visited = traverse(
      u0, v0, du, dv, s0, s1, -1, cols - 1, -1, rows - 1, [&](int i, int j, double sa, double sb) {
        double h00 = detail::clamped_height(h, cols, rows, i, j);
        double h10 = detail::clamped_height(h, cols, rows, i + 1, j);
        double h01 = detail::clamped_height(h, cols, rows, i, j + 1);
        double h11 = detail::clamped_height(h, cols, rows, i + 1, j + 1);
        // Split the piece where it crosses the square's diagonal a + b = 1.
        double cuts[3] = {sa, sb, sb};
        int n = 2;
        if (duv != 0.0) {
          double sd = (1.0 + i + j - u0 - v0) / duv;
          if (sd > sa && sd < sb) {
            cuts[1] = sd;
            n = 3;
          }
        }
        for (int k = 0; k + 1 < n; ++k) {
          double pa = cuts[k], pb = cuts[k + 1];
          double mid = 0.5 * (pa + pb);
          bool lower = (u0 + mid * du - i) + (v0 + mid * dv - j) <= 1.0;
          double top_a = f.ground_y + detail::surface_in_square(h00, h10, h01, h11, u0 + pa * du - i,
                                                               v0 + pa * dv - j, lower);
          double top_b = f.ground_y + detail::surface_in_square(h00, h10, h01, h11, u0 + pb * du - i,
                                                               v0 + pb * dv - j, lower);
          detail::accumulate_piece(pa, pb, top_a, top_b, edge.a.y + pa * d.y, edge.a.y + pb * d.y, f,
                                   seg_len, out);
        }
      });
  return out;
}

}  // namespace

ContactResult measure_contact(const HeightGrid& grid, Representation representation,
                              const Segment& edge) {
  if (!is_finite(edge.a) || !is_finite(edge.b)) return {};
  return representation == Representation::kColumns ? contact_columns(grid, edge)
                                                    : contact_surface(grid, edge);
}

}  // namespace terracut
