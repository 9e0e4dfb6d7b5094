// Force models: what the operator feels when the blade cuts soil.
//
// Three models, each a pure function of read-only parameters and the sample's
// inputs (no state, no allocation, no exceptions on the hot path):
//   - contact drag (the paper's proposal): a drag against the tool's motion,
//     proportional to the length of the blade in contact;
//   - earthmoving: the Fundamental Earthmoving Equation (Reece 1964) in
//     McKyes' formulation (McKyes 1985, "Soil Cutting and Tillage", ch. 4):
//     the passive force of a planar soil wedge ahead of a flat blade;
//   - surface: a proxy (god-object) kept on the terrain surface and a
//     spring-damper between the proxy and the device point, so the tool
//     cannot sink into the soil without resistance;
//   - penetration: the soil's bearing capacity under an edge pushed down
//     into it (Terzaghi 1943, with Prandtl's, Reissner's and Vesic's
//     factors) and the friction on its faces;
//   - twist: the cutting resistance of every part of a buried edge turned
//     about the vertical, as a torque and a net force.
// ForceModel combines one cutting model with the others, checks once
// at construction that the device can render the result stably (Colgate &
// Brown 1994) and scales world forces to the device.
//
// Frames and units: SI throughout; world frame right-handed, Y up, ground
// plane X-Z. Forces are the forces ON the tool (and so on the operator's hand
// after scaling). See docs/forces.md for the derivations and sources.
#pragma once

#include <numbers>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "terracut/core/contact.hpp"
#include "terracut/core/grid.hpp"
#include "terracut/core/math.hpp"
#include "terracut/core/ranges.hpp"
#include "terracut/core/surface.hpp"

