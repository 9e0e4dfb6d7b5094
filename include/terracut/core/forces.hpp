// The haptic rendering of the force on the tool: what a haptic device is
// sent, computed each tick from the step's physical force (tool_force.hpp)
// and the device's own motion estimate. The physical force is what the soil
// does; this is what a device can render of it:
//   - the cutting model: the physical soil force (`earthmoving`), or the
//     paper's contact drag (drag.hpp), or none;
//   - the low-speed damper: below F / beta the soil's resistance grows
//     linearly with the device's speed instead of flipping with its sign
//     (saturated_drag_n), for the cutting force, penetration and twist;
//   - the surface model: a proxy spring-damper on the ground (surface_force.hpp);
//   - the carried load's weight and (filtered) inertia, the rigid bodies' force;
//   - the device check, once at construction: the rendering's stiffness and
//     damping within what the device renders stably (Colgate & Brown 1994),
//     refused or clamped, and the whole soil force scaled when the damper is
//     beyond the device;
//   - world newtons to device newtons (force_scale).
// None of it changes the physical force.
//
// Frames and units: SI throughout; world frame right-handed, Y up, ground
// plane X-Z. Forces are the forces ON the tool (and so on the operator's hand
// after scaling). See docs/forces.md for the derivations and sources.
#pragma once

#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "terracut/core/enum_names.hpp"
#include "terracut/core/drag.hpp"
#include "terracut/core/earthmoving.hpp"
#include "terracut/core/math.hpp"
#include "terracut/core/penetration.hpp"
#include "terracut/core/ranges.hpp"
#include "terracut/core/surface_force.hpp"
#include "terracut/core/tool_force.hpp"
#include "terracut/core/twist.hpp"

