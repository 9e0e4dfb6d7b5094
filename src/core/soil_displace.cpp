// Soil that flows, the displacement (soil.hpp): what the blade's edge cuts
// is pushed ahead of it and put down where an avalanche down the face would
// leave it; the blade marked as a wall for the relaxation.
#include "terracut/core/soil.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "soil_internal.hpp"

namespace terracut {

using namespace soil_internal;

void SoilFlow::before_cut(HeightGrid& grid, const Segment& from, const Segment& to) {
  // (A settle under way goes on in after_cut, once this step's displacement
  // and its spill round the blade's ends have had their share of the cap.)
  // The bounding rectangle of the four endpoints, plus a cell.
  const GridSpec& spec = grid.spec();
  double u0 = 1e300, u1 = -1e300, v0 = 1e300, v1 = -1e300;
  for (const Vec3& p : {from.a, from.b, to.a, to.b}) {
    const double u = to_cells(p.x, spec.origin_m.x, dx_), v = to_cells(p.z, spec.origin_m.z, dz_);
    u0 = std::min(u0, u);
    u1 = std::max(u1, u);
    v0 = std::min(v0, v);
    v1 = std::max(v1, v);
  }
  Rect r;
  r.c0 = int(std::clamp(std::floor(u0) - 1.0, 0.0, double(cols_)));
  r.c1 = int(std::clamp(std::floor(u1) + 2.0, 0.0, double(cols_)));
  r.r0 = int(std::clamp(std::floor(v0) - 1.0, 0.0, double(rows_)));
  r.r1 = int(std::clamp(std::floor(v1) + 2.0, 0.0, double(rows_)));
  before_rect_ = r;
  before_.resize(std::size_t(r.area()));
  after_cut_.resize(std::size_t(r.area()));
  const float* h = grid.heights();
  std::size_t k = 0;
  for (int row = r.r0; row < r.r1; ++row)
    for (int c = r.c0; c < r.c1; ++c) before_[k++] = h[std::int64_t(row) * cols_ + c];
}

void SoilFlow::mark_blade(const HeightGrid& grid, const Segment& from, const Segment& edge) {
  // The cells whose centres lie within kBladeRadiusCells of the edge in
  // plan: row by row, the columns where the row's line can meet that
  // capsule (the part of the edge within the radius of the row, widened by
  // the radius), each tested exactly.
  const GridSpec& spec = grid.spec();
  const double radius = kBladeRadiusCells * std::max(dx_, dz_);
  const Vec3 d = edge.b - edge.a;
  const double plan_length = std::hypot(d.x, d.z);
  blade_ = {edge.a.x, edge.a.z, d.x, d.z, edge.a.y - spec.origin_m.y, d.y, plan_length > 0.0};
  if (!blade_.present) return;
  const double len2 = plan_length * plan_length;
  blade_.len2 = d.x * d.x + d.z * d.z;
  blade_.len = std::sqrt(blade_.len2);
  const double half_num = 0.5 * (std::abs(d.z) * dx_ + std::abs(d.x) * dz_);
  blade_.half = half_num / blade_.len;
  // Where |nb| is certainly below or above half_num (relative rounding of
  // the quotients ~1e-16; the margin 1e-12), |nb| / len < half is decided
  // without dividing (blade_blocks).
  blade_.half_lo = half_num * (1.0 - 1e-12);
  blade_.half_hi = half_num * (1.0 + 1e-12);
  // Each end's motion across the line since `from` (motion_origin's origin
  // by the ends; any motion counts).
  const auto across = [&](const Vec3& was, const Vec3& is) {
    const double n = d.x * (is.z - was.z) - d.z * (is.x - was.x);
    return std::abs(n) > std::max(1e-9 * half_num, coord_rounding_m_ * plan_length) ? n : 0.0;
  };
  blade_.across_a = across(from.a, edge.a);
  blade_.across_b = across(from.b, edge.b);
  const double zlo = std::min(edge.a.z, edge.b.z) - radius, zhi = std::max(edge.a.z, edge.b.z) + radius;
  const int r0 = floor_within(to_cells(zlo, spec.origin_m.z, dz_) - 0.5, 0, rows_);
  const int r1 = ceil_within(to_cells(zhi, spec.origin_m.z, dz_) - 0.5, -1, rows_ - 1);
  for (int r = r0; r <= r1; ++r) {
    const double z = spec.origin_m.z + (r + 0.5) * dz_;
    // The edge's parameters where it is within the radius of this row's z.
    double s0 = 0.0, s1 = 1.0;
    if (std::abs(d.z) > 1e-12) {
      const double sa = (z - radius - edge.a.z) / d.z, sb = (z + radius - edge.a.z) / d.z;
      s0 = std::max(0.0, std::min(sa, sb));
      s1 = std::min(1.0, std::max(sa, sb));
      if (s0 > s1) continue;
    } else if (std::abs(z - edge.a.z) > radius) {
      continue;
    }
    const double xa = edge.a.x + d.x * s0, xb = edge.a.x + d.x * s1;
    const int c0 = floor_within(to_cells(std::min(xa, xb) - radius, spec.origin_m.x, dx_) - 0.5, 0, cols_);
    const int c1 = ceil_within(to_cells(std::max(xa, xb) + radius, spec.origin_m.x, dx_) - 0.5, -1, cols_ - 1);
    for (int c = c0; c <= c1; ++c) {
      const std::uint32_t i = std::uint32_t(std::int64_t(r) * cols_ + c);
      const double x = spec.origin_m.x + (c + 0.5) * dx_;
      const double s = std::clamp(((x - edge.a.x) * d.x + (z - edge.a.z) * d.z) / len2, 0.0, 1.0);
      const double ex = x - (edge.a.x + d.x * s), ez = z - (edge.a.z + d.z * s);
      if (ex * ex + ez * ez > radius * radius) continue;
      set_flag(i, kNearBlade);
      marked_.push_back(i);
    }
  }
}

void SoilFlow::clear_blade() {
  for (std::uint32_t i : marked_) clear_flag(i, kNearBlade);
  marked_.clear();
  blade_.present = false;
}

void SoilFlow::displace(HeightGrid& grid, const Segment& from, const Segment& moved_from, const Segment& to,
                        double bucket_room_m3, SoilStepResult& out) {
  const GridSpec& spec = grid.spec();
  const double cell = std::max(dx_, dz_);
  // The edge's horizontal normal, turned to the side it moved to.
  const Vec3 e = to.b - to.a;
  double nx = -e.z, nz = e.x;
  const double plan_length = std::hypot(nx, nz);
  // Which way the cut soil goes, at each point of the edge: that point's
  // motion across the edge's line in this step where that is more than
  // rounding (every sample the edge cut in the step lies in what it swept,
  // on the side it came from in the step), else its motion since the blade
  // last moved (motion_origin: a blade standing still, going straight down
  // or sliding along its line keeps the way it went), else none (each cut
  // sample's soil to its own side, a centre on the line to the side the
  // edge's normal (-e.z, e.x) faces, which is the blade frame's +Z for a
  // level blade). (A test of a hundredth of a cell's
  // motion in the step took a slow blade for one at rest, 0.1 m/s on 1 cm
  // cells, and put the cut of each centre the edge had just passed on that
  // centre's own side: behind the blade, at every row.) A point's motion is
  // its ends' motions interpolated along the edge: a turning blade's two
  // parts can go opposite ways (one way for the whole edge, its midpoint's,
  // pushed the cut of the part going forward behind it when a hand's tremor
  // took the midpoint back: a 0.55 m blade on 2 cm cells, 2 cm behind it).
  // Rounding: a billionth of a cell, or the rounding of the world
  // coordinates where the terrain lies far from the origin (a
  // georeferenced terrain: at 1e7 m a double's step is 1.9e-9 m, more than
  // a billionth of a 1 cm cell), so that which side a centre on the line
  // is on does not turn with where the terrain lies. (Decided by the sign
  // of its distance alone, a centre on the line of a blade set down at
  // rest went ahead of it with the terrain at the origin and behind it 1 km
  // out: 1.7 cm behind a 1.1 m blade on 2 cm cells once it moved on.)
  const double rounding = std::max(1e-9 * cell, coord_rounding_m_);
  // On the edge's line: within the still band and the sweeps' reach back
  // (a millionth of a cell each; Simulation), with room, or rounding.
  const double on_line = rounding + 4e-6 * std::min(dx_, dz_);
  if (plan_length > 1e-12) {
    nx /= plan_length;
    nz /= plan_length;
  } else {
    // An edge seen end-on: push along the motion, or along +X at rest.
    const PlanMotion step_motion = midpoint_motion(from, to);
    const PlanMotion m = std::hypot(step_motion.x, step_motion.z) > 1e-12 ? step_motion : midpoint_motion(moved_from, to);
    const double length = std::hypot(m.x, m.z);
    nx = length > 1e-12 ? m.x / length : 1.0;
    nz = length > 1e-12 ? m.z / length : 0.0;
  }
  const double line_nx = nx, line_nz = nz;  // the normal, before it is turned to a point's way
  const auto across = [&](const Vec3& was, const Vec3& is) { return line_nx * (is.x - was.x) + line_nz * (is.z - was.z); };
  const double step_a = across(from.a, to.a), step_b = across(from.b, to.b);
  const double since_a = across(moved_from.a, to.a), since_b = across(moved_from.b, to.b);
  const double edge_len2 = e.x * e.x + e.z * e.z;
  // The motion across the line (along the normal) of the edge's point
  // nearest to (x, z), 0 for none.
  // (this_step: whether it is this step's motion.)
  const auto motion_at = [&](double x, double z, bool& this_step) {
    const double t =
        edge_len2 > 0.0 ? std::clamp(((x - to.a.x) * e.x + (z - to.a.z) * e.z) / edge_len2, 0.0, 1.0) : 0.5;
    const double now = (1.0 - t) * step_a + t * step_b;
    this_step = std::abs(now) > rounding;
    if (this_step) return now;
    const double since = (1.0 - t) * since_a + t * since_b;
    return std::abs(since) > rounding ? since : 0.0;
  };
  const auto way_at = [&](double x, double z) {
    bool this_step = false;
    return motion_at(x, z, this_step);
  };
  // The step's first edge's normal, turned as the last edge's: a cut sample
  // behind that line (by more than rounding) in the way the edge went there
  // was not swept by the edge (see below).
  const double from_ex = from.b.x - from.a.x, from_ez = from.b.z - from.a.z;
  const double from_len = std::hypot(from_ex, from_ez);
  double from_nx = line_nx, from_nz = line_nz;
  if (from_len > 1e-12 && plan_length > 1e-12) {
    from_nx = -from_ez / from_len;
    from_nz = from_ex / from_len;
    if (from_nx * line_nx + from_nz * line_nz < 0.0) from_nx = -from_nx, from_nz = -from_nz;
  }
  // One cell along the push (the longer cell side across it, so the roll
  // never skips a cell).
  const double step = std::min(dx_ / std::max(std::abs(nx), 1e-9), dz_ / std::max(std::abs(nz), 1e-9));
  // The repose drop over one such cell.
  const double limit_step = std::tan(params_.material.repose_deg * std::numbers::pi / 180.0) * step *
                            std::hypot(nx, nz);

  const HeightGrid::EditLayers layers = grid.edit_layers();
  const Rect& r = before_rect_;
  // What the cut took (exact in double: a difference of two floats) and
  // what the displacement put down, measured as it writes, so that the
  // rounding of the writes is given back at the end.
  double taken = 0.0, put = 0.0;
  displace_work_ = 0;
  // The last cell written, and the last with a millimetre of room under the
  // ceiling (the rounding is given back there when the last has none).
  std::int64_t last_put = -1, last_with_room = -1;
  const auto write = [&](std::int64_t cell, float value) {
    dirty(std::uint32_t(cell));
    settle_exclude(cell);
    put += double(value) - double(layers.height_m[cell]);
    layers.height_m[cell] = value;
    last_put = cell;
    if (value <= ceiling_m_ - kGiveBackRoom_m) last_with_room = cell;
  };
  // Whether the centre of cell (c, r) lies behind the edge (on the side
  // that part of it came from, past the half cell its line passes through),
  // within its length: the cut behind the blade, where no displaced soil
  // may go.
  const auto behind_blade = [&](int c, int r) {
    if (!(edge_len2 > 0.0)) return false;
    const double x = spec.origin_m.x + (c + 0.5) * dx_ - to.a.x, z = spec.origin_m.z + (r + 0.5) * dz_ - to.a.z;
    const double t = (x * e.x + z * e.z) / edge_len2;
    if (!(t >= 0.0 && t <= 1.0)) return false;
    const double n = x * line_nx + z * line_nz;
    return (way_at(x + to.a.x, z + to.a.z) < 0.0 ? -n : n) < -0.5 * cell;
  };
  // Puts `add` metres on `cell`, never above the ceiling (a Bullet
  // heightfield's upper bound would clamp, and so delete, soil above it):
  // what would rise above it goes to the nearest cells around with room,
  // ring by ring, none under a body nor behind the blade.
  const auto put_down = [&](std::int64_t cell, float add) {
    float v = std::max(0.0f, layers.height_m[cell] + add);
    float over = v > ceiling_m_ ? v - ceiling_m_ : 0.0f;
    write(cell, v - over);
    const int c0 = col_of(std::uint32_t(cell)), r0 = row_of(std::uint32_t(cell));
    out.changed.include(c0, r0);
    candidate(std::uint32_t(cell), false);
    for (int ring = 1; ring <= kMaxPushCells && over > 0.0f; ++ring)
      for (int dr = -ring; dr <= ring && over > 0.0f; ++dr)
        for (int dc = -ring; dc <= ring && over > 0.0f; dc += (dr == -ring || dr == ring) ? 1 : 2 * ring) {
          const int c = c0 + dc, r = r0 + dr;
          if (c < 0 || r < 0 || c >= cols_ || r >= rows_) continue;
          const std::int64_t j = std::int64_t(r) * cols_ + c;
          const float room = ceiling_m_ - layers.height_m[j];
          if (obstacle_[j] != 0 || !(room > 0.0f) || behind_blade(c, r)) continue;
          const float give = std::min(over, room);
          // (h + (ceiling - h) may round an ulp above the ceiling.)
          write(j, std::min(layers.height_m[j] + give, ceiling_m_));
          over -= give;
          out.changed.include(c, r);
          candidate(std::uint32_t(j), false);
        }
  };
  // The share of each sample's cut that goes into the bucket: all of it
  // while the bucket has room for the step's cut, else what fits.
  double keep = 0.0;
  if (bucket_room_m3 > 0.0) {
    double cut = 0.0;
    std::size_t j = 0;
    for (int row = r.r0; row < r.r1; ++row)
      for (int c = r.c0; c < r.c1; ++c, ++j) {
        const float lost = before_[j] - layers.height_m[std::int64_t(row) * cols_ + c];
        if (lost > 0.0f) cut += double(lost);
      }
    cut *= spec.cell_area_m2();
    keep = cut > 0.0 ? std::min(1.0, bucket_room_m3 / cut) : 0.0;
  }
  // The heights the cut left, before any is written: soil put down on a cut
  // sample not yet handled must not shrink what that sample's cut counts
  // (else the books give back less than the cut took, and soil is lost).
  std::size_t k = 0;
  for (int row = r.r0; row < r.r1; ++row)
    for (int c = r.c0; c < r.c1; ++c, ++k) after_cut_[k] = layers.height_m[std::int64_t(row) * cols_ + c];
  // The cells a sample's push passes, one step apart from the first cell
  // ahead (the shift, the fill and the rest each walk them from there):
  // found once a sample, as far as one of them reads.
  std::int64_t walk_cell[kMaxPushCells];
  bool walk_off[kMaxPushCells];
  // The heights the push's shift gives the cells of its run, and what the
  // fill puts on each cell of the walk (negative: nothing): found first,
  // written once.
  float shifted[kMaxPushCells], add_at[kMaxPushCells];
  // The cells the fill reached: the walk's, and past a body met, the cells
  // along its face (fill_ahead).
  std::int64_t fill_cell[kMaxPushCells];
  const bool open_edge = params_.edge == SoilEdge::kOpen;
  k = 0;
  for (int row = r.r0; row < r.r1; ++row)
    for (int c = r.c0; c < r.c1; ++c, ++k) {
      const std::int64_t i = std::int64_t(row) * cols_ + c;
      const float cut = before_[k] - after_cut_[k];
      if (!(cut > 0.0f)) continue;
      // Ground: the part of the cut below the initial surface.
      out.cut_from_ground_m3 +=
          std::max(0.0, std::min(double(before_[k]), double(layers.initial_m[i])) - double(after_cut_[k])) *
          spec.cell_area_m2();
      dirty(std::uint32_t(i));
      settle_exclude(i);
      candidate(std::uint32_t(i), true);  // its walls may now be too steep
      const float kept = keep >= 1.0 ? cut : float(double(cut) * keep);
      out.bucket_in_m3 += double(kept) * spec.cell_area_m2();
      const float lost = cut - kept;  // what is displaced
      if (!(lost > 0.0f)) continue;
      taken += double(before_[k]) - double(after_cut_[k]) - double(kept);
      // Straight ahead of the edge: the cell centre's distance to the edge's
      // line along the normal, plus kDepositAheadCells. At rest, away from
      // the line on the cell's own side.
      const double x = spec.origin_m.x + (c + 0.5) * dx_;
      const double z = spec.origin_m.z + (row + 0.5) * dz_;
      // The push's direction: the normal turned to this point's way. A
      // sample behind the step's first edge in that way, by more than
      // rounding, was not swept by the edge: the cut's sweep starts a
      // millionth of a cell behind the first edge (Simulation's
      // reach_back, so that consecutive sweeps overlap and a row on the
      // line they share is not missed), and took it there. The edge went
      // away from it, so it keeps its side, as a sample at rest does.
      // (Pushed the way the edge went, the column a pile had slid onto it
      // as that part of the blade backed away went through the blade: 3.9
      // cm behind a 2 m blade on 5 mm cells, wobbling, rolled 3 degrees,
      // from a sample 6e-10 m past the first edge.)
      bool this_step = false;
      double way = motion_at(x, z, this_step);
      if (this_step && ((x - from.a.x) * from_nx + (z - from.a.z) * from_nz) * (way < 0.0 ? -1.0 : 1.0) < -rounding)
        way = 0.0;
      // A point of the edge that this step moved by no more than rounding
      // (a blade at rest, or the pivot of a turn) swept nothing there: what
      // it cut is a centre on its line (the still band, a millionth of a
      // cell either side: Simulation) or, in the columns cut, a column whose
      // square its line crosses. The way since the blade last moved is for
      // the centre on the line; a column whose centre lies off it keeps its
      // own side, as at rest. (Pushed the way since, a column 0.53 cells
      // ahead of a turning, wobbling 0.87 m blade's pivot, which had backed
      // 1e-5 m since, went 1.5 cells back through it: 1.3 cm behind it on
      // 2 cm cells 1e7 m out, where the rounding is 1.4e-7 m; and 1.9 cm
      // behind a 2 m blade whose pivot had backed 1.5 cm.)
      if (!this_step && way != 0.0 && std::abs((x - to.a.x) * line_nx + (z - to.a.z) * line_nz) > on_line)
        way = 0.0;
      const bool moving = way != 0.0;
      nx = way < 0.0 ? -line_nx : line_nx;
      nz = way < 0.0 ? -line_nz : line_nz;
      const double s = (x - to.a.x) * nx + (z - to.a.z) * nz;
      // At rest, its own side; on the line within rounding, the normal's.
      const double side = moving || s >= -rounding ? 1.0 : -1.0;
      const double go = side * (kDepositAheadCells * cell) - s;
      // A walk's target beyond a wall stops against it, on the cell nearest
      // to it, (cu, cv); where that cell is not ahead of the edge's line
      // by more than half a cell's width across it (outside the blade: the
      // walk's cells near a corner the line runs into lie on the wall
      // beside the blade, and some behind it), the soil is pushed along the
      // wall the way that leads ahead of the line, to the first cell there
      // (the wall along z when the walk left over a column's end, along x
      // over a row's; at a corner, the one leading ahead faster first).
      // With no such cell within kMaxPushCells, the nearest cell. (Clamped
      // alone, a 2 m blade pushing into the terrain's corner at 2 m/s put
      // its cut on a cell just behind its line, and the relaxation spread it
      // over the trench: 1.25 cm behind the blade.)
      // A cell whose centre lies ahead of the edge's line by more than half
      // its width across it: outside the blade, a cell the relaxation may
      // move soil from (blade_blocks).
      const double ahead_by = 0.5 * (std::abs(nx) * dx_ + std::abs(nz) * dz_);
      // How far ahead of the edge's line a line round a body runs, so that
      // every cell it crosses lies outside the blade: twice ahead_by, plus a
      // hundredth of a cell (round_body's callers).
      const double clear_by = 2.0 * ahead_by + 0.01 * std::min(dx_, dz_);
      const auto ahead = [&](int c, int r) {
        const double px = spec.origin_m.x + (c + 0.5) * dx_ - to.a.x, pz = spec.origin_m.z + (r + 0.5) * dz_ - to.a.z;
        return side * (px * nx + pz * nz) > ahead_by;
      };
      const auto against_wall = [&](int& cu, int& cv, bool past_column_end, bool past_row_end) {
        if (ahead(cu, cv)) return;
        // Along z (past a column's end), the rows go the way of side * nz;
        // along x (past a row's end), the columns the way of side * nx.
        const int dr = side * nz > 0.0 ? 1 : -1, dc = side * nx > 0.0 ? 1 : -1;
        const bool z_first = past_column_end && (!past_row_end || std::abs(nz) >= std::abs(nx));
        for (int pass = 0; pass < 2; ++pass) {
          const bool along_z = (pass == 0) == z_first;
          if (along_z ? !past_column_end : !past_row_end) continue;
          for (int k = 1; k < kMaxPushCells; ++k) {
            const int c = along_z ? cu : cu + k * dc, r = along_z ? cv + k * dr : cv;
            if (c < 0 || r < 0 || c >= cols_ || r >= rows_) break;
            if (ahead(c, r)) {
              cu = c, cv = r;
              return;
            }
          }
        }
      };
      // Step m (< kMaxPushCells) of the walk from `go`: its cell and whether
      // it lies beyond an open edge. Beyond a wall, a target is the cell on
      // the grid nearest to it (the cell repeats as the walk goes on out),
      // moved along the wall where it has to be to the first cell ahead of
      // the edge's line, outside the blade (against_wall); beyond an open
      // edge, the soil leaves the terrain.
      int walked = 0;
      // (A walk along a grid axis keeps the other coordinate: x + 0 * along
      // is x, divided once, not at every step.)
      const double u_fixed = to_cells(x, spec.origin_m.x, dx_), v_fixed = to_cells(z, spec.origin_m.z, dz_);
      const auto walk_to = [&](int m) {
        for (; walked <= m; ++walked) {
          const double along = go + side * walked * step;
          const double u = nx == 0.0 ? u_fixed : to_cells(x + nx * along, spec.origin_m.x, dx_);
          const double v = nz == 0.0 ? v_fixed : to_cells(z + nz * along, spec.origin_m.z, dz_);
          const bool outside = u < 0.0 || v < 0.0 || u >= cols_ || v >= rows_;
          walk_off[walked] = open_edge && outside;
          // (On the grid floor is the truncation; a NaN goes to floor_within.)
          int cu = u >= 0.0 && u < cols_ ? int(u) : floor_within(u, 0, cols_ - 1);
          int cv = v >= 0.0 && v < rows_ ? int(v) : floor_within(v, 0, rows_ - 1);
          if (outside && !open_edge) against_wall(cu, cv, u < 0.0 || u >= cols_, v < 0.0 || v >= rows_);
          walk_cell[walked] = std::int64_t(cv) * cols_ + cu;
        }
      };
      const auto walk = [&](int m) {
        if (m >= walked) walk_to(m);
        return walk_cell[m];
      };
      const auto walk_beyond = [&](int m) {
        if (m >= walked) walk_to(m);
        return walk_off[m];
      };
      // A run of cells filled to one line falling at the repose slope, the
      // line as high as `volume` (metres of height on one cell) needs:
      // next(m, u, b) gives the run's m-th cell u and the height b the line
      // must pass to reach it (its surface plus the repose rise from the
      // run's first cell), or false where the run ends. Cells are taken
      // while they lie below the line; what each takes goes in add[j]
      // (negative: nothing), cells[j] the cell (-1: beyond an open edge).
      // Returns how many cells it examined; reach[j] is the height the line
      // must pass to reach cell j.
      const auto fill_line = [&](double volume, const auto& next, std::int64_t* cells, double* add,
                                 double* reach) -> int {
        int count = 0;
        double sum = 0.0, line = 0.0;
        for (int m = 0; m < kMaxPushCells; ++m) {
          std::int64_t u = -1;
          double b = 0.0;
          if (!next(m, u, b)) break;
          if (count > 0 && !(b < line)) break;  // at or above the line: nothing reaches it
          cells[count] = u;
          reach[count] = b;
          sum += b;
          ++count;
          line = (volume + sum) / count;
        }
        if (count == 0) return 0;
        // A cell of the run above the final line (a hump) takes nothing:
        // without it the line comes lower, until no more drop out. A cell
        // that dropped out stays out, so the rounds end: the line only comes
        // down in exact arithmetic, but the rounding of the next mean could
        // let a cell at the line back in and the line go up and down
        // between two values for ever (a bucket digging while it turned, on
        // a terrain 1e7 m out: the step never ended).
        bool in_run[kMaxPushCells];
        std::fill_n(in_run, count, true);
        for (int in = count;;) {
          double s_in = 0.0;
          int n_in = 0;
          for (int j = 0; j < count; ++j)
            if (in_run[j] && reach[j] < line) s_in += reach[j], ++n_in;
          if (n_in == in || n_in == 0) break;
          for (int j = 0; j < count; ++j) in_run[j] = in_run[j] && reach[j] < line;
          in = n_in;
          line = (volume + s_in) / n_in;
        }
        for (int j = 0; j < count; ++j) {
          const double give = line - reach[j];
          add[j] = in_run[j] && give > 0.0 ? give : -1.0;
        }
        return count;
      };
      // The rest of the cut lands where an avalanche down the face ahead
      // would leave it: the cells of the walk from the first cell ahead,
      // up to the first one above it, filled to one line (fill_line).
      // Cells beyond an open edge stand for the bare ground there (height
      // 0): what fills them leaves the terrain. A wall ends the run. Where
      // the walk meets a body, the run goes on along the body's face, a
      // cell a step on the axis the push leads along it (a rectangle's
      // face: the axis the step into the body did not cross), while the
      // cells there are free and outside the blade. (Ended at the body, a
      // blade sweeping along a body at a slant filled each crossing's cut
      // onto the one or two cells between its edge and the body, whose
      // whole column the next crossing cut and pushed on: 9.1 m high
      // beside a 4-cell body at the default cap, a 1.25 m blade at 27
      // degrees on 5 mm cells, where the cap-free run has 0.33 m;
      // docs/soil.md, "Soil slides along a body's face".) A run that is
      // still the one cell beside the body rises no higher than `top`, the
      // cut column's height before the cut: what would stand higher goes
      // round the body from that cell (round_from, below), left in `over`
      // (metres of height on one cell), the cell in `beside`. It reads the
      // run's `length` cells at their shifted heights (the last of them
      // also where the walk, having left the grid over an open edge, comes
      // back on it: the same clamped cell) and writes nothing: what each
      // cell of the run takes goes in add_at, the cell in fill_cell.
      // Returns how many cells it reached (0: none, all of it is the
      // caller's to put down, when the first cell is a body's or the
      // grid's end, or when none of it fits under `top`).
      const auto fill_ahead = [&](float volume, int length, float top, float& over, std::int64_t& beside) -> int {
        std::int64_t cells[kMaxPushCells];
        std::int64_t last = -1;
        bool at_body = false;
        // Along a body's face: the cell reached and the step (dc, dr).
        int slide_c = 0, slide_r = 0, slide_dc = 0, slide_dr = 0;
        bool sliding = false;
        const auto free_at = [&](int c, int r) {
          return c >= 0 && r >= 0 && c < cols_ && r < rows_ && obstacle_[std::int64_t(r) * cols_ + c] == 0 && ahead(c, r);
        };
        const auto next = [&](int m, std::int64_t& u, double& b) {
          if (!sliding && m > 0 && last >= 0 && !walk_beyond(m) && obstacle_[walk(m)] != 0) {
            // The walk meets a body: the fill goes on along its face, the
            // way the push leads along it (on an axis the body's rectangle
            // does not block), one cell a step.
            const std::uint32_t into = std::uint32_t(walk(m));
            const int c0 = col_of(std::uint32_t(last)), r0 = row_of(std::uint32_t(last));
            const int dc = col_of(into) - c0, dr = row_of(into) - r0;
            const int wc = side * nx > 0.0 ? 1 : side * nx < 0.0 ? -1 : 0;
            const int wr = side * nz > 0.0 ? 1 : side * nz < 0.0 ? -1 : 0;
            if (dc != 0 && (dr == 0 || !free_at(c0, r0 + dr)) && free_at(c0 + (dr != 0 ? dc : 0), r0 + (dr != 0 ? 0 : wr)))
              slide_dc = dr != 0 ? dc : 0, slide_dr = dr != 0 ? 0 : wr;
            else if (dr != 0 && free_at(c0 + (dc != 0 ? 0 : wc), r0 + (dc != 0 ? dr : 0)))
              slide_dc = dc != 0 ? 0 : wc, slide_dr = dc != 0 ? dr : 0;
            sliding = slide_dc != 0 || slide_dr != 0;
            slide_c = c0, slide_r = r0;
          }
          if (sliding) {
            slide_c += slide_dc, slide_r += slide_dr;
            if (!free_at(slide_c, slide_r)) {
              at_body = true;
              return false;
            }
            u = std::int64_t(slide_r) * cols_ + slide_c;
            if (u == last) return false;
            b = double(layers.height_m[u]) + limit_step * m;
            last = u;
            return true;
          }
          const bool off = walk_beyond(m);
          u = off ? -1 : walk(m);
          if (!off && obstacle_[u] != 0) at_body = true;
          if (!off && (u == last || obstacle_[u] != 0)) return false;  // against the grid's edge, or a body
          const float now = off                                        ? 0.0f
                            : m < length                                 ? shifted[m]
                            : length > 0 && u == walk_cell[length - 1] ? shifted[length - 1]
                                                                         : layers.height_m[u];
          b = double(now) + limit_step * m;
          if (!off) last = u;
          return true;
        };
        double add[kMaxPushCells], reach[kMaxPushCells];
        int count = fill_line(double(volume), next, cells, add, reach);
        over = 0.0f;
        if (at_body && count == 1 && cells[0] >= 0 && reach[0] + add[0] > double(top)) {
          const float part = float(std::clamp(double(top) - reach[0], 0.0, double(volume)));
          if (part > 0.0f) {
            beside = cells[0];
            over = volume - part;
            add[0] = double(part);
          } else {
            count = 0;  // none fits: the caller's walk takes it all round the body
          }
        }
        for (int j = 0; j < count; ++j) {
          fill_cell[j] = cells[j];
          add_at[j] = -1.0f;
          if (!(add[j] > 0.0)) continue;
          if (cells[j] < 0) {
            out.left_over_edge_m3 += add[j] * spec.cell_area_m2();
            taken -= add[j];
          } else {
            add_at[j] = float(add[j]);
          }
        }
        return count;
      };
      // Soil that goes round a body (`volume`, metres of height on one
      // cell): from the point (px, pz), both ways along the unit (tx, tz),
      // a cell at a time from the j0-th, to the first cell on each side that no body
      // stands over and that lies outside the blade; from there on outward
      // the cells are filled to one line falling at the repose slope
      // (fill_line), half the soil to each side when both are as near (so
      // a mirrored scene gives the mirrored result), all of it to the one
      // along (tx, tz) or the one found. Returns false (nothing put down)
      // where there is none within kMaxPushCells.
      const auto round_body = [&](double px, double pz, double tx, double tz, int j0, float volume) {
        const double along_step =
            std::min(dx_ / std::max(std::abs(tx), 1e-9), dz_ / std::max(std::abs(tz), 1e-9));
        const double rise = std::tan(params_.material.repose_deg * std::numbers::pi / 180.0) * along_step;
        const auto at = [&](double along) -> std::int64_t {
          const double u = to_cells(px + tx * along, spec.origin_m.x, dx_);
          const double v = to_cells(pz + tz * along, spec.origin_m.z, dz_);
          if (u < 0.0 || v < 0.0 || u >= cols_ || v >= rows_) return -1;
          return std::int64_t(std::floor(v)) * cols_ + std::int64_t(std::floor(u));
        };
        const auto open = [&](std::int64_t u) {
          return u >= 0 && obstacle_[u] == 0 && ahead(int(u % cols_), int(u / cols_));
        };
        for (int j = j0; j <= kMaxPushCells; ++j) {
          const std::int64_t a = at(j * along_step), b = at(-j * along_step);
          if (a < 0 && b < 0) return false;  // off the grid both ways
          bool fa = open(a), fb = open(b);
          if (!fa && !fb) continue;
          // From a free start (j0 = 0, both ways' first cell), the ways that
          // go on past it: against a body one way, the line that way is the
          // start alone, and half the soil stood on it, a column the next
          // crossing's cut took and pushed on (docs/soil.md, "Soil slides
          // along a body's face").
          if (a == b) {
            fa = open(at((j + 1) * along_step));
            fb = open(at(-(j + 1) * along_step));
            if (!fa && !fb) fa = fb = true;
          }
          const float half = fa && fb ? 0.5f * volume : 0.0f;
          for (const auto& [way_of, share] : {std::pair{fa ? 1.0 : -1.0, volume - half}, std::pair{-1.0, half}}) {
            if (!(share > 0.0f)) continue;
            const double way = way_of;  // (a lambda may not capture a structured binding: clang)
            std::int64_t last = -1;
            const auto next = [&](int m, std::int64_t& u, double& level) {
              u = at(way * (j + m) * along_step);
              if (u == last || !open(u)) return false;  // the grid's end, a body, or the blade
              level = double(layers.height_m[u]) + rise * m;
              last = u;
              return true;
            };
            std::int64_t cells[kMaxPushCells];
            double add[kMaxPushCells], reach[kMaxPushCells];
            const int count = fill_line(double(share), next, cells, add, reach);
            for (int k = 0; k < count; ++k)
              if (add[k] > 0.0) put_down(cells[k], float(add[k]));
          }
          return true;
        }
        return false;
      };
      // round_body from a free cell ahead of the blade, along the edge: on
      // the line through its centre, or, where that lies nearer the edge's
      // line than the line of the branch above (clear_by), on that one.
      // (Through the centre of a cell just ahead of the edge at a slant, the
      // line's next cells lay inside the blade and the fill stopped at the
      // first, which took it all.)
      const auto round_from = [&](std::int64_t cell, float volume) {
        const double fx = spec.origin_m.x + (double(cell % cols_) + 0.5) * dx_;
        const double fz = spec.origin_m.z + (double(cell / cols_) + 0.5) * dz_;
        const double d = side * ((fx - to.a.x) * nx + (fz - to.a.z) * nz);
        const double lift = d < clear_by ? side * (clear_by - d) : 0.0;
        return round_body(fx + nx * lift, fz + nz * lift, -nz, nx, 0, volume);
      };
      // The blade pushes what stands in front of it: along the push, the
      // descending profile ahead (cells above the edge's height) moves on by
      // one cell, the cut column's height taking the first cell's place, as
      // a pile pushed by a blade does; what the shift does not account for
      // (the cut layer itself) is put down just beyond the pile's toe. On
      // flat ground nothing shifts and the cut soil is put down ahead. The
      // run is the walk's first `length` cells.
      const float edge_top = after_cut_[k];  // the cut column's new height
      const std::int64_t first = walk(0);
      int length = 1;
      float previous = before_[k];
      // A bucket taking soil in does not push a pile.
      if (kept == 0.0f && layers.height_m[first] < previous && !(layers.height_m[first] < edge_top) &&
          !obstructed(std::uint32_t(first))) {
        while (length < kMaxPushCells) {
          const std::int64_t next = walk(length);
          if (next == walk_cell[length - 1]) break;  // against the grid's edge
          const float here = layers.height_m[walk_cell[length - 1]], ahead = layers.height_m[next];
          if (!(ahead < here) || ahead < edge_top || obstructed(std::uint32_t(next))) break;
          ++length;
        }
        for (int j = 0; j < length; ++j) {
          shifted[j] = previous;
          previous = layers.height_m[walk_cell[j]];
        }
      } else {
        length = 0;  // nothing to push: the cut soil goes to the first cell ahead
        previous = layers.height_m[first];
      }
      // What is left: the lost height less what the shift raised (which
      // telescopes to the cut column's old height less the toe's old
      // height). It extends the pile beyond its toe at the repose slope,
      // cell by cell along the push; the rest of it stays on the last cell.
      const float raised = length > 0 ? before_[k] - previous : 0.0f;
      float rest = lost - raised;
      out.displaced_volume_m3 += double(lost) * spec.cell_area_m2();
      float over = 0.0f;
      std::int64_t beside = -1;
      const int filled = rest > 0.0f ? fill_ahead(rest, length, before_[k], over, beside) : 0;
      if (filled > 0) rest = 0.0f;
      // The run's cells take their shifted heights and what the fill put on
      // them in one write (as put_down would, in the same float steps);
      // should one rise above the ceiling, the shift is written first and
      // the fill put down after, so that put_down spreads the overflow.
      // (The last cell written is the one that takes the writes' rounding
      // at the end: the last the fill put soil on, as when the fill wrote
      // after the shift.)
      const int in_run = std::min(length, filled);
      bool over_ceiling = false;
      for (int j = 0; j < in_run; ++j)
        if (add_at[j] >= 0.0f && std::max(0.0f, shifted[j] + add_at[j]) > ceiling_m_) over_ceiling = true;
      int last_add = -1;
      for (int j = 0; j < length; ++j) {
        const std::int64_t cell_j = walk_cell[j];
        const float old = layers.height_m[cell_j];
        const bool add = !over_ceiling && j < filled && add_at[j] >= 0.0f;
        write(cell_j, add ? std::max(0.0f, shifted[j] + add_at[j]) : shifted[j]);
        out.changed.include(col_of(std::uint32_t(cell_j)), row_of(std::uint32_t(cell_j)));
        candidate(std::uint32_t(cell_j), shifted[j] < old);
        if (add) last_add = j;
      }
      if (last_add >= 0) last_put = walk_cell[last_add];
      for (int j = over_ceiling ? 0 : in_run; j < filled; ++j)
        if (add_at[j] >= 0.0f) put_down(fill_cell[j], add_at[j]);
      if (over > 0.0f && beside >= 0 && !round_from(beside, over)) put_down(beside, over);
      std::int64_t t = length > 0 ? walk_cell[length - 1] : first;
      float level = length > 0 ? layers.height_m[t] : before_[k];
      // The last cell reached that is not under a rigid body (the cut
      // column itself when the body stands right ahead).
      std::int64_t free = length > 0 ? t : i;
      for (int m = length > 0 ? length : 0; m < kMaxPushCells && rest > 0.0f; ++m) {
        if (walk_beyond(m)) {
          // Pushed off the terrain: it is gone, and counted.
          out.left_over_edge_m3 += double(rest) * spec.cell_area_m2();
          taken -= double(rest);
          rest = 0.0f;
          break;
        }
        const std::int64_t u = walk(m);
        if (u == t && m > 0) break;  // against the grid's edge
        t = u;
        if (obstacle_[u] != 0) break;  // never into, under or through a body
        const float room = level - float(limit_step) - layers.height_m[u];
        if (!(room > 0.0f)) {
          if (m > 0 || length > 0) break;
          continue;
        }
        free = u;
        const float add = std::min(rest, room);
        write(u, layers.height_m[u] + add);
        rest -= add;
        level = layers.height_m[u];
        out.changed.include(col_of(std::uint32_t(u)), row_of(std::uint32_t(u)));
        candidate(std::uint32_t(u), false);
      }
      // What did not fit (or, by rounding, came out negative) is settled on
      // the last cell reached, keeping the volume.
      // Against a body with no free cell outside the blade between it and
      // the blade (the blade at, under or within a cell of it), it goes
      // round the body (round_body): beside it along the edge, on a line
      // far enough ahead of the edge's that every cell it crosses lies
      // outside the blade (twice ahead_by, plus a hundredth of a cell),
      // filled outward at the repose slope. (Put on the last free cell,
      // inside the blade, or on the one cell beside the body a cell ahead,
      // inside the blade at a slant, the soil could not slide off it, and
      // the next step's cut took it again with its own: a 1 m blade driven
      // through a static body 20 cells wide on 1 cm cells stacked 23 m of
      // soil on one cell at 30 degrees; at yaw 0, where that cell lay
      // outside the blade, a row's cut from in front of the body stood
      // there 4 m high until the relaxation spread it.)
      if (obstacle_[t] != 0 && rest > 0.0f) {
        t = free;
        if (free == i || !ahead(int(free % cols_), int(free / cols_))) {
          const double clear = side * clear_by - s;
          if (round_body(x + nx * clear, z + nz * clear, -nz, nx, 1, rest)) rest = 0.0f;
        } else if (round_from(free, rest)) {
          rest = 0.0f;
        }
      }
      if (rest != 0.0f) put_down(t, rest);
      displace_work_ += kDisplaceCellVisits * walked;
    }
  // Give back the rounding of the writes on the last cell written; on one
  // with room where that would rise past the ceiling, whose clamp would
  // delete it (up to 8e-9 m^3 over a push into a pocket under a ceiling).
  if (last_put >= 0 && put != taken)
    give_back(layers.height_m[give_back_cell(layers.height_m, last_put, last_with_room, taken - put, ceiling_m_)],
              taken - put);
  // Only the changed cells that now stand too steep (or lowered under a
  // neighbour too steep above them) are examined: a pushed pile moves as
  // a whole, and most of its cells keep their slopes.
  settle_candidates(layers.height_m);
}

}  // namespace terracut
