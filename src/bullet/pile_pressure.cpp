// Soil that flows against the bodies (PilePressureSpec; docs/bullet.md,
// "Piles against bodies"): the soil keeps a ring of one sample free round
// each body, a body that moved into soil pushes what stands in its ring a
// sample out, and the soil outside the ring presses on the body's sides
// with Rankine's active earth pressure.
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "terracut/core/format.hpp"
#include "terracut/core/ranges.hpp"
#include "terrain_world_impl.hpp"

namespace terracut::bullet {

using detail::from_bt;
using detail::to_bt;

namespace {

// The samples under a body's box: its ring (TerrainWorld::ring_around, not
// clipped) less one sample all round.
Rect footprint_of(const SoilObstacle& o) { return {o.cells.c0 + 1, o.cells.r0 + 1, o.cells.c1 - 1, o.cells.r1 - 1}; }

// A vertical face of a body that piles press on: its bottom edge's ends
// (world X and Z; Y unused) and its outward normal (horizontal, unit).
struct SideFace {
  btVector3 start, end, outward;
};

// The side faces of body b (spec: its BodySpec; lo, hi: its bounding box)
// into faces; returns how many (at most 4).
int side_faces(const btRigidBody& b, const BodySpec& spec, const btVector3& lo, const btVector3& hi,
               SideFace (&faces)[4]) {
  int n = 0;
  if (spec.shape != BodyShape::kBox) {
    // A sphere or an upright cylinder looks the same from every side: the
    // four sides of its bounding box.
    faces[n++] = {{lo.x(), 0, lo.z()}, {lo.x(), 0, hi.z()}, {-1, 0, 0}};
    faces[n++] = {{hi.x(), 0, hi.z()}, {hi.x(), 0, lo.z()}, {1, 0, 0}};
    faces[n++] = {{hi.x(), 0, lo.z()}, {lo.x(), 0, lo.z()}, {0, 0, -1}};
    faces[n++] = {{lo.x(), 0, hi.z()}, {hi.x(), 0, hi.z()}, {0, 0, 1}};
    return n;
  }
  // A box: its local axis nearest the world's Y is up, the faces normal to
  // the other two are its sides (for a box yawed about Y, exactly its
  // vertical faces), each as its horizontal projection.
  const btMatrix3x3& basis = b.getWorldTransform().getBasis();
  const btVector3 half = to_bt(half_extents_m(spec));
  const btVector3 origin = b.getWorldTransform().getOrigin();
  int up = 0;
  for (int k = 1; k < 3; ++k)
    if (std::fabs(basis.getColumn(k).y()) > std::fabs(basis.getColumn(up).y())) up = k;
  const auto flat = [](btVector3 v) { return btVector3(v.x(), 0, v.z()); };
  for (int axis = 0; axis < 3; ++axis) {
    if (axis == up) continue;
    const int other = 3 - up - axis;
    btVector3 outward = flat(basis.getColumn(axis));
    if (!(outward.length() > btScalar(1e-6))) continue;
    outward.normalize();
    const btVector3 tangent = basis.getColumn(other) * half[other];
    for (const btScalar sign : {btScalar(1), btScalar(-1)}) {
      const btVector3 middle = flat(origin + basis.getColumn(axis) * (sign * half[axis]));
      faces[n++] = {middle - flat(tangent), middle + flat(tangent), outward * sign};
    }
  }
  return n;
}

// The first sample outside cells (a body's ring, SoilObstacle::cells) on the
// horizontal ray from `from` along `outward` into col, row; false when it
// is off the grid (no soil there).
bool first_sample_out(const HeightGrid& grid, const Rect& cells, const btVector3& from,
                      const btVector3& outward, int& col, int& row) {
  // Sample c is nearest to the points of cell coordinate u in [c, c + 1)
  // (HeightGrid::cell_u): the ring's samples cover u in [c0, c1). Where the
  // ray from `from` along `outward` leaves that rectangle, the sample on
  // the far side of the edge it crosses is the first one outside.
  const GridSpec& g = grid.spec();
  const double u = grid.cell_u(double(from.x())), v = grid.cell_v(double(from.z()));
  const double dx = double(outward.x()) / g.cell_x_m(), dz = double(outward.z()) / g.cell_z_m();
  const double inf = std::numeric_limits<double>::infinity();
  const double sx = dx > 0.0 ? (cells.c1 - u) / dx : (dx < 0.0 ? (cells.c0 - u) / dx : inf);
  const double sz = dz > 0.0 ? (cells.r1 - v) / dz : (dz < 0.0 ? (cells.r0 - v) / dz : inf);
  const double s = std::max(0.0, std::min(sx, sz));
  if (!std::isfinite(s)) return false;
  col = std::clamp(int(std::floor(u + s * dx)), cells.c0 - 1, cells.c1);
  row = std::clamp(int(std::floor(v + s * dz)), cells.r0 - 1, cells.r1);
  if (sx <= sz) col = dx > 0.0 ? cells.c1 : cells.c0 - 1;
  else row = dz > 0.0 ? cells.r1 : cells.r0 - 1;
  return col >= 0 && col < grid.cols() && row >= 0 && row < grid.rows();
}

}  // namespace

std::string validate(const PilePressureSpec& p) {
  if (p.enabled && !(p.unit_weight_n_per_m3 > 0.0 && p.unit_weight_n_per_m3 <= kRangeMax))
    return must_be("pile.pile.unit_weight_n_per_m3", "in (0, 1e9]", p.unit_weight_n_per_m3);
  if (p.enabled && !(p.friction_angle_deg > 0.0 && p.friction_angle_deg <= 80.0))
    return must_be("pile.pile.friction_angle_deg", "in (0, 80]", p.friction_angle_deg);
  if (p.enabled && !(p.shed_tolerance_m >= 0.0 && p.shed_tolerance_m <= 0.01))
    return must_be("pile.pile.shed_tolerance_m", "in [0, 0.01]", p.shed_tolerance_m);
  return {};
}

SoilObstacle TerrainWorld::ring_around(int i) const {
  btVector3 lo, hi;
  impl_->bodies[std::size_t(i)]->getAabb(lo, hi);
  // The samples whose centres lie under the box, and one more all round;
  // not clipped to the grid (at most one sample past each edge).
  const GridSpec& g = grid_.spec();
  const double cx = g.cell_x_m(), cz = g.cell_z_m();
  const double c0 = std::ceil((double(lo.x()) - g.origin_m.x) / cx - 0.5) - 1.0;
  const double c1 = std::floor((double(hi.x()) - g.origin_m.x) / cx - 0.5) + 2.0;
  const double r0 = std::ceil((double(lo.z()) - g.origin_m.z) / cz - 0.5) - 1.0;
  const double r1 = std::floor((double(hi.z()) - g.origin_m.z) / cz - 0.5) + 2.0;
  const float bottom = float(double(lo.y()) - g.origin_m.y);
  if (!(std::isfinite(c0) && std::isfinite(c1) && std::isfinite(r0) && std::isfinite(r1)))
    return {{}, bottom};  // a body gone to infinity (NaN) covers nothing
  const auto bound = [](double v, int n) { return int(std::clamp(v, -1.0, double(n + 1))); };
  return {{bound(c0, g.cols), bound(r0, g.rows), bound(c1, g.cols), bound(r1, g.rows)}, bottom};
}

SoilObstacle TerrainWorld::soil_obstacle(int i) const {
  SoilObstacle o = ring_around(i);
  o.cells = {std::max(o.cells.c0, 0), std::max(o.cells.r0, 0), std::min(o.cells.c1, grid_.cols()),
             std::min(o.cells.r1, grid_.rows())};
  return o;
}

void TerrainWorld::shed_rings() {
  if (!params_.pile.enabled) return;
  Impl& m = *impl_;
  obstacles_.clear();
  for (int i = 0; i < body_count(); ++i) obstacles_.push_back(soil_obstacle(i));
  const auto obstructed = [this](int col, int row) {
    for (const SoilObstacle& o : obstacles_)
      if (col >= o.cells.c0 && col < o.cells.c1 && row >= o.cells.r0 && row < o.cells.r1) return true;
    return false;
  };
  const float* h = grid_.heights();
  const float ceiling = float(bounds_.max_height_m);
  const float tolerance = float(params_.pile.shed_tolerance_m);
  Rect changed{};
  for (std::size_t i = 0; i < m.bodies.size(); ++i) {
    const btRigidBody& b = *m.bodies[i];
    if (m.held[i] || b.isStaticOrKinematicObject()) continue;
    const SoilObstacle& o = obstacles_[i];
    if (o.cells.empty()) continue;
    const Rect f = footprint_of(ring_around(int(i)));
    // What stays in the ring: up to the body's lowest point, or to the
    // lowest soil under it where that is higher (a body resting on the soil
    // sinks into it by a fraction of a millimetre; keeping the ring at its
    // support level means that a body pushed on meets soil no higher than
    // what it stood on, with no step to ride up).
    float support = std::numeric_limits<float>::infinity();
    for (int row = std::max(f.r0, 0); row < std::min(f.r1, grid_.rows()); ++row)
      for (int col = std::max(f.c0, 0); col < std::min(f.c1, grid_.cols()); ++col)
        support = std::min(support, h[grid_.index(col, row)]);
    const float keep = std::isfinite(support) ? std::max(o.bottom_m, support) : o.bottom_m;
    for (int row = o.cells.r0; row < o.cells.r1; ++row)
      for (int col = o.cells.c0; col < o.cells.c1; ++col) {
        const int dc = col < f.c0 ? -1 : (col >= f.c1 ? 1 : 0);
        const int dr = row < f.r0 ? -1 : (row >= f.r1 ? 1 : 0);
        if (dc == 0 && dr == 0) continue;  // under the body: its support
        const int tc = col + dc, tr = row + dr;
        if (tc < 0 || tc >= grid_.cols() || tr < 0 || tr >= grid_.rows() || obstructed(tc, tr)) continue;
        const std::int64_t from = grid_.index(col, row), to = grid_.index(tc, tr);
        // Soil within the tolerance of what stays is left (a resting body
        // settles by fractions of a micrometre).
        if (!(h[from] - keep > tolerance)) continue;
        const float move = std::min(h[from] - keep, ceiling - h[to]);
        if (!(move > 0.0f)) continue;
        move_height(from, to, move);
        pending_shed_m3_ += double(move) * grid_.spec().cell_area_m2();
        changed.include(col, row);
        changed.include(tc, tr);
      }
  }
  if (changed.empty()) return;
  pending_shed_rect_.include(changed);
  terrain_changed(changed);
}

void TerrainWorld::apply_pile_pressure() {
  if (!params_.pile.enabled) return;
  Impl& m = *impl_;
  const GridSpec& g = grid_.spec();
  const float* h = grid_.heights();
  // Rankine's active coefficient on a smooth vertical face: K = tan^2(45 - phi/2).
  const double half_phi = 0.5 * params_.pile.friction_angle_deg * std::numbers::pi / 180.0;
  const double t = std::tan(0.25 * std::numbers::pi - half_phi);
  const double coeff = 0.5 * t * t * params_.pile.unit_weight_n_per_m3;  // P / h^2, N/m^3
  for (std::size_t i = 0; i < m.bodies.size(); ++i) {
    btRigidBody& b = *m.bodies[i];
    if (m.held[i] || b.isStaticOrKinematicObject()) continue;
    SoilView& view = views_[i];
    const bool asleep = !b.isActive();
    if (asleep && view.pile_asleep && !view.band_changed) {
      // Asleep since it was last summed, on soil that has not changed: the
      // same push, and a sleeping body is only woken by a changed band.
      if (view.pile_magnitude_n > 0.0) {
        pending_pile_force_n_ += view.pile_magnitude_n;
        pending_pile_thrust_n_ = pending_pile_thrust_n_ + view.pile_force_n;
      }
      continue;
    }
    view.pile_asleep = false;
    const SoilObstacle o = soil_obstacle(int(i));
    if (o.cells.empty()) continue;
    btVector3 lo, hi;
    b.getAabb(lo, hi);
    const double bottom = double(o.bottom_m), tall = double(hi.y() - lo.y());
    const btVector3 centre = b.getCenterOfMassPosition();
    btVector3 force(0, 0, 0), torque(0, 0, 0);
    double magnitude = 0.0;
    // Each side face is split into pieces no wider than a cell; a piece is
    // pressed by the soil on the first sample outside the ring straight out
    // from it (along the face's outward normal): the soil banks against the
    // ring, so that sample is the pile's height at the face.
    const double piece_m = std::min(g.cell_x_m(), g.cell_z_m());
    SideFace faces[4];
    const int face_count = side_faces(b, specs_[i], lo, hi, faces);
    for (int fi = 0; fi < face_count; ++fi) {
      const SideFace& face = faces[fi];
      const btVector3 along = face.end - face.start;
      const double width = double(along.length());
      if (!(width > 0.0)) continue;
      const int pieces = std::max(1, int(std::ceil(width / piece_m)));
      for (int k = 0; k < pieces; ++k) {
        const btVector3 q = face.start + along * btScalar((k + 0.5) / pieces);
        int col = 0, row = 0;
        if (!first_sample_out(grid_, o.cells, q, face.outward, col, row)) continue;
        const double above = std::clamp(double(h[grid_.index(col, row)]) - bottom, 0.0, tall);
        if (!(above > 0.0)) continue;
        const double p = coeff * above * above * width / pieces;
        const btVector3 f = face.outward * btScalar(-p);
        const btVector3 at(q.x(), btScalar(g.origin_m.y + bottom + above / 3.0), q.z());
        force += f;
        torque += (at - centre).cross(f);
        magnitude += p;
      }
    }
    view.pile_asleep = asleep;
    view.pile_magnitude_n = magnitude;
    view.pile_force_n = from_bt(force);
    if (!(magnitude > 0.0)) continue;
    pending_pile_force_n_ += magnitude;
    pending_pile_thrust_n_ = pending_pile_thrust_n_ + view.pile_force_n;
    // Static friction carries a thrust below the body's sliding friction on
    // level ground (Bullet multiplies the two friction coefficients): the
    // body would not move, and Bullet's iterative solver lets an awake body
    // under a steady sub-friction push creep (about 3 um per step).
    const double friction = double(b.getFriction()) * params_.terrain_friction *
                            specs_[i].mass_kg * params_.gravity_m_s2;
    if (!(double(force.length()) > friction)) continue;
    // A sleeping body wakes when the soil that presses on it changed.
    if (!b.isActive()) {
      if (!views_[i].band_changed) continue;
      b.activate(true);
    }
    b.applyCentralForce(force);
    b.applyTorque(torque);
  }
  for (SoilView& view : views_) view.band_changed = false;
}

Rect TerrainWorld::pile_band(const SoilObstacle& o) const { return grown_by_one(o.cells); }

}  // namespace terracut::bullet
