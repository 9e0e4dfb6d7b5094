// Settings of a haptic session: the `haptics:` section of a scenario file as
// plain data (its reader is terracut/haptics/settings_yaml.hpp). Read-only
// during a run; validated once, by LoopParams (loop.hpp), which also builds
// the force model from them.
//
// Frames. The world frame is right-handed with Y up (ground plane X-Z). A
// haptic device reports positions in its own frame; terracut uses CHAI3D's
// convention for it (CHAI3D's device frame, as its device drivers report
// positions: https://www.chai3d.org): origin at the workspace centre,
// x toward the operator, y to the operator's right, z up, metres. With
// yaw_deg = 0 the operator stands on the +Z side of the scene looking along
// -Z (as an OpenGL camera does), so
//
//   device x (toward operator) -> world +Z
//   device y (right)           -> world +X
//   device z (up)              -> world +Y
//
// i.e. world = offset + scale * Ry(yaw) * P * device, with P the cyclic
// permutation (x, y, z) -> (y, z, x) written out above and Ry(yaw) a rotation
// of yaw_deg about world +Y (positive turns +X toward -Z). Forces go back
// the other way: device force = P^T * Ry(yaw)^T * (device-newton force along
// world axes). The scale applies to positions only; forces are scaled by
// ForceModelParams::force_scale.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "terracut/core/enum_names.hpp"
#include "terracut/core/forces.hpp"
#include "terracut/core/math.hpp"
#include "terracut/core/ranges.hpp"
#include "terracut/core/safety.hpp"

