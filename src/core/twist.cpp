// Twist: the resistance to turning a buried blade. See twist.hpp.
#include "terracut/core/twist.hpp"

#include <cmath>

namespace terracut {

TwistResult twist_resistance(double resistance_n_per_m, const TwistEngagement& engagement,
                             double yaw_rate_rad_per_s, double low_speed_damping_n_s_per_m,
                             double blade_length_m) noexcept {
  TwistResult out;
  const double w = yaw_rate_rad_per_s;
  if (!std::isfinite(w)) {
    out.torque_n_m = out.net_force_n = w;  // for the safety limiter to catch
    return out;
  }
  const double torque = resistance_n_per_m * engagement.abs_moment_m2;
  if (w == 0.0 || !(torque > 0.0)) return out;
  // Every part a damper of beta / blade_length per metre below saturation:
  // the torque of the whole grows as beta |omega| integral s^2 ds / L_blade.
  // Uncapped, the whole torque at any rate (inf x 0 would be NaN).
  double scale = 1.0;
  if (std::isfinite(low_speed_damping_n_s_per_m)) {
    const double rotational_damping =
        low_speed_damping_n_s_per_m * engagement.second_moment_m3 / blade_length_m;
    scale = saturated_drag_n(torque, std::abs(w), rotational_damping) / torque;
  }
  const double sense = w > 0.0 ? -1.0 : 1.0;
  out.torque_n_m = sense * torque * scale;
  out.net_force_n = sense * resistance_n_per_m * engagement.signed_length_m * scale;
  return out;
}

}  // namespace terracut