namespace terracut {

// ---------------------------------------------------------------------------
// Low-speed regularisation shared by the cutting models
// ---------------------------------------------------------------------------

/// Magnitude of a force that opposes motion, regularised at low speed as a
/// saturated damper: min(force_n, low_speed_damping * speed). A force that
/// flips direction with the sign of the velocity would chatter at rest; below
/// force_n / low_speed_damping the force grows linearly with speed instead,
/// with a slope the device can render. Returns 0 at zero speed, never NaN for
/// finite inputs. force_n >= 0, speed >= 0, low_speed_damping > 0 (N s/m).
double saturated_drag_n(double force_n, double speed_m_per_s,
                        double low_speed_damping_n_s_per_m) noexcept;

// ---------------------------------------------------------------------------
// Contact drag (the paper's proposal)
// ---------------------------------------------------------------------------

/// Parameters of the contact-drag model; read-only during a run.
struct ContactDragParams {
  /// k_drag: drag per metre of blade in contact, N/m, finite, >= 0.
  double drag_n_per_m = 400.0;
  /// c_viscous: extra viscous drag per metre of contact per m/s of speed,
  /// N/(m * m/s) = N s/m^2, finite, >= 0. 0 disables the viscous term.
  double viscous_n_s_per_m2 = 0.0;
};

/// Returns an empty string when params are valid, else a message naming the field.
std::string validate(const ContactDragParams& params);

/// World force on the tool from the contact-drag model:
///   F = -saturated_drag_n(k_drag * L, |v|, low_speed_damping) * v/|v| - c_viscous * L * v
/// with L = contact_length_m (>= 0; negative counts as 0) and v the tool's
/// velocity (world, m/s). Zero velocity gives zero force (no NaN). Above the
/// saturation speed k_drag * L / low_speed_damping the force is exactly
/// linear in L. low_speed_damping_n_s_per_m > 0. Parameters are trusted
/// (validate once before the run).
Vec3 contact_drag_force(const ContactDragParams& params, double contact_length_m,
                        Vec3 velocity_m_per_s, double low_speed_damping_n_s_per_m) noexcept;

// ---------------------------------------------------------------------------
// Earthmoving: the Fundamental Earthmoving Equation (McKyes' formulation)
// ---------------------------------------------------------------------------

/// Mohr-Coulomb soil and soil-tool interface properties; read-only.
struct SoilParams {
  // Defaults: the kDrySand preset.
  double unit_weight_n_per_m3 = 16.25e3;  ///< gamma: soil unit weight, N/m^3, finite, > 0
  double cohesion_pa = 1.3e3;             ///< c: soil cohesion, Pa, finite, >= 0
  double adhesion_pa = 0.0;               ///< c_a: soil-tool adhesion, Pa, finite, >= 0
  /// phi: internal friction angle, rad, [0, pi/2).
  double internal_friction_rad = 31.1 * std::numbers::pi / 180.0;
  /// delta: soil-tool friction angle, rad, [0, pi/2).
  double soil_tool_friction_rad = (2.0 / 3.0) * 31.1 * std::numbers::pi / 180.0;
  double surcharge_pa = 0.0;  ///< q: surcharge on the soil surface, Pa, finite, >= 0
};

/// Built-in soils with cited values (docs/forces.md lists the sources).
enum class SoilPreset {
  kDrySand,    ///< medium-dense dry sand (Wong's LETE sand strength; Das' unit weights)
  kLooseSand,  ///< loose dry sand (Wong's "dry sand, LLL"; Das' loose uniform sand)
  kClay,       ///< clayey soil (Wong's "clayey soil, Thailand", 38 % moisture; Das' soft clay)
};

/// The soil of a preset.
SoilParams soil_preset(SoilPreset preset);
/// "dry_sand", "loose_sand" or "clay".
std::string_view to_string(SoilPreset preset);
/// Inverse of to_string; nullopt for anything else.
std::optional<SoilPreset> parse_soil_preset(std::string_view name);

/// Parameters of the earthmoving model; read-only during a run.
struct EarthmovingParams {
  SoilParams soil{};
  /// alpha: rake angle of the blade face from the horizontal, rad, in
  /// (0, pi); pi/2 is a vertical plate. The tip leads and the face leans back
  /// over the cut soil for alpha < pi/2. Needs alpha + delta + phi < pi
  /// (otherwise no planar failure wedge exists).
  double rake_angle_rad = std::numbers::pi / 2.0;
};

/// Returns an empty string when params are valid, else a message naming the field.
std::string validate(const SoilParams& soil);
std::string validate(const EarthmovingParams& params);

/// McKyes' dimensionless factors at one failure-plane angle beta (rad, from
/// the horizontal). With D = cos(alpha+delta) + sin(alpha+delta) cot(beta+phi):
///   N_gamma = (cot alpha + cot beta) / (2 D)
///   N_c     = (1 + cot beta cot(beta+phi)) / D
///   N_a     = (1 - cot alpha cot(beta+phi)) / D
///   N_q     = (cot alpha + cot beta) / D
struct EarthmovingFactors {
  double n_gamma = 0.0;
  double n_c = 0.0;
  double n_a = 0.0;
  double n_q = 0.0;
};

/// The factors of params at failure-plane angle beta_rad (no minimisation).
EarthmovingFactors earthmoving_factors(const EarthmovingParams& params, double beta_rad) noexcept;

/// The passive force of the wedge at one failure-plane angle:
///   P(beta) = (gamma d^2 N_gamma + c d N_c + c_a d N_a + q d N_q) w, newtons.
double earthmoving_total_n(const EarthmovingParams& params, double width_m, double depth_m,
                           double beta_rad) noexcept;

/// Open range of failure-plane angles with a valid wedge, rad:
/// (0, min(pi/2, pi - alpha - delta - phi)).
struct BetaRange {
  double lo_rad = 0.0;
  double hi_rad = 0.0;
};
BetaRange earthmoving_beta_range(const EarthmovingParams& params) noexcept;

/// The earthmoving force on the blade for one cut.
struct EarthmovingResult {
  /// P: the soil's resultant on the blade face (McKyes' "F"/"P"), at angle
  /// delta to the face normal, excluding adhesion; N, >= 0 in valid cases.
  double total_n = 0.0;
  /// H = P sin(alpha+delta) + c_a d w cot(alpha): horizontal force resisting
  /// the blade's motion (on the blade it points against the motion), N.
  double horizontal_n = 0.0;
  /// V = P cos(alpha+delta) - c_a d w: vertical force, positive when it
  /// pushes the blade DOWN into the soil (McKyes' sign), N. For a vertical
  /// rough blade V < 0: the rising wedge lifts the blade.
  double vertical_n = 0.0;
  /// beta*: failure-plane angle from the horizontal that minimises P, rad.
  double beta_rad = 0.0;
  EarthmovingFactors factors{};  ///< the factors at beta*
};

/// FEE force for a blade of engaged width width_m (the contact length) at
/// cutting depth depth_m (material depth ahead of the edge). beta* is found by
/// minimising P(beta) over earthmoving_beta_range: a 48-point scan, then a
/// golden-section search in the bracket around the best sample, to 1e-10 rad;
/// the open ends of the range are kept 1e-4 rad away (the pi/2 end is included).
/// Width or depth <= 0 gives all zeros (beta_rad = 0). Allocates nothing;
/// parameters are trusted (validate once).
EarthmovingResult earthmoving_force(const EarthmovingParams& params, double width_m,
                                    double depth_m) noexcept;

/// World force on the blade from an earthmoving result and the blade's world
/// velocity: -H_s * u - V_s * Y, where u is the unit horizontal (X-Z) direction
/// of motion and (H_s, V_s) = (H, V) * s with
/// s = saturated_drag_n(H, |v_xz|, low_speed_damping) / H (the low-speed
/// regularisation scales both components, keeping the force's direction).
/// No horizontal motion gives zero force. low_speed_damping_n_s_per_m > 0.
Vec3 earthmoving_world_force(const EarthmovingResult& result, Vec3 velocity_m_per_s,
                             double low_speed_damping_n_s_per_m) noexcept;

// ---------------------------------------------------------------------------
// Surface: proxy on the terrain and a spring-damper to the device point
// ---------------------------------------------------------------------------

// The surface query the proxy reads (surface_y_m) lives with the grid:
// terracut/core/surface.hpp.

/// Parameters of the surface model, world units; read-only during a run.
struct SurfaceParams {
  /// K: spring between proxy and device point, N/m (world), finite, > 0.
  double stiffness_n_per_m = 100e3;
  /// B: damping of the device's vertical velocity while below the surface,
  /// N s/m (world), finite, >= 0.
  double damping_n_s_per_m = 12.5;
};

/// Returns an empty string when params are valid, else a message naming the field.
std::string validate(const SurfaceParams& params);

/// What the surface model computed for one sample.
struct SurfaceForce {
  Vec3 force_n{};              ///< world force on the device point, N
  Vec3 proxy_m{};              ///< proxy position (on or above the surface), world metres
  double penetration_m = 0.0;  ///< depth of the device point below the surface, metres, >= 0
  bool in_contact = false;     ///< the device point is below the surface
};

/// The proxy sits at the device point lifted vertically onto the surface
/// (proxy = (x, max(y, surface_y), z)); below the surface
///   F = K (proxy - device) - B v_y Y = (K * depth - B * v_y) Y,
/// and above it F = 0. The force is vertical and continuous in position
/// wherever the surface is (kSurface). velocity: device point, world m/s.
SurfaceForce surface_force(const SurfaceParams& params, Vec3 device_point_m, Vec3 velocity_m_per_s,
                           double surface_y_m) noexcept;

// ---------------------------------------------------------------------------
// Penetration: a blade edge pushed down into the soil
// ---------------------------------------------------------------------------

/// Bearing-capacity factors of a strip footing (dimensionless):
///   N_q     = e^(pi tan phi) tan^2(45 deg + phi/2)   (Prandtl 1921, Reissner 1924)
///   N_c     = (N_q - 1) cot phi, -> pi + 2 as phi -> 0 (Prandtl)
///   N_gamma = 2 (N_q + 1) tan phi                     (Vesic 1973)
/// phi: internal friction angle, rad, [0, pi/2).
struct BearingFactors {
  double n_c = 0.0;
  double n_q = 0.0;
  double n_gamma = 0.0;
};
BearingFactors bearing_capacity_factors(double internal_friction_rad) noexcept;

/// Parameters of the penetration model; read-only during a run.
struct PenetrationParams {
  bool enabled = true;  ///< add the resistance to vertical motion
  /// B: thickness of the cutting edge, the width of the strip the soil bears
  /// under it, m, finite, > 0. Also the depth over which the bearing is
  /// mobilised (docs/forces.md). Default: a 2 cm steel cutting edge.
  double edge_thickness_m = 0.02;
};

/// Returns an empty string when params are valid, else a message naming the field.
std::string validate(const PenetrationParams& params);

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

/// The resistance of the soil to an edge of engaged length length_m at
/// embedment depth depth_m (the edge's depth below the soil beside it), with
/// an extra surcharge_pa on the soil around it. Zero when length or depth is
/// <= 0. Allocates nothing; parameters are trusted (validate once).
PenetrationResult penetration_resistance(const SoilParams& soil, const PenetrationParams& params,
                                         double length_m, double depth_m,
                                         double surcharge_pa = 0.0) noexcept;

/// World force from a penetration result: moving down (v_y < 0),
/// +saturated_drag_n(down_n, |v_y|, beta) Y; moving up,
/// -saturated_drag_n(up_n, v_y, beta) Y; zero at v_y = 0. Horizontal motion
/// does not enter. low_speed_damping_n_s_per_m > 0.
Vec3 penetration_world_force(const PenetrationResult& result, Vec3 velocity_m_per_s,
                             double low_speed_damping_n_s_per_m) noexcept;

// ---------------------------------------------------------------------------
// Twist: a buried blade turned about the vertical
// ---------------------------------------------------------------------------

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
/// with f per metre of edge (the cutting model's resistance per width),
/// against its motion. Summed over the engaged parts:
///   T = -sign(omega) f integral |s| ds,   F_n = -sign(omega) f integral sign(s) ds,
/// both scaled by the low-speed regularisation of the whole,
/// saturated_drag_n(f abs_moment, |omega|, beta second_moment / blade_length)
/// / (f abs_moment): below that rate each part of the edge is a damper of
/// beta / blade_length per metre. Zero yaw rate or no engagement gives zeros.
/// resistance_n_per_m >= 0, low_speed_damping_n_s_per_m > 0, blade_length_m > 0.
TwistResult twist_resistance(double resistance_n_per_m, const TwistEngagement& engagement,
                             double yaw_rate_rad_per_s, double low_speed_damping_n_s_per_m,
                             double blade_length_m) noexcept;

// ---------------------------------------------------------------------------
// Device limits and the passivity rule
// ---------------------------------------------------------------------------

/// What the haptic device can render; defaults: a Novint Falcon, from
/// CHAI3D's Novint Falcon device specification (cFalconDevice, in CHAI3D's
/// src/devices/CFalconDevice.cpp; www.chai3d.org): max force 8 N, max
/// stiffness 3000 N/m, max damping 20 N/(m/s), workspace radius 0.04 m.
/// Device units (device metres, device newtons).
struct DeviceLimits {
  double max_force_n = 8.0;               ///< largest force, N, finite, > 0
  double max_stiffness_n_per_m = 3000.0;  ///< largest stable stiffness at 1 kHz, N/m, finite, > 0
  double max_damping_n_s_per_m = 20.0;    ///< largest stable virtual damping, N s/m, finite, > 0
  /// b: inherent (physical) damping the passivity rule may count on, N s/m,
  /// finite, > 0. The default 1.5 is what Colgate & Brown's condition needs
  /// for CHAI3D's 3000 N/m at 1 kHz with no virtual damping (K T / 2); set
  /// the measured value of your device.
  double inherent_damping_n_s_per_m = 1.5;
};

/// Returns an empty string when limits are valid, else a message naming the field.
std::string validate(const DeviceLimits& limits);

/// Colgate & Brown (1994): a sampled virtual wall of stiffness K and damping
/// B on a device of inherent damping b at sample period T is passive when
/// b > K T / 2 + |B|. This returns the largest passive stiffness,
/// 2 (b - |B|) / T = 2 (b - |B|) * rate_hz, N/m (<= 0 when |B| >= b).
double passive_stiffness_limit_n_per_m(double inherent_damping_n_s_per_m,
                                       double virtual_damping_n_s_per_m, double rate_hz) noexcept;

// ---------------------------------------------------------------------------
// Combination
// ---------------------------------------------------------------------------

/// Which cutting model drives the resistance to motion.
enum class CuttingModel {
  kNone,
  kContactDrag,  ///< the paper's proposal
  kEarthmoving,  ///< the Fundamental Earthmoving Equation
};
/// "none", "contact_drag" or "earthmoving".
std::string_view to_string(CuttingModel model);
std::optional<CuttingModel> parse_cutting_model(std::string_view name);

/// What to do when the requested rendering is beyond the device (stiffness or
/// damping above the limits or the passivity rule).
enum class LimitPolicy {
  kRefuse,  ///< the ForceModel constructor throws InputError naming the field and the bound
  /// Values are lowered to the bound and RenderingCheck records what was
  /// limited. A surface damping that leaves no passive stiffness (|B| >= b)
  /// is lowered to b / 2 first.
  kClamp,
};
/// "refuse" or "clamp".
std::string_view to_string(LimitPolicy policy);
std::optional<LimitPolicy> parse_limit_policy(std::string_view name);

/// Parameters of the combined force model; read-only during a run.
struct ForceModelParams {
  CuttingModel cutting = CuttingModel::kContactDrag;
  ContactDragParams contact_drag{};
  EarthmovingParams earthmoving{};
  bool surface_enabled = true;  ///< add the surface (proxy) model
  SurfaceParams surface{};
  /// Slope of the cutting force at low speed (saturated damper), N s/m
  /// (world), finite, > 0. Shared by both cutting models.
  double low_speed_damping_n_s_per_m = 1000.0;
  PenetrationParams penetration{};
  /// Add the resistance to turning the blade about the vertical while it is
  /// in soil (twist_resistance).
  bool twist_enabled = true;
  /// Earthmoving only: use the engaged width projected across the motion,
  /// width = contact length * |sin(angle between edge and horizontal motion)|,
  /// when the input gives the edge direction. A blade sliding along its own
  /// edge cuts nothing.
  bool project_width_on_motion = true;
  /// Device newtons per world newton, finite, > 0. World forces of a real
  /// blade are hundreds of newtons; the default maps 400 N to 8 N.
  double force_scale = 0.02;
  /// World metres per device metre of the loop's workspace mapping, finite,
  /// > 0. Needed only to express world stiffness and damping on the device:
  /// K_device = K_world * force_scale * workspace_scale.
  double workspace_scale = 1.0;
  /// Longest possible contact (the blade length), metres, finite, > 0; bounds
  /// the viscous term's damping for the device check.
  double max_contact_length_m = 1.0;
  /// Haptic loop rate, Hz, finite, in (0, 1e6]; T = 1 / rate in the passivity rule.
  double loop_rate_hz = 1000.0;
  DeviceLimits device{};
  LimitPolicy policy = LimitPolicy::kClamp;
};

/// Returns an empty string when the fields are in range (not the device
/// check, which the ForceModel constructor applies), else a message naming
/// the field.
std::string validate(const ForceModelParams& params);
/// The ranges of ForceModelParams' settable fields, by their paths in it
/// ("surface.stiffness_n_per_m", "earthmoving.soil.cohesion_pa"), which the
/// validate() functions of these structs check (core/ranges.hpp). Angles in
/// radians. The fields the session derives (workspace_scale, loop_rate_hz,
/// max_contact_length_m) are not in it.
std::span<const Range> force_ranges();

/// The device check made at construction, all in device units.
struct RenderingCheck {
  double surface_stiffness_n_per_m = 0.0;  ///< K on the device after limiting
  double surface_damping_n_s_per_m = 0.0;  ///< B on the device after limiting
  double passive_stiffness_n_per_m = 0.0;  ///< 2 (b - |B|) / T with the B above
  /// Low-speed slope plus the viscous term at the longest contact, after
  /// limiting (the requested damping times cutting_gain).
  double cutting_damping_n_s_per_m = 0.0;
  /// The same three as requested, before limiting, device units.
  double requested_surface_stiffness_n_per_m = 0.0;
  double requested_surface_damping_n_s_per_m = 0.0;
  double requested_cutting_damping_n_s_per_m = 0.0;
  /// Factor on the whole soil-resistance force (cutting, penetration, twist),
  /// in (0, 1]: when the cutting damping is beyond the device (kClamp), the
  /// force is scaled down as a whole instead of lowering its low-speed
  /// slope, so that it keeps its shape against contact length and depth.
  double cutting_gain = 1.0;
  bool surface_stiffness_limited = false;  ///< K was lowered (kClamp)
  bool surface_damping_limited = false;    ///< B was lowered (kClamp)
  bool cutting_damping_limited = false;    ///< low-speed damping / viscous were lowered (kClamp)
  bool any_limited() const {
    return surface_stiffness_limited || surface_damping_limited || cutting_damping_limited;
  }
};

/// Inputs of one force sample (world frame).
struct ForceInput {
  Vec3 velocity_m_per_s{};        ///< tool (and device point) velocity, world m/s
  double contact_length_m = 0.0;  ///< blade length in material (ContactResult::length_m), m
  /// Material depth ahead of the edge, m (e.g. section_area_m2 / length_m).
  double cut_depth_m = 0.0;
  /// Surcharge on the soil ahead of the blade from soil piled on it (a pile
  /// the blade pushes: unit weight x the pile's height over the failure
  /// wedge), Pa, finite, >= 0; added to the soil's own surcharge_pa.
  double surcharge_pa = 0.0;
  /// Earthmoving: the length of edge with soil ahead of it, m (>= 0), used
  /// instead of contact_length_m when given; negative: not given.
  double cut_width_m = -1.0;
  /// Direction of the cutting edge (any length; zero = unknown, no projection).
  Vec3 edge_direction{};
  Vec3 device_point_m{};     ///< point held on the surface by the proxy, world metres
  double surface_y_m = 0.0;  ///< world Y of the terrain surface below device_point_m
  /// Penetration: depth of the edge below the soil beside it, m (>= 0), and
  /// the length of edge that deep in soil, m (>= 0).
  double embedment_depth_m = 0.0;
  double embedded_length_m = 0.0;
  /// Twist: the tool's angular velocity about world +Y, rad/s; the engaged
  /// parts for that sense of turning, and their mean depth of material, m.
  double yaw_rate_rad_per_s = 0.0;
  TwistEngagement twist{};
  double twist_depth_m = 0.0;
  /// Length of the blade, m (> 0), for the twist's low-speed damping share.
  double blade_length_m = 1.0;
};

/// Outputs of one force sample.
struct ForceOutput {
  Vec3 cutting_n{};                 ///< cutting model's world force, N
  Vec3 surface_n{};                 ///< surface model's world force, N
  Vec3 world_n{};                   ///< cutting + surface, world force on the tool, N
  Vec3 device_n{};                  ///< world_n * force_scale: device newtons, world axes
  SurfaceForce surface{};           ///< proxy, penetration, contact (zero when disabled)
  EarthmovingResult earthmoving{};  ///< the FEE solution (zero unless kEarthmoving)
  double engaged_width_m = 0.0;     ///< width used by the cutting model, m
  Vec3 penetration_n{};             ///< penetration model's world force (vertical), N
  PenetrationResult penetration{};  ///< tip and face resistance (zero when disabled)
  Vec3 twist_n{};                   ///< twist's net world force (horizontal), N
  double twist_torque_n_m = 0.0;    ///< twist's torque about world +Y, N m (not rendered by a 3-DOF device)
  /// The cutting force before the low-speed cap, N, and the cap itself
  /// (low_speed_damping_n_s_per_m x speed), N, both after the device's
  /// cutting gain: the cutting force is the lower of the two (kEarthmoving:
  /// its horizontal part, the speed the horizontal one; kContactDrag: the
  /// drag along the motion, viscous part aside). Zero for kNone. A factor
  /// on the soil scales the first, not the cap.
  double cutting_uncapped_n = 0.0;
  double cutting_cap_n = 0.0;
};

/// The combined model: validated and device-checked once, then a pure const
/// compute() per sample.
class ForceModel {
 public:
  /// Throws InputError naming the bad field, or (kRefuse) the rendering that
  /// exceeds the device with the bound it broke.
  explicit ForceModel(const ForceModelParams& params);

  /// Parameters as requested.
  const ForceModelParams& requested() const { return requested_; }
  /// Parameters in use (after kClamp limiting).
  const ForceModelParams& params() const { return params_; }
  const RenderingCheck& rendering() const { return check_; }

  /// What the device check lowered, one line each, requested -> used, for
  /// example "cutting damping 1000 -> 100 N s/m (world; 200 -> 20 N s/m on
  /// the device): the whole soil force x 0.1". Empty when nothing was.
  std::vector<std::string> limit_changes() const;

  /// One sample: allocates nothing, never throws. Non-finite inputs give
  /// non-finite outputs, for the safety limiter to catch and count.
  ForceOutput compute(const ForceInput& input) const noexcept;

 private:
  ForceModelParams requested_;
  ForceModelParams params_;
  RenderingCheck check_;
};

}  // namespace terracut
