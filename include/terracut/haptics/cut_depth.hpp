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

}  // namespace terracut::haptics
