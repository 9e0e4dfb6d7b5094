// The bodies' listener hears edits made between steps (Simulation::edit_heights)
// and refreshes the Bullet world there, so a body resting on an edited
// region drops onto the new surface.
#include "terracut/bullet/bodies_listener.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "test_scene.hpp"

namespace terracut::bullet {
namespace {

TEST(BodiesListener, EditUnderASleepingBodyDropsItOntoTheNewSurface) {
  const double h0 = 0.3, depth = 0.1, half = 0.1;
  SimParams sp;
  sp.grid = test::spec(50, 50, 1.0, 1.0);
  sp.blade.length_m = 0.2;
  Simulation sim(sp, std::vector<float>(2500, float(h0)));
  BodiesListener bodies(sim, {test::box("cube", {0.2, 0.2, 0.2}, 8.0, {0.3, h0 + half, 0.3})});
  // The blade is held far above the terrain: only the edit changes anything.
  const BladePose away{{0.8, 3.0, 0.8}, Quat{}};
  for (int i = 0; i < 2500; ++i) sim.step(away);
  const double tol = bodies.world().params().convex_margin_m;
  ASSERT_NEAR(bodies.world().body_state(0).position_m.y, h0 + half, tol);

  // Lower a 15 x 15 cell square (0.3 m) under the 0.2 m cube by `depth`.
  const Rect rect{8, 8, 23, 23};
  const std::vector<float> lowered(size_t(rect.area()), float(h0 - depth));
  EXPECT_EQ(sim.edit_heights(rect, lowered), rect);
  for (int i = 0; i < 1000; ++i) sim.step(away);
  EXPECT_NEAR(bodies.world().body_state(0).position_m.y, h0 - depth + half, tol);
}

}  // namespace
}  // namespace terracut::bullet
