#include "terracut/core/soil_ahead.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "terracut/core/surface.hpp"
#include "geometry.hpp"

namespace terracut {

double depth_lookahead_m(const GridSpec& spec) {
  return 1.5 * std::hypot(spec.cell_x_m(), spec.cell_z_m());
}

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

// The number of parts an edge is read at.
int edge_parts(const GridSpec& spec, const Segment& edge) {
  const double cell = std::min(spec.cell_x_m(), spec.cell_z_m());
  // (Clamped in double: a finite edge may be far longer than INT_MAX cells.)
  return static_cast<int>(std::clamp(std::ceil(length(edge.b - edge.a) / cell), 2.0, 64.0));
}

// The depth and length of a uniform cut equivalent to the parts' depths d_i
// (each of length `part`): the same sum of d (the cut's section, on which the
// cohesive and surcharge terms grow) and of d^2 (on which the weight term
// grows): depth = sum d^2 / sum d, length = part (sum d)^2 / sum d^2. A part
// at zero depth adds nothing to either, so the force stays continuous as
// parts come into or out of the soil; a uniform cut is itself.
void equivalent_cut(double sum_d, double sum_d2, double part, double& depth_m, double& length_m) {
  if (!(sum_d > 0.0) || !(sum_d2 > 0.0)) return;
  depth_m = sum_d2 / sum_d;
  length_m = part * sum_d * sum_d / sum_d2;
}

// Points start + t step (world x, z; t from t0 to t1) read in cell
// coordinates: no two divisions a point, and where every point of the walk
// lies inside the grid's outer half cells (the walk is straight, so its
// ends decide, with a margin for their rounding) the surface's clamps are
// skipped.
class Walk {
 public:
  Walk(const GridSpec& spec, Representation representation, double x, double z, double step_x, double step_z,
       double t0, double t1)
      : cols_(spec.cols),
        rows_(spec.rows),
        representation_(representation),
        u0_((x - spec.origin_m.x) / spec.cell_x_m()),
        v0_((z - spec.origin_m.z) / spec.cell_z_m()),
        du_(step_x / spec.cell_x_m()),
        dv_(step_z / spec.cell_z_m()) {
    interior_ = representation == Representation::kSurface && clear(t0) && clear(t1);
  }
  detail::SurfacePoint at(double t) const {
    const double u = u0_ + du_ * t, v = v0_ + dv_ * t;
    return interior_ ? detail::SurfacePoint::interior(cols_, u, v)
                     : detail::SurfacePoint(cols_, rows_, representation_, u, v);
  }

 private:
  bool clear(double t) const {
    const double u = u0_ + du_ * t, v = v0_ + dv_ * t;
    return u >= 0.5 + 1e-6 && u < cols_ - 0.5 - 1e-6 && v >= 0.5 + 1e-6 && v < rows_ - 0.5 - 1e-6;
  }
  int cols_, rows_;
  Representation representation_;
  double u0_, v0_, du_, dv_;
  bool interior_ = false;
};

}  // namespace

