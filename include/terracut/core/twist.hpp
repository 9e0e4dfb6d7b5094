// Twist: a buried blade turned about the vertical. Every part of the edge
// cuts sideways, so the soil resists the turn with a torque, and with a net
// force when more of the edge is engaged on one side. docs/forces.md.
#pragma once

#include "terracut/core/drag.hpp"

namespace terracut {

/// The part of the edge in soil, seen from the vertical axis through the
/// blade's centre. s is the signed horizontal distance of a point of the
/// edge from the axis along the edge; the integrals run over the engaged parts.
struct TwistEngagement {
  double engaged_length_m = 0.0;  ///< integral of ds, m, >= 0
  double abs_moment_m2 = 0.0;     ///< integral of |s| ds, m^2, >= 0
  double signed_length_m = 0.0;   ///< integral of sign(s) ds, m
  double second_moment_m3 = 0.0;  ///< integral of s^2 ds, m^3, >= 0
};

/// What turning a buried blade meets.
struct TwistResult {
  /// Torque on the tool about world +Y, N m: against the yaw rate.
  double torque_n_m = 0.0;
  /// Net force along n = Y x e (e: the edge's horizontal direction), N:
  /// nonzero when more of the edge is engaged on one side of the axis.
  double net_force_n = 0.0;
};

/// A point of the edge at s moves at omega s along n; the soil resists it
/// with f per metre of edge (the cutting force per metre of width), against
/// its motion. Summed over the engaged parts:
///   T = -sign(omega) f integral |s| ds,   F_n = -sign(omega) f integral sign(s) ds,
/// both scaled by the low-speed regularisation of the whole,
/// saturated_drag_n(f abs_moment, |omega|, beta second_moment / blade_length)
/// / (f abs_moment): below that rate each part of the edge is a damper of
/// beta / blade_length per metre. beta = kUncapped_n_s_per_m: the physical
/// torque and force. Zero yaw rate or no engagement gives zeros.
/// resistance_n_per_m >= 0, blade_length_m > 0.
TwistResult twist_resistance(double resistance_n_per_m, const TwistEngagement& engagement,
                             double yaw_rate_rad_per_s, double low_speed_damping_n_s_per_m,
                             double blade_length_m) noexcept;

}  // namespace terracut
