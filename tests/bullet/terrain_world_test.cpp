// The Bullet world over the deformable terrain: placement, support after
// cuts, bounds, determinism, no per-step creation, and the tool plate.
#include <gtest/gtest.h>

#include <btBulletDynamicsCommon.h>
#include <BulletCollision/CollisionShapes/btHeightfieldTerrainShape.h>
#include <LinearMath/btPoolAllocator.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <set>

#include "terracut/bullet/terrain_world.hpp"
#include "terracut/core/error.hpp"
#include "test_scene.hpp"

namespace terracut::bullet {
namespace {

using test::box;
using test::no_tool;
using test::Scene;
using test::spec;

constexpr double kG = 9.81;

// Straight-down ray at (x, z): the world y of the first hit, or NaN.
double ray_down(TerrainWorld& world, double x, double z, double from_y, double to_y) {
  const btVector3 a{btScalar(x), btScalar(from_y), btScalar(z)};
  const btVector3 b{btScalar(x), btScalar(to_y), btScalar(z)};
  btCollisionWorld::ClosestRayResultCallback hit(a, b);
  world.dynamics_world().rayTest(a, b, hit);
  if (!hit.hasHit()) return std::numeric_limits<double>::quiet_NaN();
  return double(hit.m_hitPointWorld.y());
}

// terracut's own surface height at (x, z), metres above ground: the length of
// a vertical segment from the ground up through the surface that lies inside
// material (the `surface` representation's contact).
double surface_height(const HeightGrid& grid, double x, double z, double top) {
  const double y0 = grid.spec().origin_m.y;
  const Segment vertical{{x, y0, z}, {x, y0 + top, z}};
  return measure_contact(grid, Representation::kSurface, vertical).length_m;
}

// Float precision of world coordinates of magnitude `scale`, with room for
// the few roundings of Bullet's vertex and ray arithmetic.
double float_tol(double scale) { return 16.0 * std::numeric_limits<float>::epsilon() * scale; }

// --- Placement -----------------------------------------------------------

TEST(TerrainWorldPlacement, RayDownHitsTheSurfaceAtAndBetweenSamples) {
  // Non-square cells, an offset origin and random heights.
  const GridSpec g = spec(9, 7, 1.8, 1.4, {-0.5, 0.2, 0.3}, 0.5);
  std::mt19937 rng(12345);
  std::uniform_real_distribution<float> height(0.0f, 0.5f);
  std::vector<float> h(std::size_t(g.sample_count()));
  for (float& v : h) v = height(rng);
  HeightGrid grid(g, h);
  TerrainWorldParams p = no_tool();
  p.floor = false;
  TerrainWorld world(grid, 1000.0, BladeSpec{}, {}, p);
  const double top = world.bounds().max_height_m + 1.0;
  const double y0 = g.origin_m.y;
  const double tol = float_tol(2.0);

  // Exactly at every sample point: ground + height. Bullet's vertical ray
  // looks only in the square at floor(local x, z), so on the last column or
  // row (no square beyond it) it misses: there the ray is moved 1e-2 of a
  // cell inwards and compared with the surface.
  for (int r = 0; r < g.rows; ++r) {
    for (int c = 0; c < g.cols; ++c) {
      const bool far_edge = c == g.cols - 1 || r == g.rows - 1;
      const double x = grid.sample_x(c) - (c == g.cols - 1 ? 1e-2 * g.cell_x_m() : 0.0);
      const double z = grid.sample_z(r) - (r == g.rows - 1 ? 1e-2 * g.cell_z_m() : 0.0);
      const double y = ray_down(world, x, z, y0 + top, y0 - 1.0);
      const double expected = far_edge ? surface_height(grid, x, z, top) : grid.height(c, r);
      ASSERT_NEAR(y, y0 + expected, tol) << "sample (" << c << ", " << r << ")";
    }
  }

  // Between samples: the same triangles as terracut's surface representation
  // (diagonal from (c+1, r) to (c, r+1)); the other diagonal would differ by
  // up to half the height range here.
  std::uniform_real_distribution<double> ux(grid.sample_x(0), grid.sample_x(g.cols - 1));
  std::uniform_real_distribution<double> uz(grid.sample_z(0), grid.sample_z(g.rows - 1));
  // Bullet's ray-triangle test accepts hits up to about 1e-4 of a cell
  // outside a triangle (its edge tolerance), where the neighbour's plane is
  // extended; points that close to an edge or the diagonal are skipped.
  int checked = 0;
  for (int k = 0; k < 500; ++k) {
    const double x = ux(rng), z = uz(rng);
    const double u = grid.cell_u(x) - 0.5, v = grid.cell_v(z) - 0.5;
    const double a = u - std::floor(u), b = v - std::floor(v);
    if (std::min({a, 1.0 - a, b, 1.0 - b, std::abs(a + b - 1.0)}) < 1e-3) continue;
    ++checked;
    const double y = ray_down(world, x, z, y0 + top, y0 - 1.0);
    ASSERT_NEAR(y - y0, surface_height(grid, x, z, top), tol) << "at (" << x << ", " << z << ")";
  }
  EXPECT_GT(checked, 490);

  // Rays see edits at once (no accelerator to rebuild).
  const Rect edit{2, 1, 6, 5};
  std::vector<float> values(std::size_t(edit.area()));
  for (float& v : values) v = height(rng);
  grid.set_heights(edit, values.data());
  world.terrain_changed(edit);
  for (int r = edit.r0; r < edit.r1; ++r)  // edit is inside the last row and column
    for (int c = edit.c0; c < edit.c1; ++c)
      ASSERT_NEAR(ray_down(world, grid.sample_x(c), grid.sample_z(r), y0 + top, y0 - 1.0),
                  y0 + grid.height(c, r), tol);
}

TEST(TerrainWorldPlacement, ShapeReadsTheGridInPlace) {
  const GridSpec g = spec(4, 3, 1.0, 1.0);
  HeightGrid grid(g, std::vector<float>(12, 0.2f));
  TerrainWorld world(grid, 1000.0, BladeSpec{}, {}, no_tool());
  EXPECT_EQ(static_cast<const void*>(world.terrain_shape().getHeightfieldRawData()),
            static_cast<const void*>(grid.heights()));
  EXPECT_EQ(world.terrain_shape().getUpAxis(), 1);
}

TEST(TerrainWorldPlacement, RefusesBadSettings) {
  const GridSpec g = spec(4, 4, 1.0, 1.0);
  HeightGrid grid(g, std::vector<float>(16, 0.3f));
  TerrainWorldParams p;
  p.max_height_m = 0.2;  // below the terrain
  EXPECT_THROW(TerrainWorld(grid, 1000.0, BladeSpec{}, {}, p), InputError);
  p = {};
  p.tool.height_m = -1.0;
  EXPECT_THROW(TerrainWorld(grid, 1000.0, BladeSpec{}, {}, p), InputError);
  EXPECT_THROW(TerrainWorld(grid, 0.0, BladeSpec{}, {}), InputError);
  BodySpec bad = box("a", {0.1, -0.1, 0.1}, 1.0, {0.5, 0.5, 0.5});
  try {
    TerrainWorld(grid, 1000.0, BladeSpec{}, {bad});
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bodies[0] (a): size_m[1]"), std::string::npos) << e.what();
  }
  HeightGrid thin(spec(1, 4, 1.0, 1.0), std::vector<float>(4, 0.3f));
  EXPECT_THROW(TerrainWorld(thin, 1000.0, BladeSpec{}, {}), InputError);
}

// --- Support after a cut -------------------------------------------------

// Steps until the body has settled; returns its lowest centre height seen.
double advance_tracking_min_y(TerrainWorld& world, int body, int steps) {
  double lowest = world.body_state(body).position_m.y;
  for (int i = 0; i < steps; ++i) {
    world.advance();
    lowest = std::min(lowest, world.body_state(body).position_m.y);
  }
  return lowest;
}

// 1 m x 1 m of soil 0.3 m deep, 2 cm cells; two 0.2 m cubes resting on it,
// one at (0.3, 0.3), one far from it at (0.75, 0.75), settled until both
// sleep (Bullet's deactivation time is 2 s).
struct TwoRestingBoxes {
  static constexpr double h0 = 0.3, half = 0.1;
  HeightGrid grid{spec(50, 50, 1.0, 1.0), std::vector<float>(2500, float(h0))};
  TerrainWorld world{grid, 1000.0, BladeSpec{},
                     {box("over_cut", {0.2, 0.2, 0.2}, 8.0, {0.3, h0 + half, 0.3}),
                      box("far", {0.2, 0.2, 0.2}, 8.0, {0.75, h0 + half, 0.75})},
                     no_tool()};
  TwoRestingBoxes() {
    for (int i = 0; i < 2500; ++i) world.advance();
  }
};

TEST(TerrainWorldSupport, BodyFallsByTheCutDepthAndOthersStayPut) {
  TwoRestingBoxes scene;
  const double h0 = scene.h0, depth = 0.1, half = scene.half;
  HeightGrid& grid = scene.grid;
  TerrainWorld& world = scene.world;
  ASSERT_FALSE(world.body_state(0).active);
  ASSERT_FALSE(world.body_state(1).active);
  const BodyState before = world.body_state(0);
  const BodyState far_before = world.body_state(1);
  // Resting contact: the body sits on the surface to a small fraction of its
  // collision margin (Bullet resolves penetration over a few steps).
  const double margin = world.params().convex_margin_m;
  const double tol = margin;
  EXPECT_NEAR(before.position_m.y, h0 + half, tol);

  // Cut a square around the first body (2 cells wider than its footprint on
  // each side) down by `depth`, as the Simulation would.
  const Rect cut{8, 8, 23, 23};  // x, z in [0.16, 0.46]
  for (int r = cut.r0; r < cut.r1; ++r)
    for (int c = cut.c0; c < cut.c1; ++c) grid.lower(grid.index(c, r), float(h0 - depth));
  world.terrain_changed(cut);
  EXPECT_TRUE(world.body_state(0).active);

  // Free fall of `depth` takes sqrt(2 depth / g); allow three times that plus
  // 0.1 s to come to rest.
  const int bound = int(std::ceil((3.0 * std::sqrt(2.0 * depth / kG) + 0.1) * 1000.0));
  world.advance();
  EXPECT_EQ(world.last().bodies_woken, 1);
  const double lowest = advance_tracking_min_y(world, 0, bound - 1);
  const BodyState after = world.body_state(0);
  EXPECT_NEAR(after.position_m.y, before.position_m.y - depth, tol);
  EXPECT_LT(std::abs(after.velocity_m_s.y), 0.05);
  // It never went through the new surface.
  EXPECT_GT(lowest, h0 - depth + half - tol);
  // It dropped straight down: no sideways slide beyond the resting jitter.
  EXPECT_NEAR(after.position_m.x, before.position_m.x, tol);
  EXPECT_NEAR(after.position_m.z, before.position_m.z, tol);

  // The far body was never woken and did not move at all.
  const BodyState far_after = world.body_state(1);
  EXPECT_FALSE(far_after.active);
  EXPECT_EQ(far_after.position_m.x, far_before.position_m.x);
  EXPECT_EQ(far_after.position_m.y, far_before.position_m.y);
  EXPECT_EQ(far_after.position_m.z, far_before.position_m.z);
  EXPECT_EQ(far_after.orientation.w, far_before.orientation.w);
}

TEST(TerrainWorldSupport, AWideReportWakesOnlyTheBodyWhoseSoilChanged) {
  // One rectangle round the whole grid is reported (as a step whose soil
  // moved here and there reports it), first for an edit far from both
  // bodies, then for a cut under the first one only.
  TwoRestingBoxes scene;
  const double h0 = scene.h0, depth = 0.1;
  HeightGrid& grid = scene.grid;
  TerrainWorld& world = scene.world;
  ASSERT_FALSE(world.body_state(0).active);
  ASSERT_FALSE(world.body_state(1).active);
  const Rect whole{0, 0, grid.cols(), grid.rows()};
  // A dip 4 cells from every box's reach (x, z in [0.02, 0.06]): nobody's soil.
  for (int r = 1; r < 3; ++r)
    for (int c = 1; c < 3; ++c) grid.lower(grid.index(c, r), float(h0 - depth));
  world.terrain_changed(whole);
  world.advance();
  EXPECT_EQ(world.last().bodies_woken, 0);
  EXPECT_FALSE(world.body_state(0).active);
  EXPECT_FALSE(world.body_state(1).active);

  // The cut under the first body, reported the same way: it wakes and
  // falls by the cut's depth; the far one sleeps on, unmoved.
  const BodyState before = world.body_state(0);
  const BodyState far_before = world.body_state(1);
  for (int r = 8; r < 23; ++r)
    for (int c = 8; c < 23; ++c) grid.lower(grid.index(c, r), float(h0 - depth));
  world.terrain_changed(whole);
  world.advance();
  EXPECT_EQ(world.last().bodies_woken, 1);
  EXPECT_TRUE(world.body_state(0).active);
  const int bound = int(std::ceil((3.0 * std::sqrt(2.0 * depth / kG) + 0.1) * 1000.0));
  advance_tracking_min_y(world, 0, bound);
  const double tol = world.params().convex_margin_m;
  EXPECT_NEAR(world.body_state(0).position_m.y, before.position_m.y - depth, tol);
  EXPECT_FALSE(world.body_state(1).active);
  EXPECT_EQ(world.body_state(1).position_m.y, far_before.position_m.y);
  EXPECT_EQ(world.body_state(1).position_m.x, far_before.position_m.x);

  // One sample lowered under the far body's edge (its last column of samples
  // under the box, x = 0.83), reported as the whole grid: that is its soil.
  // (The first body, still awake, is re-tested too: awake bodies over the
  // reported rectangle always are.)
  grid.lower(grid.index(41, 37), float(h0 - depth));
  world.terrain_changed(whole);
  world.advance();
  EXPECT_EQ(world.last().bodies_woken, world.body_state(0).active ? 2 : 1);
  EXPECT_TRUE(world.body_state(1).active);
}

TEST(TerrainWorldSupport, WithoutTheWakeABodyWouldHoverOnTheOldSurface) {
  // The same cut, not reported to the world: the sleeping body stays in the
  // air. This is what terrain_changed() is for.
  const double h0 = 0.3, depth = 0.1, half = 0.1;
  const GridSpec g = spec(50, 50, 1.0, 1.0);
  HeightGrid grid(g, std::vector<float>(2500, float(h0)));
  TerrainWorld world(grid, 1000.0, BladeSpec{},
                     {box("over_cut", {0.2, 0.2, 0.2}, 8.0, {0.3, h0 + half, 0.3})}, no_tool());
  for (int i = 0; i < 2500; ++i) world.advance();
  const double y = world.body_state(0).position_m.y;
  for (int r = 8; r < 23; ++r)
    for (int c = 8; c < 23; ++c) grid.lower(grid.index(c, r), float(h0 - depth));
  for (int i = 0; i < 500; ++i) world.advance();
  EXPECT_EQ(world.body_state(0).position_m.y, y);
}

TEST(TerrainWorldSupport, SimulationCutUnderABodyDropsIt) {
  // The full loop: a level pass of the blade (0.1 m deep) under a resting
  // cube, Simulation::step then TerrainWorld::step. The plate (0.05 m) stays
  // under the soil top, so only the cut moves the cube.
  const double h0 = 0.3, depth = 0.1, half = 0.1;
  SimParams sp;
  sp.grid = spec(50, 50, 1.0, 1.0);
  sp.blade.length_m = 0.6;
  Simulation sim(sp, std::vector<float>(2500, float(h0)));
  TerrainWorldParams p;
  p.tool.height_m = 0.05;
  TerrainWorld world(sim, {box("cube", {0.2, 0.2, 0.2}, 8.0, {0.5, h0 + half, 0.5})}, p);
  const double y_before = world.body_state(0).position_m.y;

  // 1 s along +Z from z = 0.1 to 0.9 at y = h0 - depth, then 1 s at rest there.
  double lowest = y_before;
  for (int i = 0; i <= 2000; ++i) {
    const double s = std::min(1.0, i / 1000.0);
    const StepOutput& out = sim.step({{0.5, h0 - depth, 0.1 + 0.8 * s}, Quat{}});
    world.step(out);
    lowest = std::min(lowest, world.body_state(0).position_m.y);
  }
  const double tol = world.params().convex_margin_m;
  const BodyState after = world.body_state(0);
  EXPECT_NEAR(after.position_m.y, h0 - depth + half, tol);
  EXPECT_GT(lowest, h0 - depth + half - tol);
  EXPECT_GT(sim.removed_volume_m3(), 0.0);
  EXPECT_EQ(world.bounds().clamped_total, 0);
}

// --- Bounds --------------------------------------------------------------

TEST(TerrainWorldBounds, HeightsAboveTheBoundAreClampedAndReported) {
  const double h0 = 0.3, max_h = 0.5, half = 0.05;
  const GridSpec g = spec(40, 40, 1.0, 1.0);
  HeightGrid grid(g, std::vector<float>(1600, float(h0)));
  TerrainWorldParams p = no_tool();
  p.max_height_m = max_h;
  p.floor = false;  // only the heightfield holds the bodies
  // One cube above a patch raised past the bound, one above a patch cut to the floor.
  TerrainWorld world(grid, 1000.0, BladeSpec{},
                     {box("high", {0.1, 0.1, 0.1}, 1.0, {0.25, max_h + half + 0.02, 0.25}),
                      box("low", {0.1, 0.1, 0.1}, 1.0, {0.75, h0 + half, 0.75})},
                     p);
  EXPECT_EQ(world.bounds().max_height_m, max_h);
  EXPECT_EQ(world.bounds().min_height_m, 0.0);

  const Rect raised{5, 5, 15, 15};  // x, z in [0.125, 0.375]
  std::vector<float> pile(std::size_t(raised.area()), 0.7f);
  grid.set_heights(raised, pile.data());
  world.terrain_changed(raised);
  EXPECT_EQ(world.bounds().clamped_total, raised.area());
  EXPECT_FLOAT_EQ(float(world.bounds().highest_clamped_m), 0.7f);
  // The soil that deleted: each sample's height above the bound over its cell.
  EXPECT_NEAR(world.bounds().clamped_volume_m3, raised.area() * (double(0.7f) - max_h) * g.cell_area_m2(), 1e-12);
  for (int r = raised.r0; r < raised.r1; ++r)
    for (int c = raised.c0; c < raised.c1; ++c) ASSERT_EQ(grid.height(c, r), float(max_h));

  const Rect floor{25, 25, 35, 35};  // x, z in [0.625, 0.875]
  std::vector<float> zero(std::size_t(floor.area()), 0.0f);
  grid.set_heights(floor, zero.data());
  world.terrain_changed(floor);
  EXPECT_EQ(world.bounds().clamped_total, raised.area());

  world.advance();
  EXPECT_EQ(world.bounds().clamped_last_step, raised.area());
  for (int i = 0; i < 1000; ++i) world.advance();
  EXPECT_EQ(world.bounds().clamped_last_step, 0);
  // Both rest on the heightfield at its bounds.
  const double tol = world.params().convex_margin_m;
  EXPECT_NEAR(world.body_state(0).position_m.y, max_h + half, tol);
  EXPECT_NEAR(world.body_state(1).position_m.y, 0.0 + half, tol);
}

TEST(TerrainWorldBounds, AutomaticBoundLeavesRoomForPiles) {
  const GridSpec g = spec(8, 8, 1.0, 1.0, {}, 0.4);
  std::vector<float> h(64, 0.1f);
  h[10] = 0.7f;
  HeightGrid grid(g, h);
  TerrainWorld world(grid, 1000.0, BladeSpec{}, {}, no_tool());
  // max(2 x full scale, highest + full scale) = max(0.8, 1.1).
  EXPECT_NEAR(world.bounds().max_height_m, 1.1, 1e-6);
}

// --- Determinism and bounded resources ------------------------------------

TEST(TerrainWorldDeterminism, SameRunTwiceIsBitwiseIdentical) {
  auto run = [] {
    auto scene = std::make_unique<Scene>();
    std::vector<float> trace;
    for (int i = 0; i < 3000; ++i) {
      scene->step(i);
      for (int b = 0; b < scene->world.body_count(); ++b) {
        const btTransform& t = scene->world.body(b).getWorldTransform();
        for (int k = 0; k < 3; ++k) trace.push_back(t.getOrigin()[k]);
        const btQuaternion q = t.getRotation();
        for (int k = 0; k < 4; ++k) trace.push_back(q[k]);
      }
      const Vec3 f = scene->world.last().tool_force_n;
      trace.push_back(float(f.x));
      trace.push_back(float(f.y));
      trace.push_back(float(f.z));
    }
    return std::make_pair(trace, scene->sim.grid().state_hash());
  };
  const auto a = run();
  const auto b = run();
  ASSERT_EQ(a.first.size(), b.first.size());
  EXPECT_EQ(std::memcmp(a.first.data(), b.first.data(), a.first.size() * sizeof(float)), 0);
  EXPECT_EQ(a.second, b.second);
}

TEST(TerrainWorldResources, NothingIsCreatedOrDestroyedPerStep) {
  Scene scene;
  btDiscreteDynamicsWorld& w = scene.world.dynamics_world();
  auto* config = static_cast<btDefaultCollisionConfiguration*>(
      static_cast<btCollisionDispatcher*>(w.getDispatcher())->getCollisionConfiguration());
  auto distinct_shapes = [&] {
    std::set<const btCollisionShape*> shapes;
    for (int i = 0; i < w.getNumCollisionObjects(); ++i)
      shapes.insert(w.getCollisionObjectArray()[i]->getCollisionShape());
    return shapes;
  };
  const int objects = w.getNumCollisionObjects();
  const std::set<const btCollisionShape*> shapes = distinct_shapes();
  const btCollisionShape* terrain = scene.world.terrain_body().getCollisionShape();
  EXPECT_EQ(objects, 3 + scene.world.body_count());  // terrain, floor, tool + bodies
  EXPECT_EQ(int(shapes.size()), scene.world.shape_count());

  // At most one manifold per pair of objects that can touch.
  const int n = objects;
  const int max_pairs = n * (n - 1) / 2;
  int most_manifolds = 0, most_pool = 0;
  for (int i = 0; i < 3000; ++i) {
    scene.step(i);
    ASSERT_EQ(w.getNumCollisionObjects(), objects) << "step " << i;
    most_manifolds = std::max(most_manifolds, w.getDispatcher()->getNumManifolds());
    most_pool = std::max(most_pool, config->getPersistentManifoldPool()->getUsedCount());
  }
  EXPECT_EQ(distinct_shapes(), shapes);
  EXPECT_EQ(scene.world.terrain_body().getCollisionShape(), terrain);
  EXPECT_LE(most_manifolds, max_pairs);
  EXPECT_LE(most_pool, max_pairs);
  EXPECT_GT(most_manifolds, 0);
}

// --- The tool plate --------------------------------------------------------

TEST(TerrainWorldTool, PlatePushesALooseBoxAndFeelsItsFriction) {
  // A 2 kg cube on flat soil; the plate (edge along Z, 1 cm above the soil so
  // nothing is cut) moves along +X at 0.2 m/s into it.
  const double h0 = 0.3, half = 0.05, mass = 2.0, speed = 0.2;
  SimParams sp;
  sp.grid = spec(50, 50, 1.0, 1.0);
  sp.blade.length_m = 0.3;
  Simulation sim(sp, std::vector<float>(2500, float(h0)));
  BodySpec cube = box("cube", {0.1, 0.1, 0.1}, mass, {0.4, h0 + half, 0.5});
  TerrainWorldParams p;
  TerrainWorld world(sim, {cube}, p);
  const double x0 = world.body_state(0).position_m.x;

  const Quat edge_along_z = quat_from_euler_deg({0, 90, 0});
  Vec3 force_sum{};
  int pushing_steps = 0;
  const double start_x = 0.2;
  const int steps = 1500;
  for (int i = 0; i <= steps; ++i) {
    const double x = start_x + speed * i / 1000.0;
    const StepOutput& out = sim.step({{x, h0 + 0.01, 0.5}, edge_along_z});
    world.step(out);
    // Steady pushing: well after first contact (plate face meets the cube at
    // x = 0.34 at t = 0.7 s) and before the end.
    if (i >= 900 && world.last().tool_contact_points > 0) {
      force_sum = force_sum + world.last().tool_force_n;
      ++pushing_steps;
    }
  }
  EXPECT_EQ(sim.removed_volume_m3(), 0.0);
  ASSERT_GT(pushing_steps, 400);
  const Vec3 mean = force_sum * (1.0 / pushing_steps);
  // The box moved along +X with the plate (the plate's far face ends at
  // start_x + travel + thickness / 2; the box's near face sits there).
  const double travel = speed * steps / 1000.0;
  const double expected_x = start_x + travel + 0.5 * p.tool.thickness_m + half;
  EXPECT_NEAR(world.body_state(0).position_m.x, expected_x, 0.01) << "from " << x0;
  // Steady sliding: the plate's force on the box balances kinetic friction
  // mu m g with mu = cube friction x soil friction (Bullet multiplies them);
  // the force on the plate is opposite to the push.
  const double mu = cube.friction * p.terrain_friction;
  EXPECT_LT(mean.x, 0.0);
  EXPECT_NEAR(-mean.x, mu * mass * kG, 0.1 * mu * mass * kG);
  EXPECT_LT(std::abs(mean.z), 0.1 * mu * mass * kG);
}

TEST(TerrainWorldTool, NoForceWithoutContact) {
  SimParams sp;
  sp.grid = spec(20, 20, 1.0, 1.0);
  Simulation sim(sp, std::vector<float>(400, 0.3f));
  TerrainWorld world(sim, {box("far", {0.1, 0.1, 0.1}, 1.0, {0.9, 0.35, 0.9})});
  for (int i = 0; i < 100; ++i) world.step(sim.step({{0.3, 0.5, 0.3}, Quat{}}));
  EXPECT_EQ(world.last().tool_contact_points, 0);
  EXPECT_EQ(world.last().tool_force_n.x, 0.0);
  EXPECT_EQ(world.last().tool_force_n.y, 0.0);
  EXPECT_EQ(world.last().tool_force_n.z, 0.0);
}

}  // namespace
}  // namespace terracut::bullet
