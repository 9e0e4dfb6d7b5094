// What the soil presents to the edge: the depth of undisturbed soil ahead
// of a moving edge (the `d` of the earthmoving equation) and the pile over
// its failure wedge, how deep the edge sits in the soil beside it
// (penetration), and which parts of it a turn drives into soil (twist).
// Pure readings of the height grid, for the step's tool force
// (tool_force.hpp).
//
// Why not section_area / length: the contact is measured against the
// terrain as the previous steps left it, and those steps have already
// lowered every sample the edge passed. On the surface representation the
// terrain at the edge is then interpolated between a cut sample behind it
// and an uncut sample ahead, so the mean depth along the edge falls from the
// full depth to nearly zero and back once per cell the blade crosses (a
// sawtooth at speed / cell size: 50 Hz for 1 m/s on 2 cm cells, which a hand
// feels as vibration). The depth ahead reads the terrain one and a half cell
// diagonals ahead of the edge along its horizontal motion, where no sample
// has been cut yet, so a steady cut gives a steady depth.
#pragma once

#include "terracut/core/blade.hpp"
#include "terracut/core/contact.hpp"
#include "terracut/core/twist.hpp"
#include "terracut/core/grid.hpp"

namespace terracut {

/// Distance ahead of the edge at which the uncut terrain is read: 1.5 cell
/// diagonals, so that every sample the reading interpolates lies ahead of
/// the edge whatever the direction of motion.
double depth_lookahead_m(const GridSpec& spec);

/// The soil ahead of a moving edge: the edge is divided into n equal parts
/// (n = edge length / smallest cell side, in [2, 64]); at each part's
/// centre p the depth of undisturbed soil is read one lookahead ahead along
/// the horizontal direction of motion u,
///   d = min(current, initial surface)(p + u lookahead) - p.y
/// (against the lower of the two surfaces, so a pile the blade pushes is
/// not depth of cut), and parts with d > 0 are engaged. The lookahead
/// reads soil no sample of which the edge has cut yet, so a steady cut
/// gives a steady depth on either representation (the surface at the edge
/// is the trench it made). The parts are summed as one uniform cut with the
/// same sum of d (the section: cohesion, surcharge) and of d^2 (the weight):
/// depth = sum d^2 / sum d, width = (part length) (sum d)^2 / sum d^2, so a
/// part coming into or out of the soil at zero depth changes nothing.
struct SoilAhead {
  /// The cut's equivalent depth, metres (>= 0).
  double depth_m = 0.0;
  /// Mean height of soil piled above the initial surface over the failure
  /// wedge ahead (from the lookahead on, over wedge_per_depth x the part's
  /// depth), weighted by the parts' depths, metres (>= 0).
  double pile_m = 0.0;
  /// The cut's equivalent width: the 3-D length of edge it acts on, m (>= 0).
  double width_m = 0.0;
};

/// The failure wedge's length ahead of the blade per metre of cut depth:
/// cot(45 deg - phi / 2), the passive (Rankine) failure plane, about 2 for
/// a sand's phi of 35 degrees.
inline constexpr double kWedgeLengthPerDepth = 2.0;

/// The depth, width and pile ahead of the edge (see SoilAhead); at each part
/// of the edge the pile is averaged along the motion from the lookahead to
/// wedge_per_depth x that part's depth beyond it, by the midpoint rule on
/// intervals of one cell, or of the part's length in plan where that is
/// longer, or of 1/64 of the reach where that is longer still, the last
/// interval what is left of the reach (so the reading is continuous in the
/// depth); no pile read with wedge_per_depth 0, nor where the reach
/// overflows. A motion without a horizontal part or
/// a non-finite input gives zeros. Allocates nothing.
SoilAhead soil_ahead(const HeightGrid& grid, Representation representation, const Segment& edge,
                     Vec3 velocity_m_per_s, double lookahead_m,
                     double wedge_per_depth = kWedgeLengthPerDepth) noexcept;

/// How deep an edge sits in the soil beside it: what the penetration model
/// (core/forces.hpp) is given.
struct Embedment {
  /// The equivalent depth (as SoilAhead's) of the parts of the edge below
  /// the soil beside them, each part's depth
  ///   (surface_y_m(p + n * lookahead) + surface_y_m(p - n * lookahead)) / 2 - p.y
  /// with n the unit horizontal normal of the edge (its two faces), metres,
  /// >= 0. The soil beside the edge, not at it: the cut has already lowered
  /// the samples the edge passed through, so the surface at the edge is the
  /// edge's own height (the trench it made). A vertical edge reads four
  /// sides (+-X, +-Z).
  double depth_m = 0.0;
  /// Their equivalent length (3-D), metres, >= 0.
  double length_m = 0.0;
};

/// The embedment of the edge (see Embedment), over n parts as soil_ahead
/// divides the edge. A non-finite input gives zeros. Allocates nothing.
Embedment embedment(const HeightGrid& grid, Representation representation, const Segment& edge,
                    double lookahead_m) noexcept;

/// The parts of the edge that meet soil when the blade turns about the
/// vertical through `centre` at yaw_rate_rad_per_s (see TwistEngagement in
/// core/forces.hpp): the part at signed distance s moves along
/// sign(omega s) n; it is engaged when the soil one lookahead ahead along
/// that motion is above it. mean_depth_m receives the mean depth of those
/// parts (0 when none). Zero yaw rate, a vertical edge or a non-finite input
/// give no engagement. Allocates nothing.
TwistEngagement twist_engagement(const HeightGrid& grid, Representation representation,
                                 const Segment& edge, Vec3 centre, double yaw_rate_rad_per_s,
                                 double lookahead_m, double& mean_depth_m) noexcept;

}  // namespace terracut
