// Penetration: an edge pushed down into the soil meets the soil's bearing
// capacity under it (Terzaghi 1943 with Prandtl's, Reissner's and Vesic's
// factors) and the friction and adhesion on its faces (Jaky's earth pressure
// at rest). docs/forces.md derives it and gives its sources.
#pragma once

#include "terracut/core/drag.hpp"
#include "terracut/core/material.hpp"
#include "terracut/core/math.hpp"

namespace terracut {

/// Bearing-capacity factors of a strip footing (dimensionless):
///   N_q     = e^(pi tan phi) tan^2(45 deg + phi/2)   (Prandtl 1921, Reissner 1924)
///   N_c     = (N_q - 1) cot phi, -> pi + 2 as phi -> 0 (Prandtl)
///   N_gamma = 2 (N_q + 1) tan phi                     (Vesic 1973)
/// phi: internal friction angle, degrees, [0, 90).
struct BearingFactors {
  double n_c = 0.0;
  double n_q = 0.0;
  double n_gamma = 0.0;
};
BearingFactors bearing_capacity_factors(double internal_friction_deg) noexcept;

/// What the soil opposes to an edge of engaged length L at embedment depth D.
struct PenetrationResult {
  /// q_ult = c N_c + q N_q + gamma B N_gamma / 2 with q = gamma D + surcharge:
  /// Terzaghi's (1943) bearing capacity of a strip at depth D, Pa.
  double bearing_pa = 0.0;
  /// Tip: q_ult B L min(1, D / B), N (the bearing mobilised over the first B of depth).
  double tip_n = 0.0;
  /// Both faces: 2 L (K0 gamma D^2 tan(delta) / 2 + c_a D), K0 = 1 - sin phi
  /// (Jaky's earth pressure at rest): skin friction and adhesion, N.
  double side_n = 0.0;
  /// Resistance to pushing down (tip and faces), N, >= 0.
  double down_n() const { return tip_n + side_n; }
  /// Resistance to pulling out (the faces only), N, >= 0.
  double up_n() const { return side_n; }
};

/// The resistance of the soil to an edge of thickness edge_thickness_m
/// (B, > 0) and engaged length length_m at embedment depth depth_m (the
/// edge's depth below the soil beside it), with a surcharge surcharge_pa on
/// the soil around it. Zero when length or depth is <= 0.
PenetrationResult penetration_resistance(const SoilMaterial& soil, double edge_thickness_m,
                                         double length_m, double depth_m,
                                         double surcharge_pa = 0.0) noexcept;

/// World force from a penetration result: moving down (v_y < 0),
/// +saturated_drag_n(down_n, |v_y|, beta) Y; moving up,
/// -saturated_drag_n(up_n, v_y, beta) Y; zero at v_y = 0. Horizontal motion
/// does not enter. beta = kUncapped_n_s_per_m gives the physical force.
Vec3 penetration_world_force(const PenetrationResult& result, Vec3 velocity_m_per_s,
                             double low_speed_damping_n_s_per_m) noexcept;

}  // namespace terracut
