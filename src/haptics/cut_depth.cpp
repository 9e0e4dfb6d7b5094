#include "terracut/haptics/cut_depth.hpp"

#include <algorithm>
#include <cmath>

#include "terracut/core/forces.hpp"

namespace terracut::haptics {

double depth_lookahead_m(const GridSpec& spec) {
  return 1.5 * std::hypot(spec.cell_x_m(), spec.cell_z_m());
}

double depth_ahead_m(const HeightGrid& grid, Representation representation, const Segment& edge,
                     Vec3 velocity_m_per_s, double lookahead_m) noexcept {
  return cut_ahead(grid, representation, edge, velocity_m_per_s, lookahead_m).depth_m;
}

CutAhead cut_ahead(const HeightGrid& grid, Representation representation, const Segment& edge,
                   Vec3 velocity_m_per_s, double lookahead_m) noexcept {
  const double speed_xz = std::hypot(velocity_m_per_s.x, velocity_m_per_s.z);
  if (!(speed_xz > 0.0) || !std::isfinite(speed_xz) || !is_finite(edge.a) || !is_finite(edge.b) ||
      !std::isfinite(lookahead_m))
    return {};
  const Vec3 ahead = Vec3{velocity_m_per_s.x, 0.0, velocity_m_per_s.z} * (lookahead_m / speed_xz);
  const GridSpec& spec = grid.spec();
  const double cell = std::min(spec.cell_x_m(), spec.cell_z_m());
  const int n = std::clamp(static_cast<int>(std::ceil(length(edge.b - edge.a) / cell)), 2, 64);
  double sum = 0.0;
  int engaged = 0;
  for (int i = 0; i < n; ++i) {
    const Vec3 p = lerp(edge.a, edge.b, (i + 0.5) / n);
    const Vec3 q = p + ahead;
    const double depth = surface_y_m(grid, representation, q.x, q.z) - p.y;
    if (depth > 0.0) {
      sum += depth;
      ++engaged;
    }
  }
  if (engaged == 0) return {};
  return {sum / engaged, length(edge.b - edge.a) * engaged / n};
}

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
  const int n = std::clamp(static_cast<int>(std::ceil(length(edge.b - edge.a) / cell)), 2, 64);
  const double ground = spec.origin_m.y;
  double depth_sum = 0.0, pile_sum = 0.0;
  int engaged = 0;
  for (int i = 0; i < n; ++i) {
    const Vec3 p = lerp(edge.a, edge.b, (i + 0.5) / n);
    // The depth at the lookahead, below the undisturbed surface.
    const Vec3 q = p + u * lookahead_m;
    const double now = surface_height_m(grid, representation, q.x, q.z);
    const double before = surface_height_m(spec, grid.initial(), representation, q.x, q.z);
    const double depth = ground + std::min(now, before) - p.y;
    if (!(depth > 0.0)) continue;
    ++engaged;
    depth_sum += depth;
    // The pile over the wedge: soil above the initial surface ahead.
    const double reach_m = wedge_per_depth * depth;
    const int reach_points = std::clamp(static_cast<int>(std::ceil(reach_m / cell)), 1, 64);
    double pile = 0.0;
    for (int k = 0; k < reach_points; ++k) {
      const Vec3 r = q + u * (reach_m * (k + 0.5) / reach_points);
      pile += std::max(0.0, surface_height_m(grid, representation, r.x, r.z) -
                                surface_height_m(spec, grid.initial(), representation, r.x, r.z));
    }
    pile_sum += pile / reach_points;
  }
  if (engaged > 0) {
    out.depth_m = depth_sum / engaged;
    out.pile_m = pile_sum / engaged;
    out.width_m = length(edge.b - edge.a) * engaged / n;
  }
  return out;
}

namespace {

// The number of parts depth_ahead_m divides an edge into.
int edge_parts(const GridSpec& spec, const Segment& edge) {
  const double cell = std::min(spec.cell_x_m(), spec.cell_z_m());
  return std::clamp(static_cast<int>(std::ceil(length(edge.b - edge.a) / cell)), 2, 64);
}

}  // namespace

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
  double sum = 0.0;
  int engaged = 0;
  for (int i = 0; i < n; ++i) {
    const Vec3 p = lerp(edge.a, edge.b, (i + 0.5) / n);
    double beside = 0.0;
    for (int k = 0; k < side_count; ++k)
      beside += surface_y_m(grid, representation, p.x + sides[k].x, p.z + sides[k].z);
    const double depth = beside / side_count - p.y;
    if (depth > 0.0) {
      sum += depth;
      ++engaged;
    }
  }
  if (engaged > 0) {
    out.depth_m = sum / engaged;
    out.length_m = length(e) * engaged / n;
  }
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

}  // namespace terracut::haptics
