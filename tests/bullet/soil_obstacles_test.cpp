// Rigid bodies as obstacles for soil that flows: the bodies' listener hands
// the soil phase the bodies' bounding boxes every step, and the pile a
// blade pushes banks against a body instead of passing through it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "terracut/bullet/bodies_listener.hpp"
#include "test_scene.hpp"

namespace terracut::bullet {
namespace {

struct PushIntoBody {
  static constexpr float kLayer = 0.1f;
  SimParams params = test::flow_on_1cm(0.4);
  std::unique_ptr<Simulation> sim;
  std::unique_ptr<BodiesListener> bodies;

  explicit PushIntoBody(bool with_body) {
    sim = std::make_unique<Simulation>(params, std::vector<float>(100 * 100, kLayer));
    if (with_body) {
      // A heavy static block resting on the sand, its face at z = 0.6 m.
      BodiesListenerOptions o;
      o.world = test::no_tool();
      bodies = std::make_unique<BodiesListener>(
          *sim, std::vector<BodySpec>{test::box("block", {0.4, 0.1, 0.2}, 0.0, {0.5, kLayer + 0.05, 0.7})}, o);
    }
    // A 0.4 m blade 5 cm deep pushes along +Z from 0.2 m to 0.55 m: a pile
    // of about 0.4 x 0.05 x 0.35 = 0.007 m^3, which would reach past 0.6 m.
    const int steps = int(std::lround(0.35 / 0.0006));
    for (int i = 0; i <= steps; ++i) sim->step({{0.5, kLayer - 0.05, 0.2 + 0.35 * i / steps}, Quat{}});
  }
  // The soil above the layer in the block's footprint (x 0.3-0.7, z 0.6-0.8), m^3.
  double soil_in_block() const {
    double v = 0.0;
    for (int r = 60; r < 80; ++r)
      for (int c = 30; c < 70; ++c) v += std::max(0.0, double(sim->grid().height(c, r)) - kLayer) * 1e-4;
    return v;
  }
};

TEST(SoilObstacles, APushedPileBanksAgainstABodyAndNeverEntersIt) {
  PushIntoBody free(false), blocked(true);
  EXPECT_GT(free.soil_in_block(), 1e-4);  // without the block the pile runs on
  // None of it, to the float rounding of the footprint's 800 heights of 0.1 m.
  EXPECT_LT(blocked.soil_in_block(), 800 * 1e-4 * 0.1 * 1.2e-7);
  // The pile stands against the block's face (at z = 0.6 m) a sample away,
  // above the layer: sample 59 (z = 0.595) is the ring kept free round the
  // block, sample 58 holds the pile.
  EXPECT_LT(blocked.sim->grid().height(50, 59), PushIntoBody::kLayer + 1e-6f);
  EXPECT_GT(blocked.sim->grid().height(50, 58), PushIntoBody::kLayer + 0.03f);
  // Nothing was lost, and the block did not move.
  EXPECT_NEAR(blocked.sim->grid().volume_m3(), 1.0 * 1.0 * PushIntoBody::kLayer, 1e-6);
  EXPECT_NEAR(blocked.bodies->world().body_state(0).position_m.z, 0.7, 1e-6);  // Bullet's floats
}

}  // namespace
}  // namespace terracut::bullet
