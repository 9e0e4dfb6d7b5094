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

}  // namespace terracut::haptics
