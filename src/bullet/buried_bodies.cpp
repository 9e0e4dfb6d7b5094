// Buried bodies (BodySpec::buried; docs/bullet.md, "Buried bodies"): held
// still, static in Bullet, while the soil covers them; released when the
// blade reaches one (the tool plate's box meets its box, or the cut takes
// the soil over its footprint down to its top), or, with a force-limited
// plate, when the plate pushes it harder than its break-out force (the
// soil's passive resistance): it becomes dynamic, and the soil it stood in
// is lowered to its lowest point.
#include <algorithm>
#include <cmath>
#include <numbers>

#include "terrain_world_impl.hpp"

namespace terracut::bullet {

double break_out_resistance_n(const BreakOutSpec& soil, const BreakOutGeometry& g) {
  const double phi = soil.friction_angle_deg * std::numbers::pi / 180.0;
  const double root_kp = std::tan(0.25 * std::numbers::pi + 0.5 * phi);  // sqrt(K_p)
  const double kp = root_kp * root_kp;
  const double zt = g.top_depth_m, zb = std::max(g.bottom_depth_m, g.top_depth_m);
  const double passive = g.width_m * (0.5 * kp * soil.unit_weight_n_per_m3 * (zb * zb - zt * zt) +
                                      2.0 * soil.cohesion_pa * root_kp * (zb - zt));
  const double normal = g.weight_n + soil.unit_weight_n_per_m3 * g.overburden_m * g.footprint_m2 +
                        g.down_push_n;
  // The base slides on the soil under it: Mohr-Coulomb shear, c A + N tan phi.
  return passive + soil.cohesion_pa * g.footprint_m2 + normal * std::tan(phi);
}

double lift_out_resistance_n(const BreakOutSpec& soil, const BreakOutGeometry& g) {
  return g.weight_n + soil.unit_weight_n_per_m3 * g.overburden_m * g.footprint_m2;
}

BreakOutGeometry TerrainWorld::break_out_geometry(int i, Vec3 push, double down_n) const {
  const btRigidBody& b = *impl_->bodies[std::size_t(i)];
  btVector3 lo, hi;
  b.getCollisionShape()->getAabb(b.getWorldTransform(), lo, hi);
  const double ground = grid_.spec().origin_m.y;
  BreakOutGeometry g;
  const double sx = double(hi.x() - lo.x()), sz = double(hi.z() - lo.z());
  Vec3 d{push.x, 0.0, push.z};
  const double l = length(d);
  d = l > 0.0 ? d * (1.0 / l) : Vec3{};
  g.width_m = std::fabs(d.z) * sx + std::fabs(d.x) * sz;
  g.footprint_m2 = sx * sz;
  g.weight_n = specs_[std::size_t(i)].mass_kg * params_.gravity_m_s2;
  g.down_push_n = std::max(down_n, 0.0);
  const double top = double(hi.y()) - ground, bottom = double(lo.y()) - ground;
  // The soil over it: the mean height over its footprint.
  const Rect f = samples_under(lo, hi);
  const float* h = grid_.heights();
  double over = 0.0;
  for (int row = f.r0; row < f.r1; ++row)
    for (int col = f.c0; col < f.c1; ++col) over += double(h[grid_.index(col, row)]);
  if (!f.empty()) g.overburden_m = std::max(over / double(f.area()) - top, 0.0);
  // The soil beside the face the push drives into the soil: the samples one
  // cell out of the footprint whose distance from the centre along the push
  // passes the box's half depth along it (the whole ring without a push).
  const double cx = 0.5 * double(lo.x() + hi.x()), cz = 0.5 * double(lo.z() + hi.z());
  const double half = 0.5 * (std::fabs(d.x) * sx + std::fabs(d.z) * sz);
  const Rect ring = grown_by_one(f);
  double sum = 0.0, all = 0.0;
  int n = 0, n_all = 0;
  for (int row = ring.r0; row < ring.r1; ++row)
    for (int col = ring.c0; col < ring.c1; ++col) {
      if (col >= f.c0 && col < f.c1 && row >= f.r0 && row < f.r1) continue;
      const double v = double(h[grid_.index(col, row)]);
      all += v;
      ++n_all;
      if ((grid_.sample_x(col) - cx) * d.x + (grid_.sample_z(row) - cz) * d.z > half) {
        sum += v;
        ++n;
      }
    }
  const double surface = n > 0 ? sum / n : (n_all > 0 ? all / n_all : top);
  g.top_depth_m = std::max(surface - top, 0.0);
  g.bottom_depth_m = std::max(surface - bottom, 0.0);
  return g;
}

void TerrainWorld::judge_held_pushes() {
  Impl& m = *impl_;
  info_.held_push_n = 0.0;
  info_.held_resistance_n = 0.0;
  for (std::size_t i = 0; i < m.bodies.size(); ++i) {
    const Vec3 f = held_push_n_[i];
    held_push_n_[i] = {};
    if (!m.held[i] || (f.x == 0.0 && f.y == 0.0 && f.z == 0.0)) continue;
    const double across = std::hypot(f.x, f.z);
    const BreakOutGeometry g = break_out_geometry(int(i), f, -f.y);
    const double resist = break_out_resistance_n(params_.break_out, g);
    if (across >= info_.held_push_n) {
      info_.held_push_n = across;
      info_.held_resistance_n = resist;
    }
    if (across > resist || f.y > lift_out_resistance_n(params_.break_out, g)) m.breaking[i] = 1;
  }
}

int TerrainWorld::held_count() const {
  return int(std::count(impl_->held.begin(), impl_->held.end(), char(1)));
}

void TerrainWorld::release_reached(const Rect& changed) {
  Impl& m = *impl_;
  const float* h = grid_.heights();
  const double ground = grid_.spec().origin_m.y;
  btVector3 tool_lo(0, 0, 0), tool_hi(0, 0, 0);
  // The plate takes part once it has a pose (its contacts are on).
  const bool tool = m.tool_body && !(m.tool_body->getCollisionFlags() &
                                     btCollisionObject::CF_NO_CONTACT_RESPONSE);
  if (tool) m.tool_body->getAabb(tool_lo, tool_hi);
  if (tool_limited()) {
    // The soil holds it until the plate's push exceeds its break-out
    // force (judge_held_pushes): neither a touch nor a cut to its top
    // (still embedded to its full depth) releases it. A cut that took the
    // soil under its centre down to its bottom (the blade passed under it,
    // the plate below its box) does: nothing holds it, and it falls.
    for (std::size_t i = 0; i < m.bodies.size(); ++i) {
      if (!m.held[i]) continue;
      bool undermined = false;
      if (!m.breaking[i]) {
        btVector3 lo, hi;
        m.bodies[i]->getAabb(lo, hi);
        const Rect f = samples_under(lo, hi);
        const int col = (f.c0 + f.c1 - 1) / 2, row = (f.r0 + f.r1 - 1) / 2;
        undermined = !f.empty() && col >= changed.c0 && col < changed.c1 && row >= changed.r0 &&
                     row < changed.r1 &&
                     h[grid_.index(col, row)] <= float(double(lo.y()) - ground);
      }
      if (m.breaking[i] || undermined) release(int(i));
    }
    return;
  }
  for (std::size_t i = 0; i < m.bodies.size(); ++i) {
    if (!m.held[i]) continue;
    btVector3 lo, hi;
    m.bodies[i]->getAabb(lo, hi);
    bool reached = tool && tool_lo.x() <= hi.x() && tool_hi.x() >= lo.x() &&
                   tool_lo.y() <= hi.y() && tool_hi.y() >= lo.y() && tool_lo.z() <= hi.z() &&
                   tool_hi.z() >= lo.z();
    // Or the cut took the soil over its footprint down to its top.
    const Rect f = samples_under(lo, hi);
    const Rect c{std::max(f.c0, changed.c0), std::max(f.r0, changed.r0),
                 std::min(f.c1, changed.c1), std::min(f.r1, changed.r1)};
    const float top = float(double(hi.y()) - ground);
    for (int row = c.r0; row < c.r1 && !reached; ++row)
      for (int col = c.c0; col < c.c1 && !reached; ++col)
        reached = h[grid_.index(col, row)] <= top;
    if (reached) release(int(i));
  }
}

void TerrainWorld::release(int i) {
  Impl& m = *impl_;
  btRigidBody& b = *m.bodies[std::size_t(i)];
  btVector3 lo, hi;
  b.getAabb(lo, hi);
  // The soil it stood in: the samples under its box and one more all round
  // go down to its lowest point (lower() only lowers: a deeper cut stays),
  // so it rests on a level floor and no terrain triangle reaches into it.
  const Rect pit = grown_by_one(samples_under(lo, hi));
  const float floor_h = float(double(lo.y()) - grid_.spec().origin_m.y);
  for (int row = pit.r0; row < pit.r1; ++row)
    for (int col = pit.c0; col < pit.c1; ++col) lower_sample(grid_.index(col, row), floor_h);
  // Dynamic from now on: out of the world and back, so that the broadphase
  // gives it the dynamic body's collision groups (Bullet allocates its new
  // pairs here, once per release).
  m.world.removeRigidBody(&b);
  b.setMassProps(btScalar(specs_[std::size_t(i)].mass_kg), m.inertia[std::size_t(i)]);
  b.updateInertiaTensor();
  b.setLinearVelocity(btVector3(0, 0, 0));
  b.setAngularVelocity(btVector3(0, 0, 0));
  m.world.addRigidBody(&b);
  b.activate(true);
  m.held[std::size_t(i)] = 0;
  m.breaking[std::size_t(i)] = 0;
  ++pending_released_;
  pending_released_rect_.include(pit);
  terrain_changed(pit);
}

}  // namespace terracut::bullet