namespace terracut {

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

/// Which force the device renders as the resistance to cutting.
enum class CuttingModel {
  kNone,         ///< none (nor penetration, nor twist)
  kContactDrag,  ///< the paper's proposal: a drag per metre of blade in the soil
  kEarthmoving,  ///< the physical soil force (cutting, the pile's surcharge)
};
/// Its names (enum_names.hpp: to_string, parse_enum).
inline constexpr EnumName<CuttingModel> kCuttingModelNames[] = {
    {CuttingModel::kNone, "none"},
    {CuttingModel::kContactDrag, "contact_drag"},
    {CuttingModel::kEarthmoving, "earthmoving"},
};
constexpr std::span<const EnumName<CuttingModel>> enum_names(CuttingModel) { return kCuttingModelNames; }

/// What to do when the requested rendering is beyond the device (stiffness or
/// damping above the limits or the passivity rule).
enum class LimitPolicy {
  kRefuse,  ///< the ForceModel constructor throws InputError naming the field and the bound
  /// Values are lowered to the bound and RenderingCheck records what was
  /// limited. A surface damping that leaves no passive stiffness (|B| >= b)
  /// is lowered to b / 2 first.
  kClamp,
};
/// Its names (enum_names.hpp: to_string, parse_enum).
inline constexpr EnumName<LimitPolicy> kLimitPolicyNames[] = {
    {LimitPolicy::kRefuse, "refuse"},
    {LimitPolicy::kClamp, "clamp"},
};
constexpr std::span<const EnumName<LimitPolicy>> enum_names(LimitPolicy) { return kLimitPolicyNames; }

/// Parameters of the rendering; read-only during a run.
struct ForceModelParams {
  CuttingModel cutting = CuttingModel::kContactDrag;
  ContactDragParams contact_drag{};
  bool surface_enabled = true;  ///< add the surface (proxy) model
  SurfaceParams surface{};
  /// Slope of the rendered soil force at low speed (saturated damper), N s/m
  /// (world), finite, > 0. Shared by the cutting force, penetration and twist.
  double low_speed_damping_n_s_per_m = 1000.0;
  /// Render the resistance to pushing the edge down (penetration.hpp).
  bool penetration_enabled = true;
  /// Render the resistance to turning the blade about the vertical while it
  /// is in soil (twist.hpp).
  bool twist_enabled = true;
  /// Device newtons per world newton, finite, > 0. World forces of a real
  /// blade are hundreds of newtons; the default maps 400 N to 8 N.
  double force_scale = 0.02;
  /// World metres per device metre of the loop's workspace mapping, finite,
  /// > 0. Needed only to express world stiffness and damping on the device:
  /// K_device = K_world * force_scale * workspace_scale.
  double workspace_scale = 1.0;
  /// Longest possible contact (the blade length), metres, finite, > 0; bounds
  /// the viscous term's damping for the device check, and shares the twist's
  /// damping along the edge.
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
/// ("surface.stiffness_n_per_m", "device.max_force_n"), which the
/// validate() functions of these structs check (core/ranges.hpp). The fields
/// the session derives (workspace_scale, loop_rate_hz, max_contact_length_m)
/// are not in it.
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
  /// Factor on the whole rendered soil resistance (cutting, penetration,
  /// twist), in (0, 1]: when the cutting damping is beyond the device
  /// (kClamp), the rendered force is scaled down as a whole instead of
  /// lowering its low-speed slope, so that it keeps its shape against
  /// contact length and depth. The physical force is not scaled.
  double cutting_gain = 1.0;
  bool surface_stiffness_limited = false;  ///< K was lowered (kClamp)
  bool surface_damping_limited = false;    ///< B was lowered (kClamp)
  bool cutting_damping_limited = false;    ///< low-speed damping / viscous were lowered (kClamp)
  bool any_limited() const {
    return surface_stiffness_limited || surface_damping_limited || cutting_damping_limited;
  }
};

/// Inputs of one rendered sample (world frame).
struct ForceInput {
  /// The step's physical force (StepOutput::force): its solutions (the
  /// earthmoving H and V with the pile, the penetration's resistances, the
  /// twist's engagement, the load's mass) are rendered at the device's motion.
  ToolForce physical{};
  Vec3 velocity_m_per_s{};        ///< the device's (filtered) tool velocity, world m/s
  Vec3 acceleration_m_per_s2{};   ///< its (filtered) acceleration, world m/s^2: the load's inertia
  double yaw_rate_rad_per_s = 0.0;  ///< its (filtered) yaw rate about world +Y, rad/s
  double contact_length_m = 0.0;  ///< blade length in material (ContactResult::length_m), m: the contact drag's
  Vec3 device_point_m{};     ///< point held on the surface by the proxy, world metres
  double surface_y_m = 0.0;  ///< world Y of the surface the proxy holds it on
};

/// Outputs of one rendered sample: world forces (before force_scale), N.
struct ForceOutput {
  Vec3 cutting_n{};                 ///< the rendered cutting force (with the pile's surcharge), N
  Vec3 surface_n{};                 ///< surface model's world force, N
  Vec3 penetration_n{};             ///< rendered penetration force (vertical), N
  Vec3 twist_n{};                   ///< rendered twist's net force (horizontal), N
  double twist_torque_n_m = 0.0;    ///< rendered twist torque about +Y, N m (not rendered by a 3-DOF device)
  Vec3 load_n{};                    ///< the carried load: weight and filtered inertia, N
  Vec3 bodies_n{};                  ///< the step listeners' force (rigid bodies), N
  Vec3 world_n{};                   ///< the sum: what the device renders, in world newtons
  Vec3 device_n{};                  ///< world_n * force_scale: device newtons, world axes
  SurfaceForce surface{};           ///< proxy, penetration, contact (zero when disabled)
  /// The cutting force before the low-speed cap, N, and the cap itself
  /// (low_speed_damping_n_s_per_m x speed), N, both after the device's
  /// cutting gain: the rendered cutting force is the lower of the two
  /// (kEarthmoving: its horizontal part, the speed the horizontal one;
  /// kContactDrag: the drag along the motion, viscous part aside). Zero for kNone.
  double cutting_uncapped_n = 0.0;
  double cutting_cap_n = 0.0;
};

/// The rendering: validated and device-checked once, then a pure const
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
  /// the device): the rendered soil force x 0.1". Empty when nothing was.
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
