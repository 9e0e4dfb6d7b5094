// Force models: contact drag, the Fundamental Earthmoving Equation (McKyes'
// formulation), the surface proxy, and their device-checked combination.
// Derivations and sources: docs/forces.md.
#include "terracut/core/forces.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "geometry.hpp"
#include "terracut/core/error.hpp"
#include "terracut/core/format.hpp"

namespace terracut {

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180.0;

// "FIELD must be ..., got VALUE" for the derived fields, or "".
std::string check_positive(const std::string& field, double value) {
  if (std::isfinite(value) && value > 0.0) return {};
  return must_be(field, "finite and > 0", value);
}

// The ranges of the fields a scenario's haptics.forces sets (the derived
// ones, set by the session, are checked by validate(ForceModelParams) alone).
constexpr Range kRanges[] = {
    {"force_scale", 0.0, kRangeMax, RangeEnds::kOpenLow},
    {"low_speed_damping_n_s_per_m", 0.0, kRangeMax, RangeEnds::kOpenLow},
    {"penetration.edge_thickness_m", 0.0, kRangeMax, RangeEnds::kOpenLow},
    {"contact_drag.drag_n_per_m", 0.0, kRangeMax, RangeEnds::kClosed},
    {"contact_drag.viscous_n_s_per_m2", 0.0, kRangeMax, RangeEnds::kClosed},
    {"earthmoving.soil.unit_weight_n_per_m3", 0.0, kRangeMax, RangeEnds::kOpenLow},
    {"earthmoving.soil.cohesion_pa", 0.0, kRangeMax, RangeEnds::kClosed},
    {"earthmoving.soil.adhesion_pa", 0.0, kRangeMax, RangeEnds::kClosed},
    {"earthmoving.soil.internal_friction_rad", 0.0, kPi / 2, RangeEnds::kOpenHigh},
    {"earthmoving.soil.soil_tool_friction_rad", 0.0, kPi / 2, RangeEnds::kOpenHigh},
    {"earthmoving.soil.surcharge_pa", 0.0, kRangeMax, RangeEnds::kClosed},
    {"earthmoving.rake_angle_rad", 0.0, kPi, RangeEnds::kOpen},
    {"surface.stiffness_n_per_m", 0.0, kRangeMax, RangeEnds::kOpenLow},
    {"surface.damping_n_s_per_m", 0.0, kRangeMax, RangeEnds::kClosed},
    {"device.max_force_n", 0.0, kRangeMax, RangeEnds::kOpenLow},
    {"device.max_stiffness_n_per_m", 0.0, kRangeMax, RangeEnds::kOpenLow},
    {"device.max_damping_n_s_per_m", 0.0, kRangeMax, RangeEnds::kOpenLow},
    {"device.inherent_damping_n_s_per_m", 0.0, kRangeMax, RangeEnds::kOpenLow},
};

// The check of field (its name in its own struct) by its entry at
// struct_path + field: "FIELD must be ..., got VALUE" or "". An angle's
// message gives it in degrees too.
std::string check_entry(std::string_view struct_path, std::string_view field, double value) {
  const Range& r = find_range(kRanges, std::string(struct_path) + std::string(field));
  std::string m = check(r, value, field);
  if (!m.empty() && field.ends_with("_rad"))
    m += " rad = " + format_number(value / kDeg) + " deg";
  return m;
}

// Prefixes a sub-structure's message with its field name.
std::string nested(const std::string& prefix, const std::string& message) {
  return message.empty() ? message : prefix + "." + message;
}

double cot(double angle_rad) { return std::cos(angle_rad) / std::sin(angle_rad); }

// The pieces of P(beta) that do not depend on beta, computed once per cut.
struct WedgeConstants {
  double cot_alpha;
  double sin_ad;  // sin(alpha + delta)
  double cos_ad;  // cos(alpha + delta)
  double phi;
  double weight;    // (gamma d^2 / 2 + q d) w: multiplies (cot alpha + cot beta)
  double cohesion;  // c d w: multiplies (1 + cot beta cot(beta + phi))
  double adhesion;  // c_a d w: multiplies (1 - cot alpha cot(beta + phi))

