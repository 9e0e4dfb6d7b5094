// The physical force on the tool. See tool_force.hpp; the models and their
// sources: docs/forces.md.
#include "terracut/core/tool_force.hpp"

#include <cmath>

#include "terracut/core/soil_ahead.hpp"

namespace terracut {

ToolForce soil_force_on_tool(const ToolForceParams& params, const HeightGrid& grid,
                             const Segment& edge, Vec3 centre, const ToolMotion& motion,
                             double bucket_load_m3, double lookahead_m) noexcept {
  ToolForce f;
  const SoilMaterial& soil = params.earthmoving.soil;
  // The motion that mobilises the soil: slower than kRestSpeed_m_per_s
  // (horizontally, vertically) is rest.
  Vec3 v = motion.velocity_m_per_s;
  if (std::hypot(v.x, v.z) < kRestSpeed_m_per_s) v.x = v.z = 0.0;
  if (std::abs(v.y) < kRestSpeed_m_per_s) v.y = 0.0;
  const double yaw_rate =
      std::abs(motion.yaw_rate_rad_per_s) < kRestYawRate_rad_per_s ? 0.0 : motion.yaw_rate_rad_per_s;

  // The cut: the undisturbed soil ahead along the heading, the pile over
  // its wedge, and the width across it (a blade sliding along its own edge
  // cuts nothing).
  const Vec3 heading = motion.heading;
  const SoilAhead ahead = soil_ahead(grid, params.representation, edge, heading, lookahead_m,
                                     params.piles ? kWedgeLengthPerDepth : 0.0);
  f.cut_depth_m = ahead.depth_m;
  f.cut_width_m = ahead.width_m;
  f.pile_m = ahead.pile_m;
  f.surcharge_pa = soil.unit_weight_n_per_m3 * ahead.pile_m;
  const Vec3 e = edge.b - edge.a;
  const double e_len = length(e);
  const double heading_xz = std::hypot(heading.x, heading.z);
  f.engaged_width_m = ahead.width_m;
  if (e_len > 0.0 && heading_xz > 0.0)
    f.engaged_width_m *=
        length(cross(e * (1.0 / e_len), Vec3{heading.x / heading_xz, 0.0, heading.z / heading_xz}));
  f.earthmoving = earthmoving_force(params.earthmoving, f.engaged_width_m, f.cut_depth_m, f.surcharge_pa);
  const Vec3 all = earthmoving_world_force(f.earthmoving, v, kUncapped_n_s_per_m);
  // The pile's part, resolved as the whole (the same direction of motion).
  EarthmovingResult pile;
  pile.horizontal_n = f.earthmoving.surcharge_horizontal_n;
  pile.vertical_n = f.earthmoving.surcharge_vertical_n;
  f.surcharge_n = earthmoving_world_force(pile, v, kUncapped_n_s_per_m);
  f.cutting_n = all - f.surcharge_n;

  // Penetration: how deep the edge sits in the soil beside it.
  const Embedment emb = embedment(grid, params.representation, edge, lookahead_m);
  f.embedment_depth_m = emb.depth_m;
  f.embedded_length_m = emb.length_m;
  f.penetration = penetration_resistance(soil, params.edge_thickness_m, emb.length_m, emb.depth_m,
                                         f.surcharge_pa);
  f.penetration_n = penetration_world_force(f.penetration, v, kUncapped_n_s_per_m);

  // Twist: the parts of the edge a turn drives into soil, each resisted by
  // the cutting force per metre of width (the 2-D equation) at their depth.
  const double eh = std::hypot(e.x, e.z);
  if (eh > 0.0) f.edge_normal = Vec3{e.z / eh, 0.0, -e.x / eh};
  if (yaw_rate != 0.0) {
    f.twist = twist_engagement(grid, params.representation, edge, centre, yaw_rate,
                               lookahead_m, f.twist_depth_m);
    if (f.twist.engaged_length_m > 0.0) {
      EarthmovingParams per_metre = params.earthmoving;
      per_metre.side_failure = false;
      f.twist_resistance_n_per_m = earthmoving_force(per_metre, 1.0, f.twist_depth_m).horizontal_n;
      const TwistResult t = twist_resistance(f.twist_resistance_n_per_m, f.twist, yaw_rate,
                                             kUncapped_n_s_per_m, params.blade_length_m);
      f.twist_torque_n_m = t.torque_n_m;
      f.twist_n = f.edge_normal * t.net_force_n;
    }
  }

  // The soil a bucket carries: its weight, and its inertia against the
  // tool's acceleration.
  const double load_n = soil.unit_weight_n_per_m3 * bucket_load_m3;
  f.load_mass_kg = load_n / kStandardGravity_m_per_s2;
  f.load_n = Vec3{0.0, -load_n, 0.0} + motion.acceleration_m_per_s2 * (-f.load_mass_kg);

  f.total_n = f.cutting_n + f.surcharge_n + f.penetration_n + f.twist_n + f.load_n;
  return f;
}

}  // namespace terracut
