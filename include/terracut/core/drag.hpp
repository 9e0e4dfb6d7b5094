// Resistance to motion regularised at low speed, and the paper's contact
// drag (a rendering model: a drag per metre of blade in the soil).
//
// The saturated damper min(F, beta |v|) is how a force that opposes motion is
// rendered on a haptic device: a pure -F v/|v| flips with the velocity's
// sign and chatters at rest, while below F / beta it grows linearly with the
// speed, with a slope the device can render. With beta = kUncapped (+inf)
// it is the physical force itself: F whenever the tool moves, 0 at rest.
// docs/forces.md derives every model with its sources.
#pragma once

#include <limits>
#include <string>

#include "terracut/core/math.hpp"

namespace terracut {

/// The low-speed slope that caps nothing: with it every regularised force
/// below is the physical force (F when moving, 0 at rest).
inline constexpr double kUncapped_n_s_per_m = std::numeric_limits<double>::infinity();

/// Magnitude of a force that opposes motion, regularised at low speed as a
/// saturated damper: min(force_n, low_speed_damping * speed). Returns 0 at
/// zero speed, never NaN for finite inputs (nor for an infinite slope).
/// force_n >= 0, speed >= 0, low_speed_damping > 0 (N s/m) or kUncapped_n_s_per_m.
double saturated_drag_n(double force_n, double speed_m_per_s,
                        double low_speed_damping_n_s_per_m) noexcept;

/// Parameters of the contact-drag model; read-only during a run.
struct ContactDragParams {
  /// k_drag: drag per metre of blade in contact, N/m, finite, >= 0.
  double drag_n_per_m = 400.0;
  /// c_viscous: extra viscous drag per metre of contact per m/s of speed,
  /// N/(m * m/s) = N s/m^2, finite, >= 0. 0 disables the viscous term.
  double viscous_n_s_per_m2 = 0.0;
};

/// World force on the tool from the contact-drag model:
///   F = -saturated_drag_n(k_drag * L, |v|, low_speed_damping) * v/|v| - c_viscous * L * v
/// with L = contact_length_m (>= 0; negative counts as 0) and v the tool's
/// velocity (world, m/s). Zero velocity gives zero force (no NaN). Above the
/// saturation speed k_drag * L / low_speed_damping the force is exactly
/// linear in L. Parameters are trusted (validate once before the run).
Vec3 contact_drag_force(const ContactDragParams& params, double contact_length_m,
                        Vec3 velocity_m_per_s, double low_speed_damping_n_s_per_m) noexcept;

}  // namespace terracut
