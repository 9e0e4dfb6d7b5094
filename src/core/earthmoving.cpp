// The cutting force: McKyes' earthmoving equation with McKyes & Ali's side
// crescents. Derivation and sources: docs/forces.md.
#include "terracut/core/earthmoving.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "terracut/core/format.hpp"

namespace terracut {

namespace {

constexpr double kPi = std::numbers::pi;

double cot(double angle_rad) { return std::cos(angle_rad) / std::sin(angle_rad); }

// The pieces of P(beta) that do not depend on beta, computed once per cut.
struct WedgeConstants {
  double cot_alpha;
  double sin_ad;  // sin(alpha + delta)
  double cos_ad;  // cos(alpha + delta)
  double phi;
  double weight;         // (gamma d^2 / 2 + q d) w: multiplies (cot alpha + cot beta)
  double side_weight;    // gamma d^3 / 3 + q d^2 (both crescents): multiplies cot^2 beta
  double cohesion;       // c d w: multiplies (1 + cot beta cot(beta + phi))
  double side_cohesion;  // c d^2: multiplies cot beta (1 + cot beta cot(beta + phi))
  double adhesion;       // c_a d w: multiplies (1 - cot alpha cot(beta + phi))
  double surcharge;      // q d w: the surcharge's part of weight
  double side_surcharge;  // q d^2: the surcharge's part of side_weight

  WedgeConstants(const EarthmovingParams& p, double w, double d, double q)
      : cot_alpha(cot(radians(p.rake_angle_deg))),
        sin_ad(std::sin(radians(p.rake_angle_deg + p.soil.soil_tool_friction_deg))),
        cos_ad(std::cos(radians(p.rake_angle_deg + p.soil.soil_tool_friction_deg))),
        phi(radians(p.soil.internal_friction_deg)),
        weight((0.5 * p.soil.unit_weight_n_per_m3 * d * d + q * d) * w),
        side_weight(p.side_failure ? p.soil.unit_weight_n_per_m3 * d * d * d / 3.0 + q * d * d : 0.0),
        cohesion(p.soil.cohesion_pa * d * w),
        side_cohesion(p.side_failure ? p.soil.cohesion_pa * d * d : 0.0),
        adhesion(p.soil.adhesion_pa * d * w),
        surcharge(q * d * w),
        side_surcharge(p.side_failure ? q * d * d : 0.0) {}

  double denominator(double cot_bp) const { return cos_ad + sin_ad * cot_bp; }

