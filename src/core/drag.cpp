// The saturated damper and the contact drag. See drag.hpp.
#include "terracut/core/drag.hpp"

#include <cmath>

namespace terracut {

double saturated_drag_n(double force_n, double speed_m_per_s,
                        double low_speed_damping_n_s_per_m) noexcept {
  if (speed_m_per_s == 0.0) return 0.0;
  double ramp = low_speed_damping_n_s_per_m * speed_m_per_s;
  return ramp < force_n ? ramp : force_n;
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

}  // namespace terracut
