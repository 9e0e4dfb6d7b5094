// Penetration: bearing under the edge, friction on its faces. See penetration.hpp.
#include "terracut/core/penetration.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace terracut {

BearingFactors bearing_capacity_factors(double internal_friction_deg) noexcept {
  constexpr double kPi = std::numbers::pi;
  const double phi = radians(internal_friction_deg);
  const double t = std::tan(phi);
  const double k = std::tan(0.25 * kPi + 0.5 * phi);
  BearingFactors f;
  f.n_q = std::exp(kPi * t) * k * k;
  // (N_q - 1) cot phi is 0/0 at phi = 0; its limit is pi + 2 and the
  // series N_q - 1 = (pi + 2) phi + O(phi^2) makes it continuous there.
  f.n_c = phi < 1e-7 ? kPi + 2.0 : (f.n_q - 1.0) / t;
  f.n_gamma = 2.0 * (f.n_q + 1.0) * t;
  return f;
}

PenetrationResult penetration_resistance(const SoilMaterial& soil, double edge_thickness_m,
                                         double length_m, double depth_m,
                                         double surcharge_pa) noexcept {
  PenetrationResult out;
  if (!(length_m > 0.0) || !(depth_m > 0.0)) return out;
  const double b = edge_thickness_m;
  const double gamma = soil.unit_weight_n_per_m3;
  const BearingFactors f = bearing_capacity_factors(soil.internal_friction_deg);
  const double q = gamma * depth_m + surcharge_pa;
  out.bearing_pa = soil.cohesion_pa * f.n_c + q * f.n_q + 0.5 * gamma * b * f.n_gamma;
  out.tip_n = out.bearing_pa * b * length_m * std::min(1.0, depth_m / b);
  const double k0 = 1.0 - std::sin(radians(soil.internal_friction_deg));
  out.side_n = 2.0 * length_m *
               (0.5 * k0 * gamma * depth_m * depth_m * std::tan(radians(soil.soil_tool_friction_deg)) +
                soil.adhesion_pa * depth_m);
  return out;
}

Vec3 penetration_world_force(const PenetrationResult& result, Vec3 velocity_m_per_s,
                             double low_speed_damping_n_s_per_m) noexcept {
  const double vy = velocity_m_per_s.y;
  if (vy < 0.0) return {0.0, saturated_drag_n(result.down_n(), -vy, low_speed_damping_n_s_per_m), 0.0};
  if (vy > 0.0) return {0.0, -saturated_drag_n(result.up_n(), vy, low_speed_damping_n_s_per_m), 0.0};
  return {0.0, vy == 0.0 ? 0.0 : vy, 0.0};  // NaN passes through
}

}  // namespace terracut