namespace terracut::haptics {

using terracut::to_string;  // the enumerations' names (core/enum_names.hpp)

/// Which device drives the tool.
enum class DeviceKind {
  kScript,  ///< the tool follows the scenario's cut keyframes exactly
  kSim,     ///< a simulated operator hand pulled along the cut's path; feels the force
  kUdp,     ///< an external device process over the UDP bridge protocol
};
/// Its names (core/enum_names.hpp: to_string, parse_enum).
inline constexpr EnumName<DeviceKind> kDeviceKindNames[] = {
    {DeviceKind::kScript, "script"},
    {DeviceKind::kSim, "sim"},
    {DeviceKind::kUdp, "udp"},
};
constexpr std::span<const EnumName<DeviceKind>> enum_names(DeviceKind) { return kDeviceKindNames; }

/// Mapping between the device's workspace and the world (see the file comment).
struct WorkspaceMapping {
  /// World metres per device metre, finite, > 0. A Novint Falcon's workspace
  /// has a radius of about 0.04 m, so 12 maps it to about +-0.5 m of world.
  double scale = 10.0;
  /// World position of the device's workspace centre (device origin), metres, finite.
  Vec3 offset_m{};
  /// Where the operator faces: rotation of the device frame about world +Y,
  /// degrees, finite, in [-360, 360]. 0: operator looks along world -Z.
  double yaw_deg = 0.0;
};

/// Where the surface (proxy) model holds the tool point.
enum class SurfaceReference {
  /// The rigid ground under the soil (world y = terrain origin y): the blade
  /// cuts soil, and the proxy spring stops it at the floor it cannot cut.
  /// The default, because the blade removes whatever it passes through.
  kGround,
  /// The terrain surface after the step's cut (surface_y_m at the tool point).
  /// While a blade advances at depth d, the uncut sample just ahead of it
  /// lifts this surface by up to d above the blade (a sawtooth of period one
  /// cell), so use it to feel shapes, not while cutting deep.
  kTerrain,
};
/// Its names (core/enum_names.hpp: to_string, parse_enum).
inline constexpr EnumName<SurfaceReference> kSurfaceReferenceNames[] = {
    {SurfaceReference::kGround, "ground"},
    {SurfaceReference::kTerrain, "terrain"},
};
constexpr std::span<const EnumName<SurfaceReference>> enum_names(SurfaceReference) { return kSurfaceReferenceNames; }

/// The simulated operator hand of the `sim` device: a point mass held by the
/// device, pulled by a spring-damper toward a target that moves along the
/// cut's path; the rendered force acts on it. Device units and frame.
struct SimHandParams {
  /// Mass of the hand plus the device's moving parts, kg, finite, > 0.
  double mass_kg = 0.15;
  /// Stiffness of the arm pulling the hand toward the target, N/m, finite, > 0.
  double stiffness_n_per_m = 400.0;
  /// Damping of the arm relative to the target's velocity, N s/m, finite, >= 0.
  double damping_n_s_per_m = 8.0;
  /// Integration sub-steps per loop period (semi-implicit Euler; the force
  /// is held over the period, as a device driver does), in [1, 1000].
  int substeps = 20;
  /// Start position of the hand relative to the path's first point, device
  /// metres, finite (0: start on the path).
  Vec3 start_offset_m{};
};

/// The UDP bridge endpoint (the loop side binds it; terracut-device sends to it).
struct UdpSettings {
  /// IPv4 or IPv6 address to bind, text. Default loopback only: a bridge on
  /// another host is an explicit choice.
  std::string address = "127.0.0.1";
  /// UDP port, in [1, 65535].
  int port = 47000;
};

/// Everything a haptic session needs besides the scenario's terrain and blade.
struct HapticSettings {
  // The loop's rate is the simulation's (the scenario's rate_hz, or a
  // program's override): LoopParams takes it (haptics/loop.hpp).
  /// Device backend.
  DeviceKind device = DeviceKind::kSim;
  /// Name of the scenario cut whose keyframes the script and sim devices
  /// follow; empty: the first cut of the scenario's sequence.
  std::string cut;
  /// Session length, seconds, finite, > 0, at most 86400; nullopt: the path's
  /// duration plus settle_s for script and sim, 30 s for udp.
  std::optional<double> duration_s;
  /// Extra time after the path's end (script, sim default duration), seconds, finite, >= 0.
  double settle_s = 0.5;
  WorkspaceMapping workspace{};
  /// Fixed tool orientation, Euler degrees (extrinsic X-Y-Z, as keyframes);
  /// nullopt: the device's orientation when it reports one (script, sim:
  /// the cut's keyframes; udp: when the bridge sets the orientation flag),
  /// else the cut's first keyframe.
  std::optional<Vec3> tool_rotation_deg;
  /// Cut-off of the first-order low-pass on the backward-difference velocity,
  /// Hz, finite, >= 0 and below the loop's rate / 2 (LoopParams checks that);
  /// 0 disables the filter.
  double velocity_cutoff_hz = 100.0;
  SurfaceReference surface_reference = SurfaceReference::kGround;
  /// The rendering of the physical force on the device, and the device's
  /// limits (core/forces.hpp). forces.workspace_scale and
  /// forces.loop_rate_hz are derived (from workspace.scale and the loop's
  /// rate) and forces.max_contact_length_m from the blade length when the
  /// loop is built.
  ForceModelParams forces{};
  /// Safety limits; safety.max_force_n must not exceed forces.device.max_force_n.
  SafetyParams safety{};
  SimHandParams hand{};
  UdpSettings udp{};
};

/// Returns an empty string when the settings are valid, else a message that
/// starts with the field's path (e.g. "workspace.scale must be ..."). Checks
/// every field, including forces and safety (not the device-rendering check,
/// which the ForceModel constructor makes, nor the checks against the loop's
/// rate, which LoopParams makes).
std::string validate(const HapticSettings& s);
/// The ranges of HapticSettings' own numbers, which validate() checks
/// (core/ranges.hpp; forces and safety: force_ranges(), safety_ranges()).
std::span<const Range> haptic_settings_ranges();

/// The settings with the derived force fields filled in: forces.workspace_scale
/// = workspace.scale, forces.loop_rate_hz = rate_hz (the loop's) and
/// forces.max_contact_length_m = blade_length_m (> 0).
HapticSettings with_derived_fields(HapticSettings settings, double blade_length_m, double rate_hz);

}  // namespace terracut::haptics
