// The physical force on the tool: what a force sensor between a real blade
// and its arm would read, in world newtons, from the soil and from the rigid
// bodies the step's listeners simulate. It is a result of every step
// (StepOutput::force, simulation.hpp), whatever program drives the
// simulation, and nothing a haptic device can render (force scale, device
// limits, the low-speed damper) changes it: the haptic loop renders the
// device's force from it (forces.hpp).
//
// Parts, each a force on the tool (world frame, Y up):
//   cutting      the earthmoving equation with side failure
//                (earthmoving.hpp) at the depth of undisturbed soil ahead
//                and the engaged width across the motion, without the pile;
//   surcharge    what the pile ahead adds through its weight on the wedge
//                (the surcharge's terms of the same solution);
//   penetration  the bearing under the edge and the friction on its faces
//                while it moves down, the faces' friction while it moves up;
//   twist        the net force of turning a buried blade (and its torque);
//   load         the soil a bucket carries: its weight and its inertia,
//                -m a with the tool's acceleration;
//   bodies       the step listeners' force (e.g. the Bullet world's plate).
// The tool's motion is the step's own (the pose's change over the step):
// the force opposes that motion, and is zero at rest (no low-speed cap).
#pragma once

#include "terracut/core/blade.hpp"
#include "terracut/core/contact.hpp"
#include "terracut/core/earthmoving.hpp"
#include "terracut/core/grid.hpp"
#include "terracut/core/material.hpp"
#include "terracut/core/penetration.hpp"
#include "terracut/core/twist.hpp"

namespace terracut {

/// Below this speed a component of the tool's motion is rest, m/s: the
/// soil's resistance is mobilised by motion, and the float rounding of a
/// held pose (about 1e-13 m/s at 1 kHz for positions of metres) must not
/// read as motion, which would give the whole resistance in a random
/// direction. A micrometre per second is slower than any cut.
inline constexpr double kRestSpeed_m_per_s = 1e-6;
/// The same for the yaw rate, rad/s.
inline constexpr double kRestYawRate_rad_per_s = 1e-6;

/// The tool's motion over a step, from its poses (world frame).
struct ToolMotion {
  Vec3 velocity_m_per_s{};       ///< the blade centre's displacement over the step x the rate, m/s
  Vec3 acceleration_m_per_s2{};  ///< the velocity's change over the step x the rate, m/s^2
  double yaw_rate_rad_per_s = 0.0;  ///< the edge's turn about world +Y over the step x the rate, rad/s
  /// The unit horizontal direction of the stroke's latest horizontal
  /// motion (zero before any): where the soil ahead of the edge is read, so
  /// that a blade held still in a cut keeps the resistance it would meet
  /// (ToolForce::earthmoving) while the force itself is zero at rest.
  Vec3 heading{};
};

/// What the physical force model reads; derived once from the simulation's
/// parameters (validated there).
struct ToolForceParams {
  EarthmovingParams earthmoving{};  ///< the material, the blade's rake, side failure
  double edge_thickness_m = 0.02;   ///< the cutting edge's thickness, m (penetration)
  double blade_length_m = 1.0;      ///< m
  Representation representation = Representation::kSurface;
  /// Soil flows: a pile above the initial surface ahead is a surcharge, not depth.
  bool piles = false;
};

/// The physical force of one step and what it was computed from.
struct ToolForce {
  // --- what the soil presented ---------------------------------------
  double cut_depth_m = 0.0;        ///< depth of undisturbed soil ahead of the edge, m
  double cut_width_m = 0.0;        ///< 3-D length of edge with soil ahead, m
  double engaged_width_m = 0.0;    ///< that length across the horizontal motion, m
  double pile_m = 0.0;             ///< mean height of soil piled over the failure wedge, m
  double surcharge_pa = 0.0;       ///< the pile's weight on the wedge, Pa
  double embedment_depth_m = 0.0;  ///< the edge's depth below the soil beside it, m
  double embedded_length_m = 0.0;  ///< the length of edge that deep, m
  TwistEngagement twist{};         ///< the parts a turn drives into soil
  double twist_depth_m = 0.0;      ///< their mean depth, m
  double twist_resistance_n_per_m = 0.0;  ///< the cutting force per metre of edge at that depth, N/m
  Vec3 edge_normal{};              ///< Y x the edge's horizontal direction, unit (zero for a vertical edge): twist_n's direction
  double load_mass_kg = 0.0;       ///< soil carried in a bucket, kg
  // --- the models' solutions ------------------------------------------
  /// The soil's resistance along ToolMotion::heading, with the pile's
  /// surcharge (its parts inside): mobilised as cutting_n + surcharge_n
  /// while the tool moves horizontally, available to a rendering at rest.
  EarthmovingResult earthmoving{};
  PenetrationResult penetration{};
  // --- the parts, world N ---------------------------------------------
  Vec3 cutting_n{};
  Vec3 surcharge_n{};
  Vec3 penetration_n{};
  Vec3 twist_n{};
  double twist_torque_n_m = 0.0;  ///< about world +Y, N m
  Vec3 load_n{};
  Vec3 bodies_n{};
  /// The sum of the parts, world N.
  Vec3 total_n{};
};

/// The soil's force on the tool with the blade's edge at `edge` (centre
/// `centre`), moving as `motion`, over the grid after the step's cut and
/// soil phase, and a bucket carrying bucket_load_m3. lookahead_m: where the
/// undisturbed soil is read ahead of the edge (depth_lookahead_m). bodies_n
/// is left zero (the simulation adds the listeners'). Allocates nothing,
/// never throws; non-finite inputs give non-finite outputs.
ToolForce soil_force_on_tool(const ToolForceParams& params, const HeightGrid& grid,
                             const Segment& edge, Vec3 centre, const ToolMotion& motion,
                             double bucket_load_m3, double lookahead_m) noexcept;

}  // namespace terracut
