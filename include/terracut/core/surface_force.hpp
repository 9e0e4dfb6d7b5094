// The surface model, a rendering of the ground for a haptic device: a proxy
// (god-object) kept on the terrain surface above the device point and a
// spring-damper between them, so the tool point cannot sink into the soil
// without resistance (in the spirit of Zilles & Salisbury 1995). It is not
// a force of the soil on the tool (tool_force.hpp has those).
#pragma once

#include "terracut/core/math.hpp"

namespace terracut {

/// Parameters of the surface model, world units; read-only during a run.
struct SurfaceParams {
  /// K: spring between proxy and device point, N/m (world), finite, > 0.
  double stiffness_n_per_m = 100e3;
  /// B: damping of the device's vertical velocity while below the surface,
  /// N s/m (world), finite, >= 0.
  double damping_n_s_per_m = 12.5;
};

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
/// never pulling down, and above it F = 0. velocity: device point, world m/s.
SurfaceForce surface_force(const SurfaceParams& params, Vec3 device_point_m, Vec3 velocity_m_per_s,
                           double surface_y_m) noexcept;

}  // namespace terracut