  // P(beta): the wedge's and the crescents' loads over D.
  double total(double beta) const {
    const double cot_b = cot(beta);
    const double cot_bp = cot(beta + phi);
    const double shear = 1.0 + cot_b * cot_bp;
    return (weight * (cot_alpha + cot_b) + side_weight * cot_b * cot_b + cohesion * shear +
            side_cohesion * cot_b * shear + adhesion * (1.0 - cot_alpha * cot_bp)) /
           denominator(cot_bp);
  }
  // The surcharge's part of P(beta).
  double surcharge_part(double beta) const {
    const double cot_b = cot(beta);
    return (surcharge * (cot_alpha + cot_b) + side_surcharge * cot_b * cot_b) /
           denominator(cot(beta + phi));
  }
  // The crescents' part of P(beta).
  double side_part(double beta) const {
    const double cot_b = cot(beta);
    const double cot_bp = cot(beta + phi);
    return (side_weight * cot_b * cot_b + side_cohesion * cot_b * (1.0 + cot_b * cot_bp)) /
           denominator(cot_bp);
  }
};

}  // namespace

std::string validate(const EarthmovingParams& params) {
  if (std::string m = validate(params.soil); !m.empty()) return "soil." + m;
  if (std::string m = check(find_range(kEarthmovingRanges, "rake_angle_deg"), params.rake_angle_deg);
      !m.empty())
    return m;
  // A planar wedge needs a failure-plane angle with D > 0: beta < 180 - alpha
  // - delta - phi. Ask for at least one degree of room.
  const double sum = params.rake_angle_deg + params.soil.soil_tool_friction_deg +
                     params.soil.internal_friction_deg;
  if (!(sum <= 179.0))
    return must_be("rake_angle_deg + soil.soil_tool_friction_deg + soil.internal_friction_deg",
                   "at most 179", sum) +
           " deg: no planar failure wedge exists";
  return {};
}

EarthmovingFactors earthmoving_factors(const EarthmovingParams& params, double beta_rad,
                                       double width_m, double depth_m) noexcept {
  const double alpha = radians(params.rake_angle_deg);
  const double delta = radians(params.soil.soil_tool_friction_deg);
  const double phi = radians(params.soil.internal_friction_deg);
  const double cot_a = cot(alpha), cot_b = cot(beta_rad), cot_bp = cot(beta_rad + phi);
  const double d = std::cos(alpha + delta) + std::sin(alpha + delta) * cot_bp;
  const double s = params.side_failure ? depth_m / width_m : 0.0;
  EarthmovingFactors f;
  f.n_gamma = (0.5 * (cot_a + cot_b) + s * cot_b * cot_b / 3.0) / d;
  f.n_c = (1.0 + cot_b * cot_bp) * (1.0 + s * cot_b) / d;
  f.n_a = (1.0 - cot_a * cot_bp) / d;
  f.n_q = ((cot_a + cot_b) + s * cot_b * cot_b) / d;
  return f;
}

double earthmoving_total_n(const EarthmovingParams& params, double width_m, double depth_m,
                           double beta_rad, double surcharge_pa) noexcept {
  return WedgeConstants(params, width_m, depth_m, surcharge_pa).total(beta_rad);
}

BetaRange earthmoving_beta_range(const EarthmovingParams& params) noexcept {
  const double hi = std::min(kPi / 2, kPi - radians(params.rake_angle_deg +
                                                    params.soil.soil_tool_friction_deg +
                                                    params.soil.internal_friction_deg));
  return {0.0, hi};
}

EarthmovingResult earthmoving_force(const EarthmovingParams& params, double width_m,
                                    double depth_m, double surcharge_pa) noexcept {
  EarthmovingResult out;
  if (!(width_m > 0.0) || !(depth_m > 0.0)) return out;
  const WedgeConstants wedge(params, width_m, depth_m, surcharge_pa);

  // Search inside the open range; P grows without bound at both ends in the
  // usual cases (cot beta -> inf at 0, D -> 0 at pi - alpha - delta - phi),
  // but may be smallest at the pi/2 end, which the closed search includes.
  const BetaRange range = earthmoving_beta_range(params);
  constexpr double kEdge = 1e-4;  // rad kept clear of the open ends (rounding near 0/0)
  const double lo = range.lo_rad + kEdge;
  const double hi = range.hi_rad == kPi / 2 ? range.hi_rad : range.hi_rad - kEdge;

  // Coarse scan for the basin of the global minimum.
  constexpr int kScan = 48;
  const double step = (hi - lo) / (kScan - 1);
  int best = 0;
  double best_p = wedge.total(lo);
  for (int k = 1; k < kScan; ++k) {
    const double p = wedge.total(lo + k * step);
    if (p < best_p) {
      best_p = p;
      best = k;
    }
  }

  // Golden-section search in the bracket of the best sample's neighbours.
  double a = lo + std::max(best - 1, 0) * step;
  double b = lo + std::min(best + 1, kScan - 1) * step;
  constexpr double kInvPhi = 0.6180339887498949;  // (sqrt(5) - 1) / 2
  double x1 = b - kInvPhi * (b - a), x2 = a + kInvPhi * (b - a);
  double f1 = wedge.total(x1), f2 = wedge.total(x2);
  for (int iter = 0; iter < 200 && b - a > 1e-10; ++iter) {
    if (f1 <= f2) {
      b = x2;
      x2 = x1;
      f2 = f1;
      x1 = b - kInvPhi * (b - a);
      f1 = wedge.total(x1);
    } else {
      a = x1;
      x1 = x2;
      f1 = f2;
      x2 = a + kInvPhi * (b - a);
      f2 = wedge.total(x2);
    }
  }
  double beta = f1 <= f2 ? x1 : x2;
  double p = std::min(f1, f2);
  // The scan's best sample can beat the bracket's interior at a range end.
  if (best_p < p) {
    p = best_p;
    beta = lo + best * step;
  }

  // Resolve the face force and the adhesion (c_a w d / sin alpha along the
  // face) into horizontal and vertical components (docs/forces.md).
  const double adhesion = params.soil.adhesion_pa * depth_m * width_m;
  out.total_n = p;
  out.beta_rad = beta;
  out.factors = earthmoving_factors(params, beta, width_m, depth_m);
  out.horizontal_n = p * wedge.sin_ad + adhesion * wedge.cot_alpha;
  out.vertical_n = p * wedge.cos_ad - adhesion;
  if (surcharge_pa > 0.0) {
    out.surcharge_total_n = wedge.surcharge_part(beta);
    out.surcharge_horizontal_n = out.surcharge_total_n * wedge.sin_ad;
    out.surcharge_vertical_n = out.surcharge_total_n * wedge.cos_ad;
  }
  out.side_total_n = params.side_failure ? wedge.side_part(beta) : 0.0;
  return out;
}

Vec3 earthmoving_world_force(const EarthmovingResult& result, Vec3 velocity_m_per_s,
                             double low_speed_damping_n_s_per_m) noexcept {
  const double speed = std::hypot(velocity_m_per_s.x, velocity_m_per_s.z);
  const double h = std::abs(result.horizontal_n);
  if (speed == 0.0 || h == 0.0) return {};
  const double scale = saturated_drag_n(h, speed, low_speed_damping_n_s_per_m) / h;
  const double ux = velocity_m_per_s.x / speed, uz = velocity_m_per_s.z / speed;
  const double hs = result.horizontal_n * scale;
  return {-hs * ux, -result.vertical_n * scale, -hs * uz};
}

}  // namespace terracut
