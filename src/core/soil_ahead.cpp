#include "terracut/core/soil_ahead.hpp"

#include <algorithm>
#include <cmath>

#include "terracut/core/surface.hpp"
#include "geometry.hpp"

namespace terracut {

double depth_lookahead_m(const GridSpec& spec) {
  return 1.5 * std::hypot(spec.cell_x_m(), spec.cell_z_m());
}

namespace {

// The number of parts an edge is read at.
int edge_parts(const GridSpec& spec, const Segment& edge) {
  const double cell = std::min(spec.cell_x_m(), spec.cell_z_m());
  // (Clamped in double: a finite edge may be far longer than INT_MAX cells.)
  return static_cast<int>(std::clamp(std::ceil(length(edge.b - edge.a) / cell), 2.0, 64.0));
}

// The depth and length of a uniform cut equivalent to the parts' depths d_i
// (each of length `part`): the same sum of d (the cut's section, on which the
// cohesive and surcharge terms grow) and of d^2 (on which the weight term
// grows): depth = sum d^2 / sum d, length = part (sum d)^2 / sum d^2. A part
// at zero depth adds nothing to either, so the force stays continuous as
// parts come into or out of the soil; a uniform cut is itself.
void equivalent_cut(double sum_d, double sum_d2, double part, double& depth_m, double& length_m) {
  if (!(sum_d > 0.0) || !(sum_d2 > 0.0)) return;
  depth_m = sum_d2 / sum_d;
  length_m = part * sum_d * sum_d / sum_d2;
}

}  // namespace

SoilAhead soil_ahead(const HeightGrid& grid, Representation representation, const Segment& edge,
                     Vec3 velocity_m_per_s, double lookahead_m, double wedge_per_depth) noexcept {
  SoilAhead out;
  const double speed_xz = std::hypot(velocity_m_per_s.x, velocity_m_per_s.z);
  if (!(speed_xz > 0.0) || !std::isfinite(speed_xz) || !is_finite(edge.a) || !is_finite(edge.b) ||
      !std::isfinite(lookahead_m) || !std::isfinite(wedge_per_depth))
    return out;
  const Vec3 u = Vec3{velocity_m_per_s.x, 0.0, velocity_m_per_s.z} * (1.0 / speed_xz);
  const GridSpec& spec = grid.spec();
  const double cell = std::min(spec.cell_x_m(), spec.cell_z_m());
  const int n = edge_parts(spec, edge);
  // The parts' length in plan: the wedge is read as finely along the
  // motion as across it (one point a cell, or a part's length where the
  // parts are longer: on a 1 m edge of 64 parts over 5 mm cells, 15.6 mm).
  // Finer along than across buys no accuracy (the coarser spacing sets the
  // quadrature's error) and cost two thirds of the step's force there.
  const double part_m = std::hypot(edge.b.x - edge.a.x, edge.b.z - edge.a.z) / n;
  const double ground = spec.origin_m.y;
  const float* now_m = grid.heights();
  const float* initial_m = grid.initial();
  double sum_d = 0.0, sum_d2 = 0.0, sum_pile_d = 0.0;
  for (int i = 0; i < n; ++i) {
    const Vec3 p = lerp(edge.a, edge.b, (i + 0.5) / n);
    // The depth at the lookahead, below the undisturbed surface.
    const Vec3 q = p + u * lookahead_m;
    const auto [now, before] = surface_heights_m(spec, grid.heights(), grid.initial(), representation, q.x, q.z);
    const double depth = ground + std::min(now, before) - p.y;
    if (!(depth > 0.0)) continue;
    sum_d += depth;
    sum_d2 += depth * depth;
    // The pile over the wedge: soil above the initial surface ahead.
    if (!(wedge_per_depth > 0.0)) continue;
    const double reach_m = wedge_per_depth * depth;
    const int reach_points = static_cast<int>(std::clamp(std::ceil(reach_m / std::max(cell, part_m)), 1.0, 64.0));
    // The points q + u reach (k + 1/2) / reach_points, walked in cell
    // coordinates (the same points to rounding, without two divisions each).
    const double qu = (q.x - spec.origin_m.x) / spec.cell_x_m(), qv = (q.z - spec.origin_m.z) / spec.cell_z_m();
    const double spacing = reach_m / reach_points;
    const double du = u.x * spacing / spec.cell_x_m(), dv = u.z * spacing / spec.cell_z_m();
    // Whether every point lies where the surface needs no clamp (the walk
    // is straight: its ends decide, with a margin for their rounding).
    const auto clear = [&](double t) {
      const double pu = qu + du * t, pv = qv + dv * t;
      return pu >= 0.5 + 1e-6 && pu < spec.cols - 0.5 - 1e-6 && pv >= 0.5 + 1e-6 && pv < spec.rows - 0.5 - 1e-6;
    };
    const bool interior = representation == Representation::kSurface && clear(0.5) && clear(reach_points - 0.5);
    double pile = 0.0;
    for (int k = 0; k < reach_points; ++k) {
      const double t = k + 0.5;
      const double pu = qu + du * t, pv = qv + dv * t;
      const detail::SurfacePoint r = interior ? detail::SurfacePoint::interior(spec.cols, pu, pv)
                                              : detail::SurfacePoint(spec.cols, spec.rows, representation, pu, pv);
      pile += std::max(0.0, r.height(now_m) - r.height(initial_m));
    }
    // Weighted by the part's depth: the surcharge acts on q d w.
    sum_pile_d += depth * pile / reach_points;
  }
  equivalent_cut(sum_d, sum_d2, length(edge.b - edge.a) / n, out.depth_m, out.width_m);
  if (sum_d > 0.0) out.pile_m = sum_pile_d / sum_d;
  return out;
}

Embedment embedment(const HeightGrid& grid, Representation representation, const Segment& edge,
                    double lookahead_m) noexcept {
  Embedment out;
  if (!is_finite(edge.a) || !is_finite(edge.b) || !std::isfinite(lookahead_m)) return out;
  const Vec3 e = edge.b - edge.a;
  const double eh = std::hypot(e.x, e.z);
  // The sides to read: the two faces, or four directions for a vertical edge.
  Vec3 sides[4];
  int side_count = 0;
  if (eh > 1e-9 * std::max(length(e), 1e-300)) {
    const Vec3 n{e.z / eh, 0.0, -e.x / eh};
    sides[0] = n * lookahead_m;
    sides[1] = n * -lookahead_m;
    side_count = 2;
  } else {
    sides[0] = {lookahead_m, 0.0, 0.0};
    sides[1] = {-lookahead_m, 0.0, 0.0};
    sides[2] = {0.0, 0.0, lookahead_m};
    sides[3] = {0.0, 0.0, -lookahead_m};
    side_count = 4;
  }
  const int n = edge_parts(grid.spec(), edge);
  double sum_d = 0.0, sum_d2 = 0.0;
  for (int i = 0; i < n; ++i) {
    const Vec3 p = lerp(edge.a, edge.b, (i + 0.5) / n);
    double beside = 0.0;
    for (int k = 0; k < side_count; ++k)
      beside += surface_y_m(grid, representation, p.x + sides[k].x, p.z + sides[k].z);
    const double depth = beside / side_count - p.y;
    if (depth > 0.0) {
      sum_d += depth;
      sum_d2 += depth * depth;
    }
  }
  equivalent_cut(sum_d, sum_d2, length(e) / n, out.depth_m, out.length_m);
  return out;
}

TwistEngagement twist_engagement(const HeightGrid& grid, Representation representation,
                                 const Segment& edge, Vec3 centre, double yaw_rate_rad_per_s,
                                 double lookahead_m, double& mean_depth_m) noexcept {
  TwistEngagement out;
  mean_depth_m = 0.0;
  const Vec3 e = edge.b - edge.a;
  const double eh = std::hypot(e.x, e.z);
  if (yaw_rate_rad_per_s == 0.0 || !std::isfinite(yaw_rate_rad_per_s) || !is_finite(edge.a) ||
      !is_finite(edge.b) || !is_finite(centre) || !std::isfinite(lookahead_m) || !(eh > 0.0))
    return out;
  const Vec3 u{e.x / eh, 0.0, e.z / eh};  // the edge's horizontal direction
  const Vec3 n{u.z, 0.0, -u.x};           // Y x u
  const int parts = edge_parts(grid.spec(), edge);
  const double ds = eh / parts;  // horizontal length of a part
  const double turn = yaw_rate_rad_per_s > 0.0 ? 1.0 : -1.0;
  double depth_sum = 0.0;
  for (int i = 0; i < parts; ++i) {
    const Vec3 p = lerp(edge.a, edge.b, (i + 0.5) / parts);
    const double s = (p.x - centre.x) * u.x + (p.z - centre.z) * u.z;
    if (s == 0.0) continue;
    const double along = turn * (s > 0.0 ? 1.0 : -1.0) * lookahead_m;  // the motion's side
    const double depth = surface_y_m(grid, representation, p.x + n.x * along, p.z + n.z * along) - p.y;
    if (!(depth > 0.0)) continue;
    // The part spans [s - ds/2, s + ds/2]; its integrals at its centre.
    out.engaged_length_m += ds;
    out.abs_moment_m2 += std::abs(s) * ds;
    out.signed_length_m += (s > 0.0 ? ds : -ds);
    out.second_moment_m3 += (s * s + ds * ds / 12.0) * ds;
    depth_sum += depth;
  }
  if (out.engaged_length_m > 0.0) mean_depth_m = depth_sum / (out.engaged_length_m / ds);
  return out;
}

}  // namespace terracut
