// The push of soil that flows on the rigid bodies it banks against: the
// parameters of TerrainWorld's pile room (src/bullet/pile_pressure.cpp;
// docs/bullet.md, "Piles against bodies").
#pragma once

#include <string>

namespace terracut::bullet {

/// The push of soil that flows on the bodies it banks against (docs/bullet.md,
/// "Piles against bodies"). The soil keeps one sample away from a body's
/// footprint (soil_obstacle), so that no heightfield triangle ramps from a
/// pile under the body's edge; the pile's push is Rankine's active earth
/// pressure on a smooth vertical face instead, horizontal, per unit width
///   P = 0.5 K gamma h^2,  K = tan^2(45 deg - phi / 2),
/// acting at h / 3 above the body's lowest point along the face's inward
/// normal, with h the soil's height above that point on the first sample
/// outside the kept-free ring straight out from the face (at most the
/// body's height). A box's faces are its own four side faces (a yawed box
/// is pushed along their normals); a sphere's or a cylinder's, the four
/// sides of its bounding box.
struct PilePressureSpec {
  bool enabled = false;                   ///< false: no earth pressure (soil that vanishes)
  /// gamma: unit weight of the piled soil, N/m^3, in (0, 1e9] (the range of
  /// SoilMaterial::unit_weight_n_per_m3). Default: dry sand, as SoilMaterial's
  /// dry_sand preset (Das). BodiesListener sets it from the simulation's
  /// soil material.
  double unit_weight_n_per_m3 = 16.25e3;
  /// phi: friction angle of the piled (loose) soil, degrees, in (0, 80]; a
  /// loose cohesionless pile's is about its angle of repose.
  double friction_angle_deg = 34.0;
  /// Soil in a body's ring up to this height above what stays there
  /// (TerrainWorld::shed_rings) is left in place, metres, in [0, 0.01].
  /// Bullet's solver lets a resting body settle by fractions of a micrometre
  /// every few steps; shedding that much soil changed the triangles under
  /// the body's edge, which woke it and dropped its contacts, so it settled
  /// again and never slept. The default is the merged heightfield's coplanar
  /// tolerance (TerrainWorldParams::merge_tolerance_m).
  double shed_tolerance_m = 1e-5;
};

/// Returns an empty string when the spec is valid (or not enabled), else a
/// message naming the field ("pile.friction_angle_deg ...").
std::string validate(const PilePressureSpec& spec);

}  // namespace terracut::bullet
