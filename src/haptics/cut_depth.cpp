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
  const double speed_xz = std::hypot(velocity_m_per_s.x, velocity_m_per_s.z);
  if (!(speed_xz > 0.0) || !std::isfinite(speed_xz) || !is_finite(edge.a) || !is_finite(edge.b) ||
      !std::isfinite(lookahead_m))
    return 0.0;
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
  return engaged > 0 ? sum / engaged : 0.0;
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
  }
  return out;
}

}  // namespace terracut::haptics