  WedgeConstants(const EarthmovingParams& p, double width_m, double depth_m)
      : cot_alpha(cot(p.rake_angle_rad)),
        sin_ad(std::sin(p.rake_angle_rad + p.soil.soil_tool_friction_rad)),
        cos_ad(std::cos(p.rake_angle_rad + p.soil.soil_tool_friction_rad)),
        phi(p.soil.internal_friction_rad),
        weight((0.5 * p.soil.unit_weight_n_per_m3 * depth_m * depth_m +
                p.soil.surcharge_pa * depth_m) *
               width_m),
        cohesion(p.soil.cohesion_pa * depth_m * width_m),
        adhesion(p.soil.adhesion_pa * depth_m * width_m) {}

  // P(beta) = [weight (cot a + cot b) + cohesion (1 + cot b cot(b+phi))
  //            + adhesion (1 - cot a cot(b+phi))] / D,
  // D = cos(a+d) + sin(a+d) cot(b+phi).
  double total(double beta) const {
    double cot_b = cot(beta);
    double cot_bp = cot(beta + phi);
    double d = cos_ad + sin_ad * cot_bp;
    return (weight * (cot_alpha + cot_b) + cohesion * (1.0 + cot_b * cot_bp) +
            adhesion * (1.0 - cot_alpha * cot_bp)) /
           d;
  }
};

}  // namespace

// ---------------------------------------------------------------------------
// Low-speed regularisation and contact drag
// ---------------------------------------------------------------------------

double saturated_drag_n(double force_n, double speed_m_per_s,
                        double low_speed_damping_n_s_per_m) noexcept {
  if (speed_m_per_s == 0.0) return 0.0;
  double ramp = low_speed_damping_n_s_per_m * speed_m_per_s;
  return ramp < force_n ? ramp : force_n;
}

std::string validate(const ContactDragParams& params) {
  if (auto m = check_entry("contact_drag.", "drag_n_per_m", params.drag_n_per_m); !m.empty())
    return m;
  return check_entry("contact_drag.", "viscous_n_s_per_m2", params.viscous_n_s_per_m2);
}

Vec3 contact_drag_force(const ContactDragParams& params, double contact_length_m,
                        Vec3 velocity_m_per_s, double low_speed_damping_n_s_per_m) noexcept {
  // Negative lengths count as no contact; NaN passes through to the output.
  double contact = contact_length_m < 0.0 ? 0.0 : contact_length_m;
  double speed = length(velocity_m_per_s);
  if (speed == 0.0) return {};
  double drag = saturated_drag_n(params.drag_n_per_m * contact, speed, low_speed_damping_n_s_per_m);
  return velocity_m_per_s * (-drag / speed - params.viscous_n_s_per_m2 * contact);
}

// ---------------------------------------------------------------------------
// Earthmoving
// ---------------------------------------------------------------------------

SoilParams soil_preset(SoilPreset preset) {
  SoilParams soil;
  switch (preset) {
    case SoilPreset::kDrySand:
      // Strength of Wong's LETE sand; unit weight midway between Das' loose
      // (14.5) and dense (18.0) uniform sand.
      soil.unit_weight_n_per_m3 = 16.25e3;
      soil.cohesion_pa = 1.3e3;
      soil.adhesion_pa = 0.0;
      soil.internal_friction_rad = 31.1 * kDeg;
      break;
    case SoilPreset::kLooseSand:
      // Wong's "dry sand (Land Locomotion Lab.)"; Das' loose uniform sand.
      soil.unit_weight_n_per_m3 = 14.5e3;
      soil.cohesion_pa = 1.04e3;
      soil.adhesion_pa = 0.0;
      soil.internal_friction_rad = 28.0 * kDeg;
      break;
    case SoilPreset::kClay:
      // Wong's "clayey soil (Thailand)" at 38 % moisture; moist unit weight
      // from Das' soft-clay dry unit weight (11.5-14.5, midpoint 13.0) times
      // (1 + 0.38); adhesion assumed half the cohesion.
      soil.unit_weight_n_per_m3 = 13.0e3 * 1.38;
      soil.cohesion_pa = 4.14e3;
      soil.adhesion_pa = 0.5 * 4.14e3;
      soil.internal_friction_rad = 13.0 * kDeg;
      break;
  }
  // Soil-tool friction: two thirds of the internal friction (rough steel face).
  soil.soil_tool_friction_rad = (2.0 / 3.0) * soil.internal_friction_rad;
  soil.surcharge_pa = 0.0;
  return soil;
}

