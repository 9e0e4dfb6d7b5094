// The depth of material ahead of a moving cutting edge: the `d` of the
// earthmoving equation.
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
#include "terracut/core/forces.hpp"
#include "terracut/core/grid.hpp"

namespace terracut::haptics {

/// Distance ahead of the edge at which the uncut terrain is read: 1.5 cell
/// diagonals, so that every sample the reading interpolates lies ahead of
/// the edge whatever the direction of motion.
double depth_lookahead_m(const GridSpec& spec);

/// Mean depth of material ahead of the edge, metres (>= 0): the edge is
/// divided into n equal parts (n = edge length / smallest cell side, in
/// [2, 64]); at each part's centre p the depth is
///   surface_y_m(p + u * lookahead) - p.y
/// with u the unit horizontal (X-Z) direction of motion; the mean is over the
/// parts where that depth is positive (0 when none is). A motion without a
/// horizontal part (|v_xz| == 0) or a non-finite input gives 0. Allocates nothing.
double depth_ahead_m(const HeightGrid& grid, Representation representation, const Segment& edge,
                     Vec3 velocity_m_per_s, double lookahead_m) noexcept;

/// The depth ahead (depth_ahead_m) with the length of edge it was read over.
struct CutAhead {
  double depth_m = 0.0;
  /// The 3-D length of the parts of the edge with soil ahead of them, m,
  /// >= 0: the earthmoving model's width. The contact length would do in a
  /// steady cut, but on the surface representation the contact drops to
  /// almost nothing for a tick or a few whenever a rising blade's edge passes
  /// above the interpolated surface between a sample it cut lower and the
  /// next (a flicker as the blade leaves the soil); the soil ahead is steady.
  double width_m = 0.0;
};
CutAhead cut_ahead(const HeightGrid& grid, Representation representation, const Segment& edge,
                   Vec3 velocity_m_per_s, double lookahead_m) noexcept;

/// The soil ahead of the edge when soil flows (SoilModel::kFlow), where the
/// surface ahead may be a pile the blade pushes.
struct SoilAhead {
  /// Depth of the undisturbed soil ahead, metres (>= 0): depth_ahead_m's
  /// reading taken against the lower of the current and the initial
  /// surface, so a pile does not count as depth of cut.
  double depth_m = 0.0;
  /// Mean height of soil piled above the initial surface over the failure
  /// wedge ahead (from the lookahead on, over wedge_per_depth x the local
  /// depth), metres (>= 0).
  double pile_m = 0.0;
  /// The 3-D length of the edge with undisturbed soil ahead, m (as CutAhead::width_m).
  double width_m = 0.0;
};

/// The failure wedge's length ahead of the blade per metre of cut depth:
/// cot(45 deg - phi / 2), the passive (Rankine) failure plane, about 2 for
/// a sand's phi of 35 degrees.
inline constexpr double kWedgeLengthPerDepth = 2.0;

/// The depth and the pile ahead of the edge (see SoilAhead), sampled as
/// depth_ahead_m samples it; at each part of the edge the pile is averaged
/// over up to 64 points along the motion from the lookahead to
/// wedge_per_depth x that part's depth beyond it. Allocates nothing.
SoilAhead soil_ahead(const HeightGrid& grid, Representation representation, const Segment& edge,
                     Vec3 velocity_m_per_s, double lookahead_m,
                     double wedge_per_depth = kWedgeLengthPerDepth) noexcept;

/// How deep an edge sits in the soil beside it: what the penetration model
/// (core/forces.hpp) is given.
struct Embedment {
  /// Mean, over the parts of the edge below the soil beside them, of
  ///   (surface_y_m(p + n * lookahead) + surface_y_m(p - n * lookahead)) / 2 - p.y
  /// with n the unit horizontal normal of the edge (its two faces), metres,
  /// >= 0. The soil beside the edge, not at it: the cut has already lowered
  /// the samples the edge passed through, so the surface at the edge is the
  /// edge's own height (the trench it made). A vertical edge reads four
  /// sides (+-X, +-Z).
  double depth_m = 0.0;
  /// The 3-D length of those parts, metres, >= 0.
  double length_m = 0.0;
};

/// The embedment of the edge (see Embedment), over n parts as depth_ahead_m
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

}  // namespace terracut::haptics