SoilAhead soil_ahead(const HeightGrid& grid, Representation representation, const Segment& edge,
                     Vec3 velocity_m_per_s, double lookahead_m, double wedge_per_depth) noexcept {
  SoilAhead out;
  const double speed_xz = std::hypot(velocity_m_per_s.x, velocity_m_per_s.z);
  if (!(speed_xz > 0.0) || !std::isfinite(speed_xz) || !is_finite(edge.a) || !is_finite(edge.b) ||
      !std::isfinite(lookahead_m) || !std::isfinite(wedge_per_depth))
    return out;
  const Vec3 u = Vec3{velocity_m_per_s.x, 0.0, velocity_m_per_s.z} * (1.0 / speed_xz);
  const GridSpec& spec = grid.spec();
  const double cell = std::min(spec.cell_x_m(), spec.cell_z_m());
  const int n = edge_parts(spec, edge);
  // The parts' length in plan, the spacing of the wedge's points along the
  // motion where it is longer than a cell (see the pile below).
  const double part_m = std::hypot(edge.b.x - edge.a.x, edge.b.z - edge.a.z) / n;
  const double ground = spec.origin_m.y;
  const float* now_m = grid.heights();
  const float* initial_m = grid.initial();
  double sum_d = 0.0, sum_d2 = 0.0, sum_pile_d = 0.0;
  // The parts' centres, one lookahead ahead.
  const Vec3 e = edge.b - edge.a;
  const Walk ahead(spec, representation, edge.a.x + u.x * lookahead_m, edge.a.z + u.z * lookahead_m, e.x / n, e.z / n,
                   0.5, n - 0.5);
  for (int i = 0; i < n; ++i) {
    const Vec3 p = lerp(edge.a, edge.b, (i + 0.5) / n);
    // The depth at the lookahead, below the undisturbed surface.
    const Vec3 q = p + u * lookahead_m;
    const detail::SurfacePoint at_q = ahead.at(i + 0.5);
    const double depth = ground + std::min(at_q.height(now_m), at_q.height(initial_m)) - p.y;
    if (!(depth > 0.0)) continue;
    sum_d += depth;
    sum_d2 += depth * depth;
    // The pile over the wedge: soil above the initial surface ahead.
    if (!(wedge_per_depth > 0.0)) continue;
    const double reach_m = wedge_per_depth * depth;
    if (!(reach_m < kInfinity)) continue;  // (an overflowing depth x wedge: no pile read)
    // The mean over the wedge by the midpoint rule on intervals of one
    // spacing h from the lookahead on, the last one what is left of the
    // reach (weighted by its length): the points stay where they are as the
    // depth changes and the last interval grows from nothing, so the pile
    // read is continuous in the depth (a count of evenly spread points,
    // ceil(reach / h), moved them all when it changed by one: a step of up
    // to 4 % of the pile on a 2 m edge over 5 mm cells). h is one cell, or
    // the part's length where that is longer (the wedge read as finely
    // along the motion as the edge is along itself: on a 1 m edge of 64
    // parts over 5 mm cells, 15.6 mm, 7 points a part where one a cell took
    // two thirds of the step's force; the force moved by at most 0.13 % over
    // the soil benchmark's push, docs/forces.md), and at least 1/64 of the
    // reach.
    const double h = std::max({cell, part_m < kInfinity ? part_m : cell, reach_m / 64.0});
    const int whole = static_cast<int>(std::clamp(std::floor(reach_m / h), 0.0, 64.0));
    const double rest_m = std::max(0.0, reach_m - whole * h);
    const double last_t = rest_m > 0.0 ? whole * h + 0.5 * rest_m : (whole - 0.5) * h;
    const Walk wedge(spec, representation, q.x, q.z, u.x, u.z, std::min(0.5 * h, last_t), last_t);
    const auto pile_at = [&](double t) {
      const detail::SurfacePoint r = wedge.at(t);
      return std::max(0.0, r.height(now_m) - r.height(initial_m));
    };
    double pile = 0.0;
    for (int k = 0; k < whole; ++k) pile += pile_at((k + 0.5) * h);
    pile *= h;
    if (rest_m > 0.0) pile += rest_m * pile_at(whole * h + 0.5 * rest_m);
    pile /= reach_m;
    // Weighted by the part's depth: the surcharge acts on q d w.
    sum_pile_d += depth * pile;
  }
  equivalent_cut(sum_d, sum_d2, length(edge.b - edge.a) / n, out.depth_m, out.width_m);
  if (sum_d > 0.0) out.pile_m = sum_pile_d / sum_d;
  return out;
}

