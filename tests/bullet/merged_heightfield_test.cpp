// The terrain's collision triangles with coplanar squares merged
// (src/bullet/merged_heightfield.cpp, TerrainWorldParams::merge_tolerance_m):
// the same surface as Bullet's two triangles per square, far fewer triangles
// where the soil is planar, Bullet's own triangles where it is not, and
// bodies that rest, land and stay put on it as on Bullet's triangles.
#include <gtest/gtest.h>

#include <btBulletDynamicsCommon.h>
#include <BulletCollision/CollisionDispatch/btConvexConcaveCollisionAlgorithm.h>
#include <BulletCollision/CollisionShapes/btHeightfieldTerrainShape.h>
#include <BulletCollision/CollisionShapes/btTriangleShape.h>
#include <BulletCollision/NarrowPhaseCollision/btGjkEpaPenetrationDepthSolver.h>
#include <BulletCollision/NarrowPhaseCollision/btGjkPairDetector.h>
#include <BulletCollision/NarrowPhaseCollision/btPointCollector.h>
#include <BulletCollision/NarrowPhaseCollision/btVoronoiSimplexSolver.h>

#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <random>
#include <vector>

#include "rescue_runner.hpp"
#include "terracut/bullet/terrain_world.hpp"
#include "test_scene.hpp"