std::string_view to_string(SoilPreset preset) {
  switch (preset) {
    case SoilPreset::kDrySand:
      return "dry_sand";
    case SoilPreset::kLooseSand:
      return "loose_sand";
    case SoilPreset::kClay:
      return "clay";
  }
  return "dry_sand";
}

std::optional<SoilPreset> parse_soil_preset(std::string_view name) {
  if (name == "dry_sand") return SoilPreset::kDrySand;
  if (name == "loose_sand") return SoilPreset::kLooseSand;
  if (name == "clay") return SoilPreset::kClay;
  return std::nullopt;
}

std::string validate(const SoilParams& soil) {
  constexpr std::string_view at = "earthmoving.soil.";
  if (auto m = check_entry(at, "unit_weight_n_per_m3", soil.unit_weight_n_per_m3); !m.empty())
    return m;
  if (auto m = check_entry(at, "cohesion_pa", soil.cohesion_pa); !m.empty()) return m;
  if (auto m = check_entry(at, "adhesion_pa", soil.adhesion_pa); !m.empty()) return m;
  if (auto m = check_entry(at, "internal_friction_rad", soil.internal_friction_rad); !m.empty())
    return m;
  if (auto m = check_entry(at, "soil_tool_friction_rad", soil.soil_tool_friction_rad); !m.empty())
    return m;
  return check_entry(at, "surcharge_pa", soil.surcharge_pa);
}

std::string validate(const EarthmovingParams& params) {
  if (auto m = nested("soil", validate(params.soil)); !m.empty()) return m;
  if (auto m = check_entry("earthmoving.", "rake_angle_rad", params.rake_angle_rad); !m.empty())
    return m;
  // A planar wedge needs a failure-plane angle with D > 0: beta < pi - alpha - delta - phi.
  // Ask for at least one degree of room.
  double room = kPi - params.rake_angle_rad - params.soil.soil_tool_friction_rad -
                params.soil.internal_friction_rad;
  if (!(room >= 1.0 * kDeg)) {
    return must_be("rake_angle_rad + soil.soil_tool_friction_rad + soil.internal_friction_rad",
                   "below 179 deg", (kPi - room) / kDeg) +
           " deg: no planar failure wedge exists";
  }
  return {};
}

EarthmovingFactors earthmoving_factors(const EarthmovingParams& params, double beta_rad) noexcept {
  double alpha = params.rake_angle_rad;
  double delta = params.soil.soil_tool_friction_rad;
  double phi = params.soil.internal_friction_rad;
  double cot_a = cot(alpha), cot_b = cot(beta_rad), cot_bp = cot(beta_rad + phi);
  double d = std::cos(alpha + delta) + std::sin(alpha + delta) * cot_bp;
  EarthmovingFactors f;
  f.n_gamma = (cot_a + cot_b) / (2.0 * d);
  f.n_c = (1.0 + cot_b * cot_bp) / d;
  f.n_a = (1.0 - cot_a * cot_bp) / d;
  f.n_q = (cot_a + cot_b) / d;
  return f;
}

double earthmoving_total_n(const EarthmovingParams& params, double width_m, double depth_m,
                           double beta_rad) noexcept {
  return WedgeConstants(params, width_m, depth_m).total(beta_rad);
}