Embedment embedment(const HeightGrid& grid, Representation representation, const Segment& edge,
                    double lookahead_m) noexcept {
  Embedment out;
  if (!is_finite(edge.a) || !is_finite(edge.b) || !std::isfinite(lookahead_m)) return out;
  const Vec3 e = edge.b - edge.a;
  const double eh = std::hypot(e.x, e.z);
  // The sides to read: the two faces, or four directions for a vertical edge.
  Vec3 sides[4];
  int side_count = 0;
  if (eh > 1e-9 * std::max(length(e), 1e-300)) {
    const Vec3 n{e.z / eh, 0.0, -e.x / eh};
    sides[0] = n * lookahead_m;
    sides[1] = n * -lookahead_m;
    side_count = 2;
  } else {
    sides[0] = {lookahead_m, 0.0, 0.0};
    sides[1] = {-lookahead_m, 0.0, 0.0};
    sides[2] = {0.0, 0.0, lookahead_m};
    sides[3] = {0.0, 0.0, -lookahead_m};
    side_count = 4;
  }
  const GridSpec& spec = grid.spec();
  const int n = edge_parts(spec, edge);
  // The surface beside each part's centre, summed over the sides (n <= 64).
  double beside[64] = {};
  for (int k = 0; k < side_count; ++k) {
    const Walk walk(spec, representation, edge.a.x + sides[k].x, edge.a.z + sides[k].z, e.x / n, e.z / n, 0.5,
                    n - 0.5);
    for (int i = 0; i < n; ++i) beside[i] += spec.origin_m.y + walk.at(i + 0.5).height(grid.heights());
  }
  double sum_d = 0.0, sum_d2 = 0.0;
  for (int i = 0; i < n; ++i) {
    const Vec3 p = lerp(edge.a, edge.b, (i + 0.5) / n);
    const double depth = beside[i] / side_count - p.y;
    if (depth > 0.0) {
      sum_d += depth;
      sum_d2 += depth * depth;
    }
  }
  equivalent_cut(sum_d, sum_d2, length(e) / n, out.depth_m, out.length_m);
  return out;
}

TwistEngagement twist_engagement(const HeightGrid& grid, Representation representation,
                                 const Segment& edge, Vec3 centre, double yaw_rate_rad_per_s,
                                 double lookahead_m, double& mean_depth_m) noexcept {
  TwistEngagement out;
  mean_depth_m = 0.0;
  const Vec3 e = edge.b - edge.a;
  const double eh = std::hypot(e.x, e.z);
  if (yaw_rate_rad_per_s == 0.0 || !std::isfinite(yaw_rate_rad_per_s) || !is_finite(edge.a) ||
      !is_finite(edge.b) || !is_finite(centre) || !std::isfinite(lookahead_m) || !(eh > 0.0))
    return out;
  const Vec3 u{e.x / eh, 0.0, e.z / eh};  // the edge's horizontal direction
  const Vec3 n{u.z, 0.0, -u.x};           // Y x u
  const int parts = edge_parts(grid.spec(), edge);
  const double ds = eh / parts;  // horizontal length of a part
  const double turn = yaw_rate_rad_per_s > 0.0 ? 1.0 : -1.0;
  double depth_sum = 0.0;
  for (int i = 0; i < parts; ++i) {
    const Vec3 p = lerp(edge.a, edge.b, (i + 0.5) / parts);
    const double s = (p.x - centre.x) * u.x + (p.z - centre.z) * u.z;
    if (s == 0.0) continue;
    const double along = turn * (s > 0.0 ? 1.0 : -1.0) * lookahead_m;  // the motion's side
    const double depth = surface_y_m(grid, representation, p.x + n.x * along, p.z + n.z * along) - p.y;
    if (!(depth > 0.0)) continue;
    // The part spans [s - ds/2, s + ds/2]; its integrals at its centre.
    out.engaged_length_m += ds;
    out.abs_moment_m2 += std::abs(s) * ds;
    out.signed_length_m += (s > 0.0 ? ds : -ds);
    out.second_moment_m3 += (s * s + ds * ds / 12.0) * ds;
    depth_sum += depth;
  }
  if (out.engaged_length_m > 0.0) mean_depth_m = depth_sum / (out.engaged_length_m / ds);
  return out;
}

}  // namespace terracut
