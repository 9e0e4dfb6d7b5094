// Soil that flows, the bucket (soil.hpp): what it holds, its hull marked
// for the relaxation, what it pours over its lip and shoulders out.
#include "terracut/core/soil.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "soil_internal.hpp"

namespace terracut {

using namespace soil_internal;

double bucket_retained_m3(const BladeSpec& blade, const Quat& orientation, double repose_deg) {
  const BucketSpec& bucket = blade.bucket;
  if (!bucket.enabled()) return 0.0;
  // The blade frame's Y and Z in the world, and the horizontal direction
  // into the bucket (the floor's, from the lip to the back).
  const Vec3 fy = rotate(orientation, {0.0, 1.0, 0.0}), fz = rotate(orientation, {0.0, 0.0, 1.0});
  // Something must carry the soil: the floor (inner normal +Y) or the back
  // wall (inner normal -Z) facing up; upside down it all falls out.
  if (!(std::max(fy.y, -fz.y) > 1e-9)) return 0.0;
  const double slope = std::tan(repose_deg * std::numbers::pi / 180.0);
  const double inward = std::hypot(fz.x, fz.z);
  // A section point (z, y) stands h = z fz.y + y fy.y above the lip and
  // s = (z fz + y fy) . u inward of it (u the unit inward direction); it is
  // held while h <= tan(repose) s: a z + b y <= 0.
  double a = fz.y, b = fy.y;
  if (inward > 1e-12) {
    const double ux = fz.x / inward, uz = fz.z / inward;
    a -= slope * (fz.x * ux + fz.z * uz);
    b -= slope * (fy.x * ux + fy.z * uz);
  }
  // The section's triangle clipped by that half-plane (Sutherland-Hodgman),
  // its area by the shoelace formula.
  const double tri[3][2] = {{0.0, 0.0}, {bucket.depth_m, 0.0}, {bucket.depth_m, bucket.height_m}};
  double poly[4][2];
  int n = 0;
  for (int k = 0; k < 3; ++k) {
    const double* p = tri[k];
    const double* q = tri[(k + 1) % 3];
    const double fp = a * p[0] + b * p[1], fq = a * q[0] + b * q[1];
    if (fp <= 0.0) poly[n][0] = p[0], poly[n++][1] = p[1];
    if ((fp < 0.0 && fq > 0.0) || (fp > 0.0 && fq < 0.0)) {
      const double t = fp / (fp - fq);
      poly[n][0] = p[0] + t * (q[0] - p[0]);
      poly[n++][1] = p[1] + t * (q[1] - p[1]);
    }
  }
  double twice_area = 0.0;
  for (int k = 0; k < n; ++k) {
    const double* p = poly[k];
    const double* q = poly[(k + 1) % n];
    twice_area += p[0] * q[1] - q[0] * p[1];
  }
  return 0.5 * std::abs(twice_area) * blade.length_m;
}

void SoilFlow::pour(HeightGrid& grid, const Segment& lip, double volume_m3, SoilStepResult& out) {
  // Spread along the lip's plan, a point per half cell, each point's share
  // put on the cell under it (or, beyond an open edge, counted as gone).
  const GridSpec& spec = grid.spec();
  const double span = std::hypot(lip.b.x - lip.a.x, lip.b.z - lip.a.z);
  // (At most 4 (cols + rows) points: a lip longer than the grid's diagonal,
  // valid input, is spread more coarsely rather than overflowing the count.)
  const int points = 1 + ceil_within(span / (0.5 * std::min(dx_, dz_)), 0, 4 * (cols_ + rows_));
  const double share_m = volume_m3 / points / spec.cell_area_m2();
  const HeightGrid::EditLayers layers = grid.edit_layers();
  double put = 0.0, wanted = 0.0;
  std::int64_t last = -1;
  for (int p = 0; p < points; ++p) {
    const double t = points > 1 ? double(p) / (points - 1) : 0.5;
    const double u = to_cells(lip.a.x + t * (lip.b.x - lip.a.x), spec.origin_m.x, dx_);
    const double v = to_cells(lip.a.z + t * (lip.b.z - lip.a.z), spec.origin_m.z, dz_);
    if (params_.edge == SoilEdge::kOpen && (u < 0.0 || v < 0.0 || u >= cols_ || v >= rows_)) {
      out.left_over_edge_m3 += share_m * spec.cell_area_m2();
      continue;
    }
    const int c = floor_within(u, 0, cols_ - 1), r = floor_within(v, 0, rows_ - 1);
    const std::int64_t i = std::int64_t(r) * cols_ + c;
    dirty(std::uint32_t(i));
    const float now = float(double(layers.height_m[i]) + share_m);
    put += double(now) - double(layers.height_m[i]);
    wanted += share_m;
    layers.height_m[i] = now;
    last = i;
    out.changed.include(c, r);
    activate(std::uint32_t(i));
  }
  // Give back the rounding of the writes on the last cell written.
  if (last >= 0 && put != wanted) {
    give_back(layers.height_m[last], wanted - put);
  }
  out.poured_m3 += volume_m3;
}

void SoilFlow::clear_hull() {
  for (std::uint32_t cell : hull_cells_) clear_flag(cell, kHull);
  hull_cells_.clear();
  hull_under_.clear();
  hull_rect_ = {};
}

void SoilFlow::mark_hull(const HeightGrid& grid, const Segment& lip, const Quat& orientation) {
  // The floor plate runs from the lip back depth_m along the blade frame's
  // +Z, the back plate from the heel up height_m along its +Y. A cell is
  // under the hull where its centre lies in the plan of either plate; the
  // underside there is the lower plate's height over the centre.
  clear_hull();
  const GridSpec& spec = grid.spec();
  const Vec3 back = rotate(orientation, {0.0, 0.0, blade_spec_.bucket.depth_m});
  const Vec3 up = rotate(orientation, {0.0, blade_spec_.bucket.height_m, 0.0});
  const Vec3 along = lip.b - lip.a;
  hull_heel_ = {lip.a + back, lip.b + back};
  const Vec3 corners[6] = {lip.a, lip.b, hull_heel_.a, hull_heel_.b, hull_heel_.a + up, hull_heel_.b + up};
  double u0 = 1e300, u1 = -1e300, v0 = 1e300, v1 = -1e300;
  hull_cx_ = hull_cz_ = 0.0;
  for (const Vec3& p : corners) {
    const double u = to_cells(p.x, spec.origin_m.x, dx_), v = to_cells(p.z, spec.origin_m.z, dz_);
    u0 = std::min(u0, u), u1 = std::max(u1, u), v0 = std::min(v0, v), v1 = std::max(v1, v);
    hull_cx_ += p.x / 6.0;
    hull_cz_ += p.z / 6.0;
  }
  // The cells whose centres can lie inside: centres at (c + 0.5) in cells.
  Rect r;
  r.c0 = int(std::clamp(std::ceil(u0 - 0.5), 0.0, double(cols_)));
  r.c1 = int(std::clamp(std::floor(u1 - 0.5) + 1.0, 0.0, double(cols_)));
  r.r0 = int(std::clamp(std::ceil(v0 - 0.5), 0.0, double(rows_)));
  r.r1 = int(std::clamp(std::floor(v1 - 0.5) + 1.0, 0.0, double(rows_)));
  if (r.empty()) return;
  hull_rect_ = r;
  hull_under_.assign(std::size_t(r.area()), std::numeric_limits<float>::infinity());
  hull_row_c0_.assign(std::size_t(r.r1 - r.r0), r.c1);
  hull_row_c1_.assign(std::size_t(r.r1 - r.r0), r.c0);
  struct Plate {
    Vec3 origin, s, t;
  };
  const Plate plates[2] = {{lip.a, along, back}, {hull_heel_.a, along, up}};
  for (int k = 0; k < 2; ++k) {
    const Plate& p = plates[k];
    hull_plans_[k] = {p.origin.x, p.origin.z, p.s.x, p.s.z, p.t.x, p.t.z, 0.0, 0.0, 0.0, 0.0};
  }
  const double ground = spec.origin_m.y;
  for (const Plate& p : plates) {
    // Plan coordinates (s, t) of a point: solve the 2x2 system of the
    // plate's two edges in plan; a plate seen edge-on covers no centre.
    const double det = p.s.x * p.t.z - p.s.z * p.t.x;
    const double area = std::hypot(p.s.x, p.s.z) * std::hypot(p.t.x, p.t.z);
    if (!(std::abs(det) > 1e-9 * area) || area == 0.0) continue;
    {
      // A cell's diagonal in s and in t: the lines s = 0 and s = 1 lie
      // |det| / |t| apart in plan, those of t |det| / |s|.
      HullPlan& plan = hull_plans_[&p - plates];
      plan.det = det;
      plan.inv_det = 1.0 / det;
      plan.margin_s = std::hypot(dx_, dz_) * std::hypot(p.t.x, p.t.z) / std::abs(det);
      plan.margin_t = std::hypot(dx_, dz_) * std::hypot(p.s.x, p.s.z) / std::abs(det);
    }
    // A centre on the lip's line (to a millionth of a cell) is the lip's to
    // cut: the step's cut may just have missed it by rounding.
    const double t_min = &p == &plates[0] ? 1e-6 * std::min(dx_, dz_) * std::hypot(p.s.x, p.s.z) / std::abs(det) : 0.0;
    // Along a row s and t are linear in the column: the columns where both
    // can lie in range, widened by a cell for rounding; the test itself is
    // made on every one of them, so the cells marked are those a test of
    // the whole rectangle would mark, at a cost that follows the plate.
    const double inv_det = 1.0 / det;
    const double ds = dx_ * p.t.z * inv_det, dt = -dx_ * p.s.z * inv_det;
    const double slope_floor = 1e-9 * (1.0 + std::abs(ds) + std::abs(dt));
    const double oy = p.origin.y - ground;
    for (int row = r.r0; row < r.r1; ++row) {
      const double pz = spec.origin_m.z + (row + 0.5) * dz_ - p.origin.z;
      const double s_z = pz * p.t.x, t_z = p.s.x * pz;
      const double px0 = spec.origin_m.x + (r.c0 + 0.5) * dx_ - p.origin.x;
      const double s0 = (px0 * p.t.z - s_z) * inv_det, t0 = (t_z - p.s.z * px0) * inv_det;
      double k0 = 0.0, k1 = double(r.c1 - r.c0 - 1);
      const auto narrow = [&](double v0, double dv, double lo, double hi) {
        if (std::abs(dv) <= slope_floor) return;  // (nearly) constant along the row: test them all
        double a = (lo - v0) / dv, b = (hi - v0) / dv;
        if (a > b) std::swap(a, b);
        k0 = std::max(k0, std::floor(a) - 1.0);
        k1 = std::min(k1, std::ceil(b) + 1.0);
      };
      narrow(s0, ds, 0.0, 1.0);
      narrow(t0, dt, t_min, 1.0);
      if (k0 > k1) continue;
      const int c_first = r.c0 + int(k0), c_end = r.c0 + int(k1) + 1;
      float* under_row = &hull_under_[hull_slot(r.c0, row)];
      int first = c_end, end = c_first;
      for (int c = c_first; c < c_end; ++c) {
        const double px = spec.origin_m.x + (c + 0.5) * dx_ - p.origin.x;
        const double s = (px * p.t.z - s_z) * inv_det, t = (t_z - p.s.z * px) * inv_det;
        if (s < 0.0 || s > 1.0 || t < t_min || t > 1.0) continue;
        const float y = float(oy + s * p.s.y + t * p.t.y);
        float& under = under_row[c - r.c0];
        under = std::min(under, y);
        first = std::min(first, c);
        end = c + 1;
      }
      int& row_first = hull_row_c0_[std::size_t(row - r.r0)];
      int& row_end = hull_row_c1_[std::size_t(row - r.r0)];
      row_first = std::min(row_first, first);
      row_end = std::max(row_end, end);
    }
  }
  for (int row = r.r0; row < r.r1; ++row)
    for (int c = hull_row_c0_[std::size_t(row - r.r0)]; c < hull_row_c1_[std::size_t(row - r.r0)]; ++c)
      if (hull_under_[hull_slot(c, row)] < std::numeric_limits<float>::infinity()) {
        const auto cell = std::uint32_t(std::int64_t(row) * cols_ + c);
        set_flag(cell, kHull);
        hull_cells_.push_back(cell);
      }
}

int SoilFlow::first_walk_sample(const GridSpec& spec, double x, double z, double nx, double nz, double step) const {
  // Along the walk every coordinate below is linear in the sample's index
  // m: the samples m in [1, M] keep each within its bounds where M is the
  // least of (bound - value) / change over the changes that head to a
  // bound. A sample more than a cell's diagonal inside a plate's plan lies
  // in a cell whose centre is inside it (at most half a diagonal away), so
  // marked; inside the grid by a cell, it is on the grid.
  double most = 0.0;
  for (const HullPlan& p : hull_plans_) {
    if (p.det == 0.0) continue;
    const double px = x - p.ox, pz = z - p.oz;
    const double s = (px * p.bz - pz * p.bx) * p.inv_det, t = (p.ax * pz - p.az * px) * p.inv_det;
    const double ds = step * (nx * p.bz - nz * p.bx) * p.inv_det, dt = step * (p.ax * nz - p.az * nx) * p.inv_det;
    const double ms = p.margin_s, mt = p.margin_t;
    double m = double(kMaxPushCells);
    const auto bound = [&m](double v, double d, double lo, double hi) {
      if (!(v > lo && v < hi)) m = 0.0;
      else if (d > 0.0) m = std::min(m, (hi - v) / d);
      else if (d < 0.0) m = std::min(m, (lo - v) / d);
    };
    bound(s, ds, ms, 1.0 - ms);
    bound(t, dt, mt, 1.0 - mt);
    most = std::max(most, m);
  }
  if (most < 1.0) return 1;
  // On the grid, a cell in from its edges.
  const double u = to_cells(x, spec.origin_m.x, dx_), v = to_cells(z, spec.origin_m.z, dz_);
  const auto bound = [&most](double w, double d, double hi) {
    if (d > 0.0) most = std::min(most, (hi - w) / d);
    else if (d < 0.0) most = std::min(most, (1.0 - w) / d);
  };
  bound(u, step * nx / dx_, double(cols_) - 1.0);
  bound(v, step * nz / dz_, double(rows_) - 1.0);
  return most < 1.0 ? 1 : int(std::floor(most)) + 1;
}

void SoilFlow::shoulder(HeightGrid& grid, SoilStepResult& out) {
  // Each cell under the hull with soil above the hull's underside passes
  // that excess outward, away from the hull's plan centre, to its
  // neighbour that way (of the 8, the one nearest the ray from the centre
  // through the cell), which adds it to its own and passes the sum on, to
  // the first cell outside the footprint, which takes it (one visit a cell:
  // walked from each cell to the footprint's edge, the pressed 0.75 m
  // bucket of docs/soil.md "The bucket under random strokes" took 2.4 ms
  // a step on 5 x 2.5 mm cells). The cells are taken in an order that
  // visits a cell's outward neighbour after it: rows outward from the
  // centre's, and in each row columns outward from the centre's. Where
  // that neighbour is off a walled grid or under a rigid body, or has no
  // room under the ceiling, the soil walks on along the cell's ray instead
  // (beyond a wall the other way), to the first cell outside the footprint
  // with room; beyond an open edge it leaves (counted).
  const GridSpec& spec = grid.spec();
  const HeightGrid::EditLayers layers = grid.edit_layers();
  float* h = layers.height_m;
  const Rect& hr = hull_rect_;
  if (hr.empty()) return;
  double taken = 0.0, put = 0.0;
  std::int64_t last_put = -1;
  // What each hull cell has been passed, metres of height on it.
  shoulder_in_.assign(hull_under_.size(), 0.0f);
  // Puts what fits under the ceiling of `rest` on cell t (outside the
  // footprint, under no body).
  const auto put_on = [&](std::int64_t t, float& rest, bool& moved) {
    const float add = std::min(rest, ceiling_m_ - h[t]);
    if (!(add > 0.0f)) return;
    dirty(std::uint32_t(t));
    const float raised = h[t] + add;
    put += double(raised) - double(h[t]);
    h[t] = raised;
    last_put = t;
    rest -= add;
    moved = true;
    out.changed.include(col_of(std::uint32_t(t)), row_of(std::uint32_t(t)));
    activate(std::uint32_t(t));
  };
  // `rest` leaves over an open edge (counted).
  const auto leave = [&](float& rest, bool& moved) {
    out.left_over_edge_m3 += double(rest) * spec.cell_area_m2();
    taken -= double(rest);
    rest = 0.0f;
    moved = true;
  };
  // Walks `rest` from the point (x, z) along the unit (nx, nz), both ways
  // (the second beyond a wall), to the first cells outside the footprint
  // and under no body with room under the ceiling; returns what found no
  // room.
  const auto walk_out = [&](double x, double z, double nx, double nz, float rest, bool& moved) {
    const double step = std::min(dx_ / std::max(std::abs(nx), 1e-9), dz_ / std::max(std::abs(nz), 1e-9));
    for (const double side : {1.0, -1.0}) {
      for (int m = first_walk_sample(spec, x, z, side * nx, side * nz, step); m <= kMaxPushCells && rest > 0.0f; ++m) {
        const double u = to_cells(x + side * nx * m * step, spec.origin_m.x, dx_);
        const double v = to_cells(z + side * nz * m * step, spec.origin_m.z, dz_);
        if (u < 0.0 || v < 0.0 || u >= cols_ || v >= rows_) {
          if (params_.edge == SoilEdge::kOpen) leave(rest, moved);
          break;
        }
        const std::int64_t t = std::int64_t(std::floor(v)) * cols_ + std::int64_t(std::floor(u));
        if (!(queued_[t] & kHull) && obstacle_[t] == 0) put_on(t, rest, moved);
      }
      if (rest <= 0.0f) break;
    }
    return rest;
  };
  const double inv_diagonal = 1.0 / std::hypot(dx_, dz_);
  const int cc = floor_within(to_cells(hull_cx_, spec.origin_m.x, dx_), hr.c0, hr.c1 - 1);
  const int rc = floor_within(to_cells(hull_cz_, spec.origin_m.z, dz_), hr.r0, hr.r1 - 1);
  const auto visit = [&](int c, int row) {
    const std::size_t slot = hull_slot(c, row);
    const float covered = hull_under_[slot];
    if (!(covered < std::numeric_limits<float>::infinity())) return;
    const auto cell = std::uint32_t(std::int64_t(row) * cols_ + c);
    const float under = std::max(0.0f, covered);
    const float now = h[cell];
    // Float rounding of the cut (which leaves the lip's height) is no excess.
    const bool excess = now - under > 4.0f * std::numeric_limits<float>::epsilon() * std::max(now, 1.0f);
    const float passed = shoulder_in_[slot];
    if (!excess && !(passed > 0.0f)) return;
    float rest = (excess ? now - under : 0.0f) + passed;
    // The way out: the ray from the hull's plan centre through the cell
    // (from the centre itself, along +X).
    const double x = spec.origin_m.x + (c + 0.5) * dx_, z = spec.origin_m.z + (row + 0.5) * dz_;
    double rx = x - hull_cx_, rz = z - hull_cz_;
    if (!(std::abs(rx) + std::abs(rz) > 1e-12)) rx = 1.0, rz = 0.0;
    // The neighbour that way: of the (up to) three with no component
    // against the ray, the one most along it (the largest cosine, here
    // times the ray's length: along X |rx|, along Z |rz|, the diagonal
    // (|rx| dx + |rz| dz) / its length).
    const int sc = rx > 0.0 ? 1 : rx < 0.0 ? -1 : 0, sr = rz > 0.0 ? 1 : rz < 0.0 ? -1 : 0;
    const double ax = std::abs(rx), az = std::abs(rz), diagonal = (ax * dx_ + az * dz_) * inv_diagonal;
    const int dc = diagonal >= std::max(ax, az) ? sc : ax >= az ? sc : 0;
    const int dr = diagonal >= std::max(ax, az) ? sr : ax >= az ? 0 : sr;
    const int tc = c + dc, tr = row + dr;
    bool moved = false;
    if (tc >= 0 && tr >= 0 && tc < cols_ && tr < rows_) {
      const std::int64_t t = std::int64_t(tr) * cols_ + tc;
      if (queued_[t] & kHull) {
        shoulder_in_[hull_slot(tc, tr)] += rest;  // passed on
        rest = 0.0f;
        moved = true;
      } else if (obstacle_[t] == 0) {
        put_on(t, rest, moved);
      }
    } else if (params_.edge == SoilEdge::kOpen) {
      leave(rest, moved);
    }
    if (rest > 0.0f) {
      const double len = std::hypot(rx, rz);
      rest = walk_out(x, z, rx / len, rz / len, rest, moved);
    }
    // What found no room (or nowhere to go: a hull filling the grid) stays
    // in the cell, on the underside (a cell below it keeps its height and
    // only passes the soil on).
    const float kept = (excess ? under : now) + rest;
    if (kept == now) return;
    dirty(cell);
    h[cell] = kept;
    taken += double(now) - double(kept);
    out.changed.include(c, row);
    if (kept < now) lowered(cell, h);
    else activate(cell);
  };
  // Rows outward from the centre's (rc, rc - 1, rc + 1, ...), in each the
  // columns outward from the centre's.
  for (int k = 0; k <= 2 * (hr.r1 - hr.r0); ++k) {
    const int row = k % 2 == 0 ? rc + k / 2 : rc - (k + 1) / 2;
    if (row < hr.r0 || row >= hr.r1) continue;
    const int c0 = hull_row_c0_[std::size_t(row - hr.r0)], c1 = hull_row_c1_[std::size_t(row - hr.r0)];
    for (int c = std::max(cc, c0); c < c1; ++c) visit(c, row);
    for (int c = std::min(cc - 1, c1 - 1); c >= c0; --c) visit(c, row);
  }
  // Give back the rounding of the writes on the last cell written.
  if (last_put >= 0 && put != taken) give_back(h[last_put], taken - put);
  out.shouldered_m3 += taken * spec.cell_area_m2();
}

}  // namespace terracut