BetaRange earthmoving_beta_range(const EarthmovingParams& params) noexcept {
  double hi = std::min(kPi / 2, kPi - params.rake_angle_rad - params.soil.soil_tool_friction_rad -
                                    params.soil.internal_friction_rad);
  return {0.0, hi};
}

EarthmovingResult earthmoving_force(const EarthmovingParams& params, double width_m,
                                    double depth_m) noexcept {
  EarthmovingResult out;
  if (width_m <= 0.0 || depth_m <= 0.0) return out;
  const WedgeConstants wedge(params, width_m, depth_m);

  // Search inside the open range; P grows without bound at both ends in the
  // usual cases (cot beta -> inf at 0, D -> 0 at pi - alpha - delta - phi),
  // but may be smallest at the pi/2 end, which the closed search includes.
  BetaRange range = earthmoving_beta_range(params);
  constexpr double kEdge = 1e-4;  // rad kept clear of the open ends (rounding near 0/0)
  double lo = range.lo_rad + kEdge;
  double hi = range.hi_rad == kPi / 2 ? range.hi_rad : range.hi_rad - kEdge;

  // Coarse scan for the basin of the global minimum.
  constexpr int kScan = 48;
  double step = (hi - lo) / (kScan - 1);
  int best = 0;
  double best_p = wedge.total(lo);
  for (int k = 1; k < kScan; ++k) {
    double p = wedge.total(lo + k * step);
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
  double adhesion = params.soil.adhesion_pa * depth_m * width_m;
  out.total_n = p;
  out.beta_rad = beta;
  out.factors = earthmoving_factors(params, beta);
  out.horizontal_n = p * wedge.sin_ad + adhesion * wedge.cot_alpha;
  out.vertical_n = p * wedge.cos_ad - adhesion;
  return out;
}

Vec3 earthmoving_world_force(const EarthmovingResult& result, Vec3 velocity_m_per_s,
                             double low_speed_damping_n_s_per_m) noexcept {
  double speed = std::hypot(velocity_m_per_s.x, velocity_m_per_s.z);
  double h = std::abs(result.horizontal_n);
  if (speed == 0.0 || h == 0.0) return {};
  double scale = saturated_drag_n(h, speed, low_speed_damping_n_s_per_m) / h;
  double ux = velocity_m_per_s.x / speed, uz = velocity_m_per_s.z / speed;
  double hs = result.horizontal_n * scale;
  return {-hs * ux, -result.vertical_n * scale, -hs * uz};
}

// ---------------------------------------------------------------------------
// Surface
// ---------------------------------------------------------------------------

std::string validate(const SurfaceParams& params) {
  if (auto m = check_entry("surface.", "stiffness_n_per_m", params.stiffness_n_per_m); !m.empty())
    return m;
  return check_entry("surface.", "damping_n_s_per_m", params.damping_n_s_per_m);
}

SurfaceForce surface_force(const SurfaceParams& params, Vec3 device_point_m, Vec3 velocity_m_per_s,
                           double surface_y_m) noexcept {
  SurfaceForce out;
  out.proxy_m = device_point_m;
  double depth = surface_y_m - device_point_m.y;
  if (depth <= 0.0) return out;  // above the surface (NaN falls through to a NaN force)
  out.in_contact = true;
  out.penetration_m = depth;
  out.proxy_m.y = surface_y_m;
  // Spring-damper along Y, never pulling the device into the surface: a
  // negative push would make the surface sticky; dropping it only dissipates.
  double push = params.stiffness_n_per_m * depth - params.damping_n_s_per_m * velocity_m_per_s.y;
  out.force_n = {0.0, push < 0.0 ? 0.0 : push, 0.0};
  return out;
}

// ---------------------------------------------------------------------------
// Penetration
// ---------------------------------------------------------------------------

BearingFactors bearing_capacity_factors(double internal_friction_rad) noexcept {
  const double phi = internal_friction_rad;
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

std::string validate(const PenetrationParams& params) {
  return check_entry("penetration.", "edge_thickness_m", params.edge_thickness_m);
}

PenetrationResult penetration_resistance(const SoilParams& soil, const PenetrationParams& params,
                                         double length_m, double depth_m,
                                         double surcharge_pa) noexcept {
  PenetrationResult out;
  if (!(length_m > 0.0) || !(depth_m > 0.0)) return out;
  const double b = params.edge_thickness_m;
  const double gamma = soil.unit_weight_n_per_m3;
  const BearingFactors f = bearing_capacity_factors(soil.internal_friction_rad);
  const double q = gamma * depth_m + soil.surcharge_pa + surcharge_pa;
  out.bearing_pa = soil.cohesion_pa * f.n_c + q * f.n_q + 0.5 * gamma * b * f.n_gamma;
  out.tip_n = out.bearing_pa * b * length_m * std::min(1.0, depth_m / b);
  const double k0 = 1.0 - std::sin(soil.internal_friction_rad);
  out.side_n = 2.0 * length_m *
               (0.5 * k0 * gamma * depth_m * depth_m * std::tan(soil.soil_tool_friction_rad) +
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

// ---------------------------------------------------------------------------
// Twist
// ---------------------------------------------------------------------------

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
  const double rotational_damping =
      low_speed_damping_n_s_per_m * engagement.second_moment_m3 / blade_length_m;
  const double scale = saturated_drag_n(torque, std::abs(w), rotational_damping) / torque;
  const double sense = w > 0.0 ? -1.0 : 1.0;
  out.torque_n_m = sense * torque * scale;
  out.net_force_n = sense * resistance_n_per_m * engagement.signed_length_m * scale;
  return out;
}

// ---------------------------------------------------------------------------
// Device limits
// ---------------------------------------------------------------------------

std::string validate(const DeviceLimits& limits) {
  constexpr std::string_view at = "device.";
  if (auto m = check_entry(at, "max_force_n", limits.max_force_n); !m.empty()) return m;
  if (auto m = check_entry(at, "max_stiffness_n_per_m", limits.max_stiffness_n_per_m); !m.empty())
    return m;
  if (auto m = check_entry(at, "max_damping_n_s_per_m", limits.max_damping_n_s_per_m); !m.empty())
    return m;
  return check_entry(at, "inherent_damping_n_s_per_m", limits.inherent_damping_n_s_per_m);
}

double passive_stiffness_limit_n_per_m(double inherent_damping_n_s_per_m,
                                       double virtual_damping_n_s_per_m, double rate_hz) noexcept {
  return 2.0 * (inherent_damping_n_s_per_m - std::abs(virtual_damping_n_s_per_m)) * rate_hz;
}

// ---------------------------------------------------------------------------
// Combination
// ---------------------------------------------------------------------------

std::string_view to_string(CuttingModel model) {
  switch (model) {
    case CuttingModel::kNone:
      return "none";
    case CuttingModel::kContactDrag:
      return "contact_drag";
    case CuttingModel::kEarthmoving:
      return "earthmoving";
  }
  return "none";
}

std::optional<CuttingModel> parse_cutting_model(std::string_view name) {
  if (name == "none") return CuttingModel::kNone;
  if (name == "contact_drag") return CuttingModel::kContactDrag;
  if (name == "earthmoving") return CuttingModel::kEarthmoving;
  return std::nullopt;
}

std::string_view to_string(LimitPolicy policy) {
  return policy == LimitPolicy::kRefuse ? "refuse" : "clamp";
}

std::optional<LimitPolicy> parse_limit_policy(std::string_view name) {
  if (name == "refuse") return LimitPolicy::kRefuse;
  if (name == "clamp") return LimitPolicy::kClamp;
  return std::nullopt;
}

std::string validate(const ForceModelParams& params) {
  if (auto m = nested("contact_drag", validate(params.contact_drag)); !m.empty()) return m;
  if (auto m = nested("earthmoving", validate(params.earthmoving)); !m.empty()) return m;
  if (auto m = nested("surface", validate(params.surface)); !m.empty()) return m;
  if (auto m = nested("penetration", validate(params.penetration)); !m.empty()) return m;
  if (auto m = check_entry("", "low_speed_damping_n_s_per_m", params.low_speed_damping_n_s_per_m);
      !m.empty())
    return m;
  if (auto m = check_entry("", "force_scale", params.force_scale); !m.empty()) return m;
  if (auto m = check_positive("workspace_scale", params.workspace_scale); !m.empty()) return m;
  if (auto m = check_positive("max_contact_length_m", params.max_contact_length_m); !m.empty())
    return m;
  if (!(std::isfinite(params.loop_rate_hz) && params.loop_rate_hz > 0.0 &&
        params.loop_rate_hz <= 1e6)) {
    return must_be("loop_rate_hz", "in (0, 1e6]", params.loop_rate_hz);
  }
  return nested("device", validate(params.device));
}

std::span<const Range> force_ranges() { return kRanges; }

ForceModel::ForceModel(const ForceModelParams& params) : requested_(params), params_(params) {
  if (auto m = validate(params); !m.empty()) throw InputError(m);
  const bool refuse = params.policy == LimitPolicy::kRefuse;
  const DeviceLimits& dev = params.device;
  // World N/m (or N s/m) -> device N/m (or N s/m).
  const double gain = params.force_scale * params.workspace_scale;
  const std::string scaling = " (x force_scale " + format_number(params.force_scale) +
                              " x workspace_scale " + format_number(params.workspace_scale) + ")";

  // Surface: damping within the device's figure, then stiffness within both
  // the device's figure and Colgate & Brown's passivity bound for that damping.
  if (params.surface_enabled) {
    double damping = params.surface.damping_n_s_per_m * gain;
    check_.requested_surface_damping_n_s_per_m = damping;
    check_.requested_surface_stiffness_n_per_m = params.surface.stiffness_n_per_m * gain;
    if (damping > dev.max_damping_n_s_per_m) {
      if (refuse) {
        throw InputError("surface.damping_n_s_per_m = " +
                         format_number(params.surface.damping_n_s_per_m) + " N s/m (world) is " +
                         format_number(damping) + " N s/m on the device" + scaling +
                         ", above device.max_damping_n_s_per_m = " +
                         format_number(dev.max_damping_n_s_per_m));
      }
      damping = dev.max_damping_n_s_per_m;
      params_.surface.damping_n_s_per_m = damping / gain;
      check_.surface_damping_limited = true;
    }
    if (!refuse && damping >= dev.inherent_damping_n_s_per_m) {
      // No stiffness would be passive: halve the budget between damping and stiffness.
      damping = 0.5 * dev.inherent_damping_n_s_per_m;
      params_.surface.damping_n_s_per_m = damping / gain;
      check_.surface_damping_limited = true;
    }
    double passive = passive_stiffness_limit_n_per_m(dev.inherent_damping_n_s_per_m, damping,
                                                     params.loop_rate_hz);
    if (!(passive > 0.0)) {
      throw InputError("surface.damping_n_s_per_m = " +
                       format_number(params_.surface.damping_n_s_per_m) + " N s/m (world) is " +
                       format_number(damping) + " N s/m on the device" + scaling +
                       ", not below device.inherent_damping_n_s_per_m = " +
                       format_number(dev.inherent_damping_n_s_per_m) +
                       ": no stiffness is passive (Colgate & Brown: b > K T / 2 + |B|)");
    }
    double limit = std::min(dev.max_stiffness_n_per_m, passive);
    double stiffness = params.surface.stiffness_n_per_m * gain;
    if (stiffness > limit) {
      if (refuse) {
        throw InputError(
            "surface.stiffness_n_per_m = " + format_number(params.surface.stiffness_n_per_m) +
            " N/m (world) is " + format_number(stiffness) + " N/m on the device" + scaling +
            ", above the limit " + format_number(limit) +
            " N/m = min(device.max_stiffness_n_per_m = " +
            format_number(dev.max_stiffness_n_per_m) + ", passivity 2 (b - |B|) / T = 2 (" +
            format_number(dev.inherent_damping_n_s_per_m) + " - " + format_number(damping) +
            ") * " + format_number(params.loop_rate_hz) + " Hz = " + format_number(passive) +
            ") (Colgate & Brown 1994)");
      }
      stiffness = limit;
      params_.surface.stiffness_n_per_m = limit / gain;
      check_.surface_stiffness_limited = true;
    }
    check_.surface_stiffness_n_per_m = stiffness;
    check_.surface_damping_n_s_per_m = damping;
    check_.passive_stiffness_n_per_m = passive;
  }

  // Cutting: the low-speed slope (and the viscous term at the longest
  // contact) is a virtual damping, within the device's figure. The same
  // slope regularises penetration and twist.
  if (params.cutting != CuttingModel::kNone) {
    double viscous = params.cutting == CuttingModel::kContactDrag
                         ? params.contact_drag.viscous_n_s_per_m2 * params.max_contact_length_m
                         : 0.0;
    double damping = (params.low_speed_damping_n_s_per_m + viscous) * gain;
    check_.requested_cutting_damping_n_s_per_m = damping;
    if (damping > dev.max_damping_n_s_per_m) {
      if (refuse) {
        throw InputError(
            "low_speed_damping_n_s_per_m = " + format_number(params.low_speed_damping_n_s_per_m) +
            " N s/m (world)" +
            (viscous > 0.0 ? " + contact_drag.viscous_n_s_per_m2 * max_contact_length_m = " +
                                 format_number(viscous)
                           : std::string()) +
            " is " + format_number(damping) + " N s/m on the device" + scaling +
            ", above device.max_damping_n_s_per_m = " + format_number(dev.max_damping_n_s_per_m));
      }
      // Scale the whole soil force, not its low-speed slope alone: a lower
      // slope alone would make the force velocity-bound (min(k L, beta |v|)
      // = beta |v| at ordinary speeds), flat whatever the contact.
      check_.cutting_gain = dev.max_damping_n_s_per_m / damping;
      damping = dev.max_damping_n_s_per_m;
      check_.cutting_damping_limited = true;
    }
    check_.cutting_damping_n_s_per_m = damping;
  }
}

std::vector<std::string> ForceModel::limit_changes() const {
  std::vector<std::string> out;
  const RenderingCheck& c = check_;
  auto line = [](const std::string& what, double world_from, double world_to, double device_from,
                 double device_to, const std::string& unit) {
    return what + " " + format_number(world_from) + " -> " + format_number(world_to) + " " + unit +
           " (world; " + format_number(device_from) + " -> " + format_number(device_to) + " " +
           unit + " on the device)";
  };
  if (c.surface_stiffness_limited)
    out.push_back(line("surface stiffness", requested_.surface.stiffness_n_per_m,
                       params_.surface.stiffness_n_per_m, c.requested_surface_stiffness_n_per_m,
                       c.surface_stiffness_n_per_m, "N/m"));
  if (c.surface_damping_limited)
    out.push_back(line("surface damping", requested_.surface.damping_n_s_per_m,
                       params_.surface.damping_n_s_per_m, c.requested_surface_damping_n_s_per_m,
                       c.surface_damping_n_s_per_m, "N s/m"));
  if (c.cutting_damping_limited)
    out.push_back(line("cutting damping", params_.low_speed_damping_n_s_per_m,
                       params_.low_speed_damping_n_s_per_m * c.cutting_gain,
                       c.requested_cutting_damping_n_s_per_m, c.cutting_damping_n_s_per_m,
                       "N s/m") +
                  ": the whole soil force x " + format_number(c.cutting_gain));
  return out;
}

ForceOutput ForceModel::compute(const ForceInput& input) const noexcept {
  ForceOutput out;
  const Vec3 v = input.velocity_m_per_s;
  if (params_.surface_enabled) {
    out.surface = surface_force(params_.surface, input.device_point_m, v, input.surface_y_m);
    out.surface_n = out.surface.force_n;
  }
  switch (params_.cutting) {
    case CuttingModel::kNone:
      break;
    case CuttingModel::kContactDrag:
      out.engaged_width_m = input.contact_length_m;
      out.cutting_n = contact_drag_force(params_.contact_drag, input.contact_length_m, v,
                                         params_.low_speed_damping_n_s_per_m);
      out.cutting_uncapped_n = params_.contact_drag.drag_n_per_m * std::max(input.contact_length_m, 0.0);
      out.cutting_cap_n = params_.low_speed_damping_n_s_per_m * length(v);
      break;
    case CuttingModel::kEarthmoving: {
      double width = input.cut_width_m >= 0.0 ? input.cut_width_m : input.contact_length_m;
      // Engaged width across the horizontal motion: L |e x u|.
      double edge_len = length(input.edge_direction);
      double speed_xz = std::hypot(v.x, v.z);
      if (params_.project_width_on_motion && edge_len > 0.0 && speed_xz > 0.0) {
        Vec3 e = input.edge_direction * (1.0 / edge_len);
        Vec3 u{v.x / speed_xz, 0.0, v.z / speed_xz};
        width *= length(cross(e, u));
      }
      out.engaged_width_m = width;
      if (input.surcharge_pa > 0.0) {
        // A pile ahead of the blade adds its weight on the wedge (N_q).
        EarthmovingParams piled = params_.earthmoving;
        piled.soil.surcharge_pa += input.surcharge_pa;
        out.earthmoving = earthmoving_force(piled, width, input.cut_depth_m);
      } else {
        out.earthmoving = earthmoving_force(params_.earthmoving, width, input.cut_depth_m);
      }
      out.cutting_n =
          earthmoving_world_force(out.earthmoving, v, params_.low_speed_damping_n_s_per_m);
      out.cutting_uncapped_n = std::abs(out.earthmoving.horizontal_n);
      out.cutting_cap_n = params_.low_speed_damping_n_s_per_m * speed_xz;
      break;
    }
  }
  if (params_.cutting != CuttingModel::kNone) {
    const double beta = params_.low_speed_damping_n_s_per_m;
    const SoilParams& soil = params_.earthmoving.soil;
    if (params_.penetration.enabled) {
      out.penetration = penetration_resistance(soil, params_.penetration, input.embedded_length_m,
                                               input.embedment_depth_m, input.surcharge_pa);
      out.penetration_n = penetration_world_force(out.penetration, v, beta);
    }
    if (params_.twist_enabled && input.yaw_rate_rad_per_s != 0.0 &&
        input.twist.engaged_length_m > 0.0) {
      // The soil's resistance per metre of edge: the drag per metre of
      // contact, or the earthmoving force per metre of width at the depth.
      const double per_m =
          params_.cutting == CuttingModel::kContactDrag
              ? params_.contact_drag.drag_n_per_m
              : earthmoving_force(params_.earthmoving, 1.0, input.twist_depth_m).horizontal_n;
      const TwistResult t = twist_resistance(per_m, input.twist, input.yaw_rate_rad_per_s, beta,
                                             input.blade_length_m);
      out.twist_torque_n_m = t.torque_n_m;
      // n = Y x e, the horizontal normal of the edge.
      const double ex = input.edge_direction.x, ez = input.edge_direction.z;
      const double eh = std::hypot(ex, ez);
      if (eh > 0.0) out.twist_n = Vec3{ez / eh, 0.0, -ex / eh} * t.net_force_n;
    }
    // A device that cannot render the cutting damping gets the whole soil
    // force scaled (RenderingCheck::cutting_gain).
    const double k = check_.cutting_gain;
    if (k != 1.0) {
      out.cutting_n = out.cutting_n * k;
      out.cutting_uncapped_n *= k;
      out.cutting_cap_n *= k;
      out.penetration_n = out.penetration_n * k;
      out.twist_n = out.twist_n * k;
      out.twist_torque_n_m *= k;
    }
  }
  out.world_n = out.cutting_n + out.penetration_n + out.twist_n + out.surface_n;
  out.device_n = out.world_n * params_.force_scale;
  return out;
}

}  // namespace terracut
