// The surface model's proxy and spring-damper. See surface_force.hpp.
#include "terracut/core/surface_force.hpp"

namespace terracut {

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

}  // namespace terracut
