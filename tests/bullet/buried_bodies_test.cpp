// Buried bodies (BodySpec::buried): held still under the soil, invisible to
// a camera looking down, released when the blade reaches them (the plate's
// box meets theirs, or the cut takes the soil down to their top), then
// resting in the soil they stood in and pushed by the plate; and the tops
// of uncovered bodies as a camera sees them (raise_to_body_tops).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "terracut/bullet/bodies_listener.hpp"
#include "terracut/core/error.hpp"
#include "test_scene.hpp"

namespace terracut::bullet {
namespace {

using test::box;
using test::spec;

// 1 m x 1 m of sand 0.3 m deep, 2 cm cells; the 0.4 m blade along X.
SimParams sand_params() {
  SimParams sp;
  sp.grid = spec(50, 50, 1.0, 1.0);
  sp.blade.length_m = 0.4;
  return sp;
}

// A 0.2 x 0.1 x 0.2 m box, its top 2 cm under the sand: centre y = 0.23.
BodySpec buried_box() {
  BodySpec b = box("rock", {0.2, 0.1, 0.2}, 8.0, {0.5, 0.23, 0.5});
  b.buried = true;
  return b;
}

// The blade's edge along X at depth y, at z, level.
BladePose blade_at(double y, double z) {
  BladePose p;
  p.position_m = {0.5, y, z};
  return p;
}

// The samples of the grid whose centres lie a cell inside the X-Z square
// of half sides (hx, hz) around (x, z).
template <class F>
void for_inside(const HeightGrid& g, double x, double z, double hx, double hz, F&& f) {
  const double cell = g.spec().cell_x_m();
  for (int row = 0; row < g.rows(); ++row)
    for (int col = 0; col < g.cols(); ++col)
      if (std::fabs(g.sample_x(col) - x) < hx - cell && std::fabs(g.sample_z(row) - z) < hz - cell)
        f(col, row);
}

TEST(BuriedBodies, HeldStillAndUnseenUnderTheSoil) {
  Simulation sim(sand_params(), std::vector<float>(2500, 0.3f));
  BodiesListener bodies(sim, {buried_box()});
  const TerrainWorld& w = bodies.world();
  const BodyState start = w.body_state(0);
  EXPECT_TRUE(start.held);
  EXPECT_EQ(w.held_count(), 1);
  // Two seconds with the blade in the air: gravity does not pull it through
  // the heightfield (which is only a surface), nothing moves it.
  for (int i = 0; i < 2000; ++i) sim.step(blade_at(0.45, 0.1));
  const BodyState now = w.body_state(0);
  EXPECT_TRUE(now.held);
  EXPECT_EQ(now.position_m.x, start.position_m.x);
  EXPECT_EQ(now.position_m.y, start.position_m.y);
  EXPECT_EQ(now.position_m.z, start.position_m.z);
  // A camera over it sees the sand.
  const Rect all{0, 0, 50, 50};
  std::vector<float> seen(sim.grid().heights(), sim.grid().heights() + 2500);
  EXPECT_EQ(w.raise_to_body_tops(all, seen), 0);
  for (float h : seen) ASSERT_EQ(h, 0.3f);
}

TEST(BuriedBodies, AShallowCutOverItLeavesItHeld) {
  Simulation sim(sand_params(), std::vector<float>(2500, 0.3f));
  BodiesListener bodies(sim, {buried_box()});
  // 1 cm deep over the whole rock (its top is 2 cm down): the plate, 0.1 m
  // high above the edge, passes over its box.
  sim.step(blade_at(0.29, 0.2));
  for (int i = 1; i <= 600; ++i) sim.step(blade_at(0.29, 0.2 + 0.001 * i));
  EXPECT_TRUE(bodies.world().body_state(0).held);
  for_inside(sim.grid(), 0.5, 0.5, 0.1, 0.1,
             [&](int c, int r) { ASSERT_NEAR(sim.grid().height(c, r), 0.29, 1e-6); });
}

TEST(BuriedBodies, WithAForceLimitACutUnderItReleasesIt) {
  // With the arm's force limit only the plate's push beyond the break-out
  // force frees a buried body, and a cut to its top does not. But the blade
  // 5 cm over the floor (the plate, 0.1 m high, passes under the box's
  // bottom at 0.18) takes the soil under it away: nothing holds it then,
  // and it must fall into the trench, not hang in the air.
  Simulation sim(sand_params(), std::vector<float>(2500, 0.3f));
  BodiesListenerOptions o;
  o.world.tool.force_limit_n = 1e6;
  BodiesListener bodies(sim, {buried_box()}, o);
  const TerrainWorld& w = bodies.world();
  ASSERT_TRUE(w.tool_limited());
  sim.step(blade_at(0.05, 0.95));
  for (int i = 1; i <= 1800; ++i) sim.step(blade_at(0.05, 0.95 - 0.0005 * i));
  for (int i = 0; i < 500; ++i) sim.step(blade_at(0.05, 0.05));
  EXPECT_EQ(w.held_count(), 0);
  // It lies on the trench's floor (0.05), its centre 5 cm over it.
  EXPECT_LT(w.body_state(0).position_m.y, 0.12);
}

TEST(BuriedBodies, ReleasedWhenThePlateReachesItThenPushedWithoutFlyingOut) {
  // rock_buried.yaml's block: 0.3 x 0.2 x 0.25 m, 40 kg, its top 2 cm under
  // the sand (centre y = 0.18), its back face at z = 0.725.
  Simulation sim(sand_params(), std::vector<float>(2500, 0.3f));
  BodySpec rock = box("rock", {0.3, 0.2, 0.25}, 40.0, {0.5, 0.18, 0.6});
  rock.buried = true;
  BodiesListener bodies(sim, {rock});
  const TerrainWorld& w = bodies.world();
  // 4 cm deep (the edge 2 cm under the rock's top) along -Z at 0.5 m/s:
  // the plate (2 cm thick) reaches the rock's back face when the edge is
  // 1 cm short of it.
  const double speed = 0.5;
  int released_at = -1;
  Rect released{};
  double max_speed = 0.0, lowest = 1.0;
  sim.step(blade_at(0.26, 0.95));
  for (int i = 1; i <= 1200; ++i) {
    const StepOutput& out = sim.step(blade_at(0.26, 0.95 - speed * i / 1000.0));
    if (released_at < 0 && w.last().bodies_released == 1) {
      released_at = i;
      released = w.last().released_rect;
      // The soil it stood in went down with the step: in its changed rectangle.
      EXPECT_LE(out.changed.c0, released.c0);
      EXPECT_GE(out.changed.c1, released.c1);
      EXPECT_LE(out.changed.r0, released.r0);
      EXPECT_GE(out.changed.r1, released.r1);
      // Under it and a cell all round: its lowest point, 0.08.
      for (int r = released.r0; r < released.r1; ++r)
        for (int c = released.c0; c < released.c1; ++c)
          ASSERT_NEAR(sim.grid().height(c, r), 0.08, 1e-6) << c << " " << r;
      // Its box and one sample more all round: the first sample left
      // standing is a cell or more from its faces, so the terrain's
      // triangles rising from the pit clear it.
      const HeightGrid& g = sim.grid();
      const double cell = g.spec().cell_x_m(), eps = 1e-6;
      EXPECT_LE(g.sample_x(released.c0 - 1), 0.35 - cell + eps);
      EXPECT_GE(g.sample_x(released.c1), 0.65 + cell - eps);
      EXPECT_LE(g.sample_z(released.r0 - 1), 0.475 - cell + eps);
      EXPECT_GE(g.sample_z(released.r1), 0.725 + cell - eps);
    }
    if (released_at >= 0) {
      max_speed = std::max(max_speed, length(w.body_state(0).velocity_m_s));
      lowest = std::min(lowest, w.body_state(0).position_m.y);
    }
  }
  ASSERT_GE(released_at, 0) << "never released";
  // Released the step the plate's front face (1 cm ahead of the edge)
  // reached the rock's back face, within a step and the plate's margin.
  const double edge_z = 0.95 - speed * released_at / 1000.0;
  EXPECT_NEAR(edge_z - 0.01, 0.725, speed * 0.001 + 0.005) << released_at;
  EXPECT_FALSE(w.body_state(0).held);
  // Pushed at its top 2 cm against the sand ahead, it rides up out of its
  // pit onto the sand (centre 0.3 + 0.1) and is pushed along it: never
  // through the floor of its pit, never faster than a few times the blade
  // (the plate's first touch is an impact), and ahead of the blade at the end.
  const BodyState end = w.body_state(0);
  EXPECT_GE(lowest, 0.18 - 0.005);
  EXPECT_LT(max_speed, 6.0 * speed);
  EXPECT_NEAR(end.position_m.y, 0.4, 0.005);
  EXPECT_LT(end.position_m.z + 0.125, 0.95 - speed * 1.2);
  // Once uncovered a camera sees its top.
  std::vector<float> seen(sim.grid().heights(), sim.grid().heights() + 2500);
  EXPECT_GT(w.raise_to_body_tops({0, 0, 50, 50}, seen), 0);
}

TEST(BuriedBodies, TopsOfUncoveredBodiesAsACameraSeesThem) {
  // A box resting on the sand and a sphere half in it, both static.
  BodySpec ball;
  ball.name = "ball";
  ball.shape = BodyShape::kSphere;
  ball.radius_m = 0.1;
  ball.mass_kg = 0.0;  // static: it stays exactly where it is
  ball.position_m = {0.25, 0.3, 0.25};
  BodySpec block = box("block", {0.2, 0.1, 0.2}, 0.0, {0.7, 0.35, 0.7});
  HeightGrid grid(spec(50, 50, 1.0, 1.0), std::vector<float>(2500, 0.3f));
  TerrainWorld w(grid, 1000.0, BladeSpec{}, {ball, block}, test::no_tool());
  // A window over part of both.
  const Rect rect{5, 5, 40, 40};
  std::vector<float> seen(std::size_t(rect.area()), 0.3f);
  EXPECT_GT(w.raise_to_body_tops(rect, seen), 0);
  for (int r = rect.r0; r < rect.r1; ++r)
    for (int c = rect.c0; c < rect.c1; ++c) {
      const float h = seen[std::size_t((r - rect.r0) * 35 + (c - rect.c0))];
      const double x = grid.sample_x(c), z = grid.sample_z(r);
      const double d2 = (x - 0.25) * (x - 0.25) + (z - 0.25) * (z - 0.25);
      double expect = 0.3;
      if (d2 < 0.01) expect = 0.3 + std::sqrt(0.01 - d2);  // the sphere's cap
      if (std::fabs(x - 0.7) < 0.1 && std::fabs(z - 0.7) < 0.1) expect = 0.4;  // the block's top
      // Exact: the shapes' own surfaces, to float rounding.
      const double tol = 1e-5;
      ASSERT_NEAR(h, expect, tol) << "x " << x << " z " << z;
    }
}

TEST(BuriedBodies, ABuriedBodyMustBeCovered) {
  HeightGrid grid(spec(50, 50, 1.0, 1.0), std::vector<float>(2500, 0.3f));
  BodySpec b = buried_box();
  b.position_m.y = 0.26;  // its top at 0.31, above the sand
  try {
    TerrainWorld w(grid, 1000.0, BladeSpec{0.4}, {b});
    FAIL() << "accepted a buried body above the soil";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_EQ(m.rfind("bodies[0] (rock): buried: the body's top (y = 0.31 m) is not under the soil", 0),
              0u)
        << m;
  }
  b.position_m = {3.0, 0.2, 3.0};  // off the terrain
  EXPECT_THROW(TerrainWorld(grid, 1000.0, BladeSpec{0.4}, {b}), InputError);
}

}  // namespace
}  // namespace terracut::bullet
