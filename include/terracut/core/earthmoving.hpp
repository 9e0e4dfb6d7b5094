// The cutting force: the Fundamental Earthmoving Equation (Reece 1964) in
// McKyes' formulation (McKyes 1985, "Soil Cutting and Tillage", ch. 4) for a
// flat blade of width w at rake angle alpha cutting depth d, with the side
// failure of a blade of finite width (the crescents of McKyes & Ali 1977)
// and a surcharge q on the soil's surface (a pile the blade pushes).
//
// The central wedge: the soil ahead of the face fails along a plane at beta
// from the horizontal. The side crescents: beyond each end of the blade the
// wedge's section ahead of the tip, turned a quarter turn about the vertical
// through the tip's end, fails with it; each element of a crescent adds its
// weight, its surcharge and the cohesion on its failure surface resolved
// along the travel, which gives, for both ends together (r = d cot beta),
//   weight   gamma d^3 cot^2 beta / 3,   surcharge   q d^2 cot^2 beta,
//   cohesion c d^2 cot beta (1 + cot beta cot(beta + phi)),
// beside the central wedge's (gamma d^2 / 2 + q d) w (cot alpha + cot beta)
// and c w d (1 + cot beta cot(beta + phi)). For a vertical blade these are
// McKyes & Ali's terms with their crescent angle at 90 degrees; as w / d
// grows they vanish against the central wedge's and the force tends to the
// 2-D equation. beta* minimises the total (the passive-failure criterion).
// docs/forces.md derives it and gives its sources.
//
// Units: SI; angles in degrees in the parameters (the scenario's), radians
// for the failure-plane angle found. Nothing allocated or thrown.
#pragma once

#include <string>

#include "terracut/core/drag.hpp"
#include "terracut/core/material.hpp"
#include "terracut/core/math.hpp"

namespace terracut {

/// Parameters of the cutting force; read-only during a run.
struct EarthmovingParams {
  SoilMaterial soil{};
  /// alpha: rake angle of the blade face from the horizontal, degrees, in
  /// (0, 180); 90 is a vertical plate. The tip leads and the face leans back
  /// over the cut soil for alpha < 90. Needs alpha + delta + phi < 179.
  double rake_angle_deg = 90.0;
  /// Add the side crescents of a blade of finite width (McKyes & Ali 1977);
  /// false: the 2-D equation times the width.
  bool side_failure = true;
};

/// The ranges of EarthmovingParams' own numbers (core/ranges.hpp; the
/// soil's: material_ranges()). The blade's rake (SimParams' blade.rake_angle_deg,
/// kSimParamsRanges) is this entry.
inline constexpr Range kEarthmovingRanges[] = {
    {"rake_angle_deg", 0.0, 180.0, RangeEnds::kOpen},
};

/// Returns an empty string when params are valid, else a message naming the
/// field ("rake_angle_deg ...", "soil.internal_friction_deg ...").
std::string validate(const EarthmovingParams& params);

/// The dimensionless factors at one failure-plane angle beta (rad) for a
/// blade of width_m cutting depth_m, such that
///   P = (gamma d^2 N_gamma + c d N_c + c_a d N_a + q d N_q) w.
/// With D = cos(alpha+delta) + sin(alpha+delta) cot(beta+phi) and s = 1 with
/// side failure (0 without):
///   N_gamma = [(cot alpha + cot beta) / 2 + s d cot^2 beta / (3 w)] / D
///   N_c     = (1 + cot beta cot(beta+phi)) (1 + s d cot beta / w) / D
///   N_a     = (1 - cot alpha cot(beta+phi)) / D
///   N_q     = [(cot alpha + cot beta) + s d cot^2 beta / w] / D
/// (without side failure McKyes' 2-D factors, N_q = 2 N_gamma). width_m > 0.
struct EarthmovingFactors {
  double n_gamma = 0.0;
  double n_c = 0.0;
  double n_a = 0.0;
  double n_q = 0.0;
};
EarthmovingFactors earthmoving_factors(const EarthmovingParams& params, double beta_rad,
                                       double width_m, double depth_m) noexcept;

/// P(beta), newtons, for the blade, the depth and a surcharge q (Pa).
double earthmoving_total_n(const EarthmovingParams& params, double width_m, double depth_m,
                           double beta_rad, double surcharge_pa = 0.0) noexcept;

/// Open range of failure-plane angles with a valid wedge, rad:
/// (0, min(pi/2, pi - alpha - delta - phi)).
struct BetaRange {
  double lo_rad = 0.0;
  double hi_rad = 0.0;
};
BetaRange earthmoving_beta_range(const EarthmovingParams& params) noexcept;

/// The cutting force for one cut.
struct EarthmovingResult {
  /// P: the soil's resultant on the blade face, at delta to its normal,
  /// excluding adhesion; N, >= 0 in valid cases.
  double total_n = 0.0;
  /// H = P sin(alpha+delta) + c_a d w cot(alpha): horizontal force resisting
  /// the motion, N.
  double horizontal_n = 0.0;
  /// V = P cos(alpha+delta) - c_a d w: vertical force, positive when it
  /// pushes the blade DOWN (McKyes' sign), N. A vertical rough blade is
  /// lifted (V < 0); a raked one is drawn in.
  double vertical_n = 0.0;
  /// The surcharge's part of P, H and V (q's terms at beta*), N: what the
  /// pile ahead adds. Zero without a surcharge.
  double surcharge_total_n = 0.0;
  double surcharge_horizontal_n = 0.0;
  double surcharge_vertical_n = 0.0;
  /// The side crescents' part of P at beta*, N (zero without side failure).
  double side_total_n = 0.0;
  /// beta*: the failure-plane angle that minimises P, rad.
  double beta_rad = 0.0;
  EarthmovingFactors factors{};  ///< at beta*
};

/// The force for a blade of width_m (the engaged width across the motion)
/// at depth_m (the depth of undisturbed soil ahead of the edge) with a
/// surcharge surcharge_pa (>= 0) on the surface ahead. beta* by a 48-point
/// scan then a golden-section search to 1e-10 rad, the open ends kept 1e-4
/// rad away (the pi/2 end included). Width or depth <= 0 gives zeros.
/// Parameters are trusted (validate once).
EarthmovingResult earthmoving_force(const EarthmovingParams& params, double width_m,
                                    double depth_m, double surcharge_pa = 0.0) noexcept;

/// World force on the blade from a result and the blade's world velocity:
/// -H_s u - V_s Y, u the unit horizontal direction of motion and
/// (H_s, V_s) = (H, V) saturated_drag_n(H, |v_xz|, beta) / H (the low-speed
/// regularisation keeps the direction). With beta = kUncapped_n_s_per_m it
/// is the physical force: -H u - V Y whenever the blade moves horizontally.
/// No horizontal motion gives zero force.
Vec3 earthmoving_world_force(const EarthmovingResult& result, Vec3 velocity_m_per_s,
                             double low_speed_damping_n_s_per_m) noexcept;

}  // namespace terracut
