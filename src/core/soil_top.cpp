// Soil that flows, the blade's top (soil.hpp, docs/soil.md "Soil over the
// blade's top"): a blade of finite height (BladeSpec::height_m) holds soil
// up to its top; what stands higher against it falls over to the other
// side, as the soil a dozer pushes rolls over a blade too short for its
// pile.
#include "terracut/core/soil.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "soil_internal.hpp"

namespace terracut {

using namespace soil_internal;

void SoilFlow::spill_over_top(HeightGrid& grid, const Segment& edge, const Quat& orientation,
                              SoilStepResult& out) {
  const double height = blade_spec_.height_m;
  if (!std::isfinite(height) || blade_spec_.bucket.enabled()) return;
  const GridSpec& spec = grid.spec();
  const double ex = edge.b.x - edge.a.x, ez = edge.b.z - edge.a.z;
  const double len2 = ex * ex + ez * ez;
  if (!(len2 > 0.0)) return;
  const double len = std::sqrt(len2);
  // The top's height above the edge: the face's local height turned with
  // the blade (rolled or pitched, the top stands lower; a face turned
  // level or below the edge holds nothing above the edge).
  const double rise = height * std::max(0.0, rotate(orientation, {0.0, 1.0, 0.0}).y);
  const double ay = edge.a.y - spec.origin_m.y, dy = edge.b.y - edge.a.y;
  // Half a cell's width across the edge's line (as blade_blocks has it): a
  // centre closer than that is inside the blade. The cells against it are
  // those whose centres lie within three halves of it (the displacement
  // puts its soil on the first line twice half a cell ahead of the edge:
  // that line's cells have their centres within three halves). What falls
  // over lands on the cell across the line at twice half a cell and a
  // hundredth of a cell, the first whose centre is clear of the blade.
  const double cell = std::min(dx_, dz_);
  const double slope = std::tan(params_.material.repose_deg * std::numbers::pi / 180.0);
  const double half = 0.5 * (std::abs(ez) * dx_ + std::abs(ex) * dz_) / len;
  const double reach = 3.0 * half + 0.02 * cell;
  const double land = 2.0 * half + 0.01 * cell;
  // The unit normal in plan (n grows along it) and the edge's direction.
  const double nx = -ez / len, nz = ex / len;
  // The rows whose centres can lie within `reach` of the edge.
  const int r0 = ceil_within(to_cells(std::min(edge.a.z, edge.b.z) - reach, spec.origin_m.z, dz_) - 0.5, 0, rows_);
  const int r1 = floor_within(to_cells(std::max(edge.a.z, edge.b.z) + reach, spec.origin_m.z, dz_) - 0.5, -1, rows_ - 1);
  float* h = grid.edit_layers().height_m;
  double moved_sum = 0.0, gained = 0.0, lost = 0.0;  // (lost: over an open edge)
  // The walks down the other side are counted (over_top_visits) and stop
  // after a cap's worth of cells of their own (what stays above the top
  // goes over in the next step): a tall blade buried deep could otherwise
  // walk far for every cell against it. (Held to what the settle and the
  // passes left of the cap, the spill would move nothing in the steps at
  // the cap, nearly every step of a slant push on 5 mm cells.)
  std::int64_t walked = 0;
  const std::int64_t budget = params_.max_pair_checks_per_step;
  std::int64_t last = -1, last_room = -1;
  const auto write = [&](std::int64_t i, float now) {
    const float old = h[i];
    gained += double(now) - double(old);
    dirty(std::uint32_t(i));
    settle_exclude(i);
    h[i] = now;
    last = i;
    if (now <= ceiling_m_ - kGiveBackRoom_m) last_room = i;
    candidate(std::uint32_t(i), now < old);
    out.changed.include(int(i % cols_), int(i / cols_));
  };
  for (int r = r0; r <= r1 && walked <= budget; ++r) {
    const double z = spec.origin_m.z + (r + 0.5) * dz_ - edge.a.z;
    // The columns whose centres meet both |n| <= reach and 0 <= t <= 1 on
    // this row: each is linear in x, so each holds on an interval of x.
    double x_lo = -std::numeric_limits<double>::infinity(), x_hi = -x_lo;
    const auto within = [&](double p, double q, double lo, double hi) {
      // p + q x in [lo, hi]
      if (std::abs(q) < 1e-300) {
        if (p < lo || p > hi) x_lo = 1.0, x_hi = 0.0;
        return;
      }
      const double u = (lo - p) / q, v = (hi - p) / q;
      x_lo = std::max(x_lo, std::min(u, v));
      x_hi = std::min(x_hi, std::max(u, v));
    };
    within(nz * z, nx, -reach, reach);
    within(z * ez / len2, ex / len2, 0.0, 1.0);
    if (!(x_lo <= x_hi)) continue;
    const int c0 = ceil_within(to_cells(edge.a.x + x_lo, spec.origin_m.x, dx_) - 0.5, 0, cols_);
    const int c1 = floor_within(to_cells(edge.a.x + x_hi, spec.origin_m.x, dx_) - 0.5, -1, cols_ - 1);
    // Along the row the top is linear in x: a cell is looked at further
    // only where it stands above the top there, with a margin for the
    // rounding of that line (most steps, no cell does).
    const double top_z = ay + rise + (z * ez / len2) * dy, top_x = ex / len2 * dy;
    const double margin = 1e-9 * (std::abs(top_z) + std::abs(top_x) * (std::abs(x_lo) + std::abs(x_hi)) + 1.0);
    for (int c = c0; c <= c1 && walked <= budget; ++c) {
      const std::int64_t i = std::int64_t(r) * cols_ + c;
      const double x = spec.origin_m.x + (c + 0.5) * dx_ - edge.a.x;
      if (!(double(h[i]) > top_z + x * top_x - margin)) continue;
      if (obstacle_[std::size_t(i)] != 0) continue;
      const double n = x * nx + z * nz;
      const double t = (x * ex + z * ez) / len2;
      if (!(std::abs(n) <= reach) || t < 0.0 || t > 1.0 || n == 0.0) continue;
      // (a top below the ground, a blade sunk past it, holds nothing: the
      // soil over it goes down to the ground, never below)
      const double top = std::max(ay + t * dy + rise, 0.0);
      const double hs = h[i];
      if (!(hs - top > quantum_m_)) continue;
      // (walked counts cells looked at down the other side: the walks have
      // an allowance of their own, a cap's worth a step, beside the settle's
      // and the passes')
      // Across the line: the cells from the point of the same t `land`
      // behind the line on the other side, on along the normal (-1: off
      // the grid; -2: under a body; -3: not clear of the blade, to
      // rounding).
      const double side = n > 0.0 ? -1.0 : 1.0;
      const auto across = [&](int k) -> std::int64_t {
        const double d = land + k * cell;
        const double px = edge.a.x + t * ex + side * d * nx, pz = edge.a.z + t * ez + side * d * nz;
        const int rc = floor_within(to_cells(px, spec.origin_m.x, dx_), -1, cols_);
        const int rr = floor_within(to_cells(pz, spec.origin_m.z, dz_), -1, rows_);
        if (rc < 0 || rr < 0 || rc >= cols_ || rr >= rows_) return -1;
        const std::int64_t j = std::int64_t(rr) * cols_ + rc;
        if (obstacle_[std::size_t(j)] != 0) return -2;
        const double xr = spec.origin_m.x + (rc + 0.5) * dx_ - edge.a.x;
        const double zr = spec.origin_m.z + (rr + 0.5) * dz_ - edge.a.z;
        return (xr * nx + zr * nz) * side > half ? j : -3;
      };
      // Past the grid's edge with `edge: open`, what falls over leaves the
      // terrain (counted in left_over_edge_m3); with a wall it stays.
      const bool open = params_.edge == SoilEdge::kOpen;
      const std::int64_t first = across(0);
      if (first < 0 && !(first == -1 && open)) continue;
      double moved = 0.0;
      if (first >= 0 && double(h[first]) > top + tolerance_m_) {
        // A buried blade (the soil across stands at its top too): the two
        // sides level over it, never below the top.
        const double hr = h[first];
        const double give = std::min({hs - top, 0.5 * (hs - hr), double(ceiling_m_) - hr});
        if (!(give > 0.0)) continue;
        const float now = std::min(quantized(hr + give), ceiling_m_);
        if (!(double(now) > hr)) continue;
        moved = double(now) - hr;
        write(first, now);
      } else {
        // What stands above the top falls over it and comes to rest down
        // the other side at the repose slope from the top: each cell along
        // the normal is filled up to the line falling from the top, from
        // the first on (those already on it, within the relaxation's
        // tolerance, passed over), until the excess is placed or a cell
        // stands above the line (what lies beyond it is out of the falling
        // soil's reach) or the walk meets a body or leaves the grid (with
        // `edge: open`, what is left leaves the terrain there). What finds
        // no room stays.
        double left = hs - top;
        std::int64_t prev = -1;
        for (int k = 0; k < kMaxPushCells && left > 0.0 && walked <= budget; ++k) {
          ++walked;
          const std::int64_t j = across(k);
          if (j == -1 && open) {
            lost += left;
            moved += left;
            left = 0.0;
          }
          if (j < 0) break;
          if (j == prev) continue;
          prev = j;
          const double xr = spec.origin_m.x + double(j % cols_ + 0.5) * dx_ - edge.a.x;
          const double zr = spec.origin_m.z + double(j / cols_ + 0.5) * dz_ - edge.a.z;
          const double d = std::abs(xr * nx + zr * nz);
          // (the top at the receiver's own point of the edge: a rolled
          // blade's top slopes along it)
          const double tr = std::clamp((xr * ex + zr * ez) / len2, 0.0, 1.0);
          const double top_r = std::max(ay + tr * dy + rise, 0.0);
          const double line = std::min(top_r - slope * std::max(0.0, d - land), double(ceiling_m_));
          const double hr = h[j];
          if (!(line > hr)) {
            if (hr > line + tolerance_m_) break;
            continue;
          }
          const float now = std::min(quantized(hr + std::min(left, line - hr)), ceiling_m_);
          // (room under half a quantum: on the line, to rounding)
          if (!(double(now) > hr)) continue;
          moved += double(now) - hr;
          left -= double(now) - hr;
          write(j, now);
        }
      }
      if (!(moved > 0.0)) continue;
      write(i, float(hs - moved));
      moved_sum += moved;
    }
  }
  out.over_top_visits += walked;
  if (walked > budget) out.reached_cap = true;
  if (last < 0) return;
  // The writes' rounding given back, on the last cell written with a
  // millimetre of room under the ceiling (at the ceiling, its clamp would
  // delete it).
  const std::int64_t back = last_room >= 0 ? last_room : last;
  if (gained + lost != 0.0) give_back(h[back], -(gained + lost));
  out.over_top_m3 += moved_sum * dx_ * dz_;
  out.left_over_edge_m3 += lost * dx_ * dz_;
  settle_candidates(h);
}

}  // namespace terracut
