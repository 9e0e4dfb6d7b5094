// Buried bodies (BodySpec::buried; docs/bullet.md, "Buried bodies"): held
// still, static in Bullet and touching nothing, while the soil covers them;
// released when the blade reaches one (the tool plate's box meets its box,
// or the cut takes the soil over its footprint down to its top): it becomes
// dynamic, and the soil it stood in is lowered to its lowest point.
#include <algorithm>

#include "terrain_world_impl.hpp"

namespace terracut::bullet {

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
  Rect pit = samples_under(lo, hi);
  pit = {std::max(pit.c0 - 1, 0), std::max(pit.r0 - 1, 0), std::min(pit.c1 + 1, grid_.cols()),
         std::min(pit.r1 + 1, grid_.rows())};
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
  ++pending_released_;
  pending_released_rect_.include(pit);
  terrain_changed(pit);
}

}  // namespace terracut::bullet