namespace terracut::bullet {
namespace {

using test::box;
using test::no_tool;
using test::spec;

using Triangle = std::array<btVector3, 3>;

// Collects what a concave shape reports, in the shape's local frame.
struct Collect final : btTriangleCallback {
  std::vector<Triangle> triangles;
  void processTriangle(btVector3* t, int, int) override { triangles.push_back({t[0], t[1], t[2]}); }
};

// The triangles the terrain shape reports for a box given in world metres.
std::vector<Triangle> triangles_in(const TerrainWorld& world, btVector3 lo, btVector3 hi) {
  const btVector3 origin =
      const_cast<TerrainWorld&>(world).terrain_body().getWorldTransform().getOrigin();
  Collect c;
  world.terrain_shape().processAllTriangles(&c, lo - origin, hi - origin);
  return c.triangles;
}

// The height over (x, z) of the triangle whose ground projection contains it
// (local frame), or nothing.
std::optional<double> height_at(const std::vector<Triangle>& ts, double x, double z) {
  for (const Triangle& t : ts) {
    const double ax = t[0].x(), az = t[0].z();
    const double e1x = t[1].x() - ax, e1z = t[1].z() - az;
    const double e2x = t[2].x() - ax, e2z = t[2].z() - az;
    const double det = e1x * e2z - e2x * e1z;
    if (std::abs(det) < 1e-12) continue;
    const double u = ((x - ax) * e2z - e2x * (z - az)) / det;
    const double v = (e1x * (z - az) - (x - ax) * e1z) / det;
    const double eps = 1e-6;
    if (u < -eps || v < -eps || u + v > 1 + eps) continue;
    return t[0].y() + u * (t[1].y() - t[0].y()) + v * (t[2].y() - t[0].y());
  }
  return std::nullopt;
}

// Total ground area of the triangles' projections, m^2.
double projected_area(const std::vector<Triangle>& ts) {
  double a = 0.0;
  for (const Triangle& t : ts) {
    const btVector3 e1 = t[1] - t[0], e2 = t[2] - t[0];
    a += 0.5 * std::abs(double(e1.x()) * e2.z() - double(e2.x()) * e1.z());
  }
  return a;
}

TerrainWorldParams merging(double tolerance_m) {
  TerrainWorldParams p = no_tool();
  p.merge_tolerance_m = tolerance_m;
  return p;
}

// 48 x 36 samples over 1.2 x 0.9 m (non-square cells) with a level part, a
// tilted plane, a trench with vertical-ish walls and a rough random part.
std::vector<float> mixed_heights(const GridSpec& g) {
  std::mt19937 rng(2024);
  std::uniform_real_distribution<float> rough(0.20f, 0.26f);
  std::vector<float> h(std::size_t(g.sample_count()));
  for (int r = 0; r < g.rows; ++r) {
    for (int c = 0; c < g.cols; ++c) {
      float v = 0.3f;                                               // level soil
      if (c >= 12 && c < 24) v = 0.1f + 0.01f * float(c - 12) + 0.004f * float(r);  // a plane
      if (c >= 24 && c < 30 && r >= 5 && r < 30) v = 0.12f;         // a trench
      if (c >= 36) v = rough(rng);                                   // rough
      h[std::size_t(r) * std::size_t(g.cols) + std::size_t(c)] = v;
    }
  }
  return h;
}

TEST(MergedHeightfield, SameSurfaceAsBulletsTrianglesWithFewerTriangles) {
  const GridSpec g = spec(48, 36, 1.2, 0.9, {-0.2, 0.1, 0.4}, 0.4);
  HeightGrid merged_grid(g, mixed_heights(g));
  HeightGrid plain_grid(g, mixed_heights(g));
  const TerrainWorldParams defaults = merging(TerrainWorldParams{}.merge_tolerance_m);
  TerrainWorld merged(merged_grid, 1000.0, BladeSpec{}, {}, defaults);
  TerrainWorld plain(plain_grid, 1000.0, BladeSpec{}, {}, merging(0.0));
  const btVector3 centre = merged.terrain_body().getWorldTransform().getOrigin();

  std::mt19937 rng(7);
  std::uniform_real_distribution<double> ux(g.origin_m.x, g.origin_m.x + g.size_x_m);
  std::uniform_real_distribution<double> uz(g.origin_m.z, g.origin_m.z + g.size_z_m);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  // Heights are floats of magnitude 0.4 (plus the shape's re-centring); the
  // merged surface is within the tolerance of every sample.
  const double tol = defaults.merge_tolerance_m + 16.0 * std::numeric_limits<float>::epsilon();
  int fewer = 0;
  for (int q = 0; q < 60; ++q) {
    // A query box anywhere, 0.05 .. 0.5 m wide, spanning every height.
    double x0 = ux(rng), z0 = uz(rng);
    const double x1 = x0 + 0.05 + 0.45 * unit(rng), z1 = z0 + 0.05 + 0.45 * unit(rng);
    if (q == 0) x0 = g.origin_m.x - 1.0, z0 = g.origin_m.z - 1.0;  // one covers everything
    const btVector3 lo(btScalar(x0), btScalar(g.origin_m.y - 1.0), btScalar(z0));
    const btVector3 hi(btScalar(q == 0 ? x0 + 5.0 : x1), btScalar(g.origin_m.y + 2.0),
                       btScalar(q == 0 ? z0 + 5.0 : z1));
    const std::vector<Triangle> m = triangles_in(merged, lo, hi);
    const std::vector<Triangle> p = triangles_in(plain, lo, hi);
    ASSERT_FALSE(p.empty());
    // The same squares, covered once each.
    EXPECT_NEAR(projected_area(m), projected_area(p), 1e-5 * projected_area(p)) << "query " << q;
    EXPECT_LE(m.size(), p.size());
    fewer += m.size() < p.size() ? 1 : 0;
    // The same surface at random points of the covered squares.
    for (int k = 0; k < 40; ++k) {
      const Triangle& t = p[std::size_t(unit(rng) * double(p.size())) % p.size()];
      const double a = unit(rng), b = unit(rng) * (1.0 - a);
      const btVector3 pt = t[0] + (t[1] - t[0]) * btScalar(a) + (t[2] - t[0]) * btScalar(b);
      const std::optional<double> hp = height_at(p, pt.x(), pt.z());
      const std::optional<double> hm = height_at(m, pt.x(), pt.z());
      ASSERT_TRUE(hp && hm) << "query " << q << " at " << pt.x() + centre.x() << ", "
                            << pt.z() + centre.z();
      EXPECT_NEAR(*hm, *hp, tol) << "query " << q;
    }
  }
  EXPECT_GT(fewer, 30);  // most boxes reach a planar part
}

TEST(MergedHeightfield, RoughSoilIsBulletsOwnTriangles) {
  // No two neighbouring squares are coplanar: every square is reported as
  // Bullet reports it (same vertices, same order).
  const GridSpec g = spec(20, 20, 0.4, 0.4);
  std::mt19937 rng(99);
  std::uniform_real_distribution<float> rough(0.2f, 0.3f);
  std::vector<float> h(400);
  for (float& v : h) v = rough(rng);
  HeightGrid a(g, h), b(g, h);
  TerrainWorld merged(a, 1000.0, BladeSpec{}, {}, merging(1e-5));
  TerrainWorld plain(b, 1000.0, BladeSpec{}, {}, merging(0.0));
  const btVector3 lo(0.05f, -1.0f, 0.07f), hi(0.31f, 1.0f, 0.22f);
  const std::vector<Triangle> m = triangles_in(merged, lo, hi);
  const std::vector<Triangle> p = triangles_in(plain, lo, hi);
  ASSERT_EQ(m.size(), p.size());
  for (std::size_t i = 0; i < m.size(); ++i)
    for (int k = 0; k < 3; ++k) EXPECT_EQ(m[i][std::size_t(k)], p[i][std::size_t(k)]) << i;
}

TEST(MergedHeightfield, LevelSoilUnderABoxIsAFewRectangles) {
  // The rescue scenario's cells (2 cm) and its slab (0.3 m square): Bullet's
  // triangles are two per square under the box's bounding box; merged, the
  // range is cut into at most 3 x 3 rectangles of two triangles.
  const GridSpec g = spec(100, 100, 2.0, 2.0);
  HeightGrid grid(g, std::vector<float>(10000, 0.3f));
  TerrainWorld world(grid, 1000.0, BladeSpec{}, {box("slab", {0.3, 0.15, 0.3}, 32.4, {0.5, 0.375, 0.6})},
                     no_tool());
  btVector3 lo, hi;
  world.body(0).getAabb(lo, hi);
  const std::vector<Triangle> m = triangles_in(world, lo, hi);
  EXPECT_LE(m.size(), 18u);
  EXPECT_GE(m.size(), 2u);
  HeightGrid plain_grid(g, std::vector<float>(10000, 0.3f));
  TerrainWorld plain(plain_grid, 1000.0, BladeSpec{}, {}, merging(0.0));
  EXPECT_GE(triangles_in(plain, lo, hi).size(), std::size_t(2 * 15 * 15));
}

// The angle between a body's local +Y and the world's +Y, degrees.
double tilt_deg(const Quat& q) {
  const Vec3 up = rotate(q, {0.0, 1.0, 0.0});
  return std::acos(std::clamp(up.y, -1.0, 1.0)) * 180.0 / 3.14159265358979;
}

TEST(MergedHeightfield, ABodyNextToACutIsWokenAndStaysAtRest) {
  // A 0.2 m cube asleep on level soil; a trench 0.1 m deep is cut 2 cm from
  // its side, inside its wake region: the cube wakes, keeps its place and
  // its level, and falls asleep again.
  const double h0 = 0.3, half = 0.1;
  const GridSpec g = spec(50, 50, 1.0, 1.0);
  HeightGrid grid(g, std::vector<float>(2500, float(h0)));
  TerrainWorld world(grid, 1000.0, BladeSpec{}, {box("cube", {0.2, 0.2, 0.2}, 8.0, {0.5, h0 + half, 0.5})},
                     no_tool());
  for (int i = 0; i < 2500; ++i) world.advance();
  ASSERT_FALSE(world.body_state(0).active);
  const BodyState before = world.body_state(0);
  const double tol = world.params().convex_margin_m;
  EXPECT_NEAR(before.position_m.y, h0 + half, tol);

  // Samples whose centres are at x in [0.63, 0.79]: the cube ends at 0.6.
  const Rect cut{31, 10, 40, 40};
  for (int r = cut.r0; r < cut.r1; ++r)
    for (int c = cut.c0; c < cut.c1; ++c) grid.lower(grid.index(c, r), float(h0 - 0.1));
  world.terrain_changed(cut);
  EXPECT_TRUE(world.body_state(0).active);
  bool slept = false;
  for (int i = 0; i < 3000; ++i) {
    world.advance();
    slept = slept || !world.body_state(0).active;
  }
  const BodyState after = world.body_state(0);
  EXPECT_NEAR(after.position_m.x, before.position_m.x, tol);
  EXPECT_NEAR(after.position_m.y, before.position_m.y, tol);
  EXPECT_NEAR(after.position_m.z, before.position_m.z, tol);
  EXPECT_LT(tilt_deg(after.orientation), 1.0);
  EXPECT_TRUE(slept);
}

TEST(MergedHeightfield, ABoxOnASlopeRestsWhereBulletsTrianglesHoldIt) {
  // Soil tilted 10 degrees about Z (rising along +X); a cube placed on it,
  // turned to the slope. Friction 0.6 x 0.8 = 0.48 > tan 10 deg = 0.18, so it
  // stays: merged and unmerged, it ends where it was put (to the margin),
  // on the slope.
  const GridSpec g = spec(60, 60, 1.2, 1.2);
  const double slope = std::tan(10.0 * 3.14159265358979 / 180.0);
  std::vector<float> h(3600);
  for (int r = 0; r < 60; ++r)
    for (int c = 0; c < 60; ++c) h[std::size_t(r) * 60 + std::size_t(c)] = float(0.1 + slope * (g.origin_m.x + (c + 0.5) * g.cell_x_m()));
  const double x = 0.6, z = 0.6, half = 0.1;
  const double angle = 10.0 * 3.14159265358979 / 180.0;
  // The cube's centre: on the surface's normal through (x, z), half an edge out.
  const Vec3 centre{x - half * std::sin(angle), 0.1 + slope * x + half * std::cos(angle), z};
  BodySpec cube = box("cube", {0.2, 0.2, 0.2}, 8.0, centre);
  cube.rotation_deg = {0.0, 0.0, 10.0};
  for (double tolerance : {1e-5, 0.0}) {
    HeightGrid grid(g, h);
    TerrainWorld world(grid, 1000.0, BladeSpec{}, {cube}, merging(tolerance));
    for (int i = 0; i < 1500; ++i) world.advance();
    const BodyState s = world.body_state(0);
    const double tol = world.params().convex_margin_m;
    EXPECT_NEAR(s.position_m.x, centre.x, tol) << "tolerance " << tolerance;
    EXPECT_NEAR(s.position_m.y, centre.y, tol) << "tolerance " << tolerance;
    EXPECT_NEAR(s.position_m.z, centre.z, tol) << "tolerance " << tolerance;
    EXPECT_NEAR(tilt_deg(s.orientation), 10.0, 1.0) << "tolerance " << tolerance;
  }
}

TEST(MergedHeightfield, ToleranceIsValidated) {
  TerrainWorldParams p;
  p.merge_tolerance_m = -1e-6;
  EXPECT_NE(validate(p).find("merge_tolerance_m"), std::string::npos);
  p.merge_tolerance_m = 0.01;
  EXPECT_NE(validate(p).find("merge_tolerance_m"), std::string::npos);
  p.merge_tolerance_m = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(validate(p).find("merge_tolerance_m"), std::string::npos);
  p.merge_tolerance_m = 0.0;
  EXPECT_EQ(validate(p), "");
}

// The triangles that reach Bullet's convex-versus-terrain callback for a
// body (as btConvexConcaveCollisionAlgorithm queries them), without running
// the narrow phase on them.
struct ReachedTriangles final : btConvexTriangleCallback {
  std::vector<Triangle> triangles;
  ReachedTriangles(btDispatcher* d, const btCollisionObjectWrapper* convex,
                   const btCollisionObjectWrapper* terrain)
      : btConvexTriangleCallback(d, convex, terrain, false) {}
  void processTriangle(btVector3* t, int, int) override { triangles.push_back({t[0], t[1], t[2]}); }
};

std::vector<Triangle> reached_by(TerrainWorld& world, int body, btScalar& threshold) {
  btCollisionObject& b = world.body(body);
  btCollisionObject& t = world.terrain_body();
  const btCollisionObjectWrapper bw(nullptr, b.getCollisionShape(), &b, b.getWorldTransform(), -1, -1);
  const btCollisionObjectWrapper tw(nullptr, t.getCollisionShape(), &t, t.getWorldTransform(), -1, -1);
  ReachedTriangles reached(world.dynamics_world().getDispatcher(), &bw, &tw);
  btManifoldResult result(&bw, &tw);
  const btScalar margin = world.terrain_shape().getMargin();
  reached.setTimeStepAndCounters(margin, world.dynamics_world().getDispatchInfo(), &bw, &tw, &result);
  reached.m_manifoldPtr->setBodies(&b, &t);
  threshold = reached.m_manifoldPtr->getContactBreakingThreshold();
  world.terrain_shape().processAllTriangles(&reached, reached.getAabbMin(), reached.getAabbMax());
  reached.clearWrapperData();
  return reached.triangles;
}

// GJK's distance between a body and a terrain triangle (the shape's local
// frame), margins taken off, as Bullet's convex-convex narrow phase finds it.
double gjk_distance(TerrainWorld& world, int body, const Triangle& tri) {
  btCollisionObject& b = world.body(body);
  const btTransform& terrain = world.terrain_body().getWorldTransform();
  btTriangleShape shape(tri[0], tri[1], tri[2]);
  shape.setMargin(world.terrain_shape().getMargin());
  btVoronoiSimplexSolver simplex;
  btGjkEpaPenetrationDepthSolver epa;
  btGjkPairDetector gjk(static_cast<const btConvexShape*>(b.getCollisionShape()), &shape, &simplex, &epa);
  btGjkPairDetector::ClosestPointInput input;
  input.m_transformA = b.getWorldTransform();
  input.m_transformB = terrain;
  btPointCollector out;
  gjk.getClosestPoints(input, out, nullptr);
  return out.m_hasResult ? double(out.m_distance) : 1e30;
}

TEST(MergedHeightfield, FarTrianglesAreCulledOnlyWhereNoContactCanComeFromThem) {
  // A box tipped over onto rough soil and the trench's wall (the mixed
  // terrain): the triangles that reach Bullet's narrow phase with the cull
  // are among those without it, far fewer, and every one left out is more
  // than the contact breaking threshold from the box by GJK itself. Merged
  // and with Bullet's own triangles.
  const GridSpec g = spec(48, 36, 1.2, 0.9, {-0.2, 0.1, 0.4}, 0.4);
  for (const double tolerance : {1e-5, 0.0}) {
    for (const Vec3 at : {Vec3{0.9, 0.38, 0.8}, Vec3{0.55, 0.33, 0.7}, Vec3{0.25, 0.39, 0.6}}) {
      BodySpec b = box("tipped", {0.3, 0.12, 0.2}, 10.0, at);
      b.rotation_deg = {25.0, 40.0, 70.0};
      TerrainWorldParams on = merging(tolerance), off = merging(tolerance);
      off.cull_far_triangles = false;
      HeightGrid grid_on(g, mixed_heights(g)), grid_off(g, mixed_heights(g));
      TerrainWorld culled(grid_on, 1000.0, BladeSpec{}, {b}, on);
      TerrainWorld all(grid_off, 1000.0, BladeSpec{}, {b}, off);
      btScalar threshold = 0;
      const std::vector<Triangle> kept = reached_by(culled, 0, threshold);
      const std::vector<Triangle> every = reached_by(all, 0, threshold);
      ASSERT_FALSE(every.empty());
      EXPECT_LT(kept.size(), every.size()) << "tolerance " << tolerance;
      std::size_t k = 0;  // the kept ones come in the same order
      int dropped = 0;
      for (const Triangle& t : every) {
        if (k < kept.size() && kept[k] == t) {
          ++k;
          continue;
        }
        ++dropped;
        EXPECT_GT(gjk_distance(all, 0, t), double(threshold)) << "tolerance " << tolerance;
      }
      EXPECT_EQ(k, kept.size());
      EXPECT_GT(dropped, 0);
    }
  }
}

// Whether two runs' body states and tool forces agree bit for bit at every step.
void expect_same_runs(const ::terracut::test::BodiesRun& a, const ::terracut::test::BodiesRun& b) {
  ASSERT_EQ(a.states.size(), b.states.size());
  std::size_t differ = 0;
  for (std::size_t i = 0; i < a.states.size(); ++i) {
    const BodyState& x = a.states[i];
    const BodyState& y = b.states[i];
    const bool same = x.position_m.x == y.position_m.x && x.position_m.y == y.position_m.y &&
                      x.position_m.z == y.position_m.z && x.orientation.w == y.orientation.w &&
                      x.orientation.x == y.orientation.x && x.orientation.y == y.orientation.y &&
                      x.orientation.z == y.orientation.z && x.velocity_m_s.x == y.velocity_m_s.x &&
                      x.velocity_m_s.y == y.velocity_m_s.y && x.velocity_m_s.z == y.velocity_m_s.z &&
                      x.angular_velocity_rad_s.x == y.angular_velocity_rad_s.x &&
                      x.angular_velocity_rad_s.y == y.angular_velocity_rad_s.y &&
                      x.angular_velocity_rad_s.z == y.angular_velocity_rad_s.z && x.active == y.active;
    differ += same ? 0 : 1;
  }
  EXPECT_EQ(differ, 0u);
  ASSERT_EQ(a.tool_force_n.size(), b.tool_force_n.size());
  std::size_t forces_differ = 0;
  for (std::size_t i = 0; i < a.tool_force_n.size(); ++i) {
    const Vec3 x = a.tool_force_n[i], y = b.tool_force_n[i];
    forces_differ += x.x == y.x && x.y == y.y && x.z == y.z ? 0 : 1;
  }
  EXPECT_EQ(forces_differ, 0u);
  EXPECT_EQ(a.final_heights_m, b.final_heights_m);
}

TEST(MergedHeightfield, CullingFarTrianglesKeepsTheRescueBitForBit) {
  // The rescue as shipped (soil that flows: block_b lies tilted on the sand
  // in its trench, where the cull drops most triangles) and with the soil
  // vanishing: every body state of every step, the plate's force and the
  // final terrain are the same with and without the cull.
  for (const SoilModel model : {SoilModel::kFlow, SoilModel::kVanish}) {
    ::terracut::test::BodiesScenario input =
        ::terracut::test::load_with_bodies(std::filesystem::path(TERRACUT_SOURCE_DIR) / "scenarios/rescue.yaml");
    input.base.soil.model = model;
    TerrainWorldParams off;
    off.cull_far_triangles = false;
    const ::terracut::test::BodiesRun culled = ::terracut::test::run_with_bodies(input, {});
    const ::terracut::test::BodiesRun all = ::terracut::test::run_with_bodies(input, {}, off);
    SCOPED_TRACE(model == SoilModel::kFlow ? "flow" : "vanish");
    expect_same_runs(culled, all);
  }
}

}  // namespace
}  // namespace terracut::bullet
