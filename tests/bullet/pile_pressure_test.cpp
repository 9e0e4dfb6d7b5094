// Piles of soil that flows against rigid bodies (PilePressureSpec): the soil
// keeps a sample away from a body, presses on its side with Rankine's active
// earth pressure, a body moving into soil pushes it aside, and none of that
// lifts the body, tilts it, puts soil under it or loses soil.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>
#include <vector>

#include "terracut/bullet/bodies_listener.hpp"
#include "test_scene.hpp"

namespace terracut::bullet {
namespace {

constexpr float kLayer = 0.1f;  // metres of sand on the floor
constexpr double kCell = 0.01;  // 100 x 100 samples over 1 m x 1 m

// Angle between the body's local +Y axis and the world's +Y, degrees.
double tilt_deg(const Quat& q) {
  const Vec3 up = rotate(q, {0.0, 1.0, 0.0});
  return std::acos(std::clamp(up.y, -1.0, 1.0)) * 180.0 / std::numbers::pi;
}

double rankine_active(double phi_deg) {
  const double t = std::tan(std::numbers::pi / 4.0 - 0.5 * phi_deg * std::numbers::pi / 180.0);
  return t * t;
}

TEST(PilePressure, ABankAgainstAFaceGivesRankinesActiveThrust) {
  // A heavy box (0.2 m wide along X) resting on the layer, and a bank of
  // soil H above the layer on its -Z side up to the ring kept free round it.
  GridSpec g = test::spec(100, 100, 1.0, 1.0);
  std::vector<float> heights(100 * 100, kLayer);
  HeightGrid grid(g, heights);
  TerrainWorldParams p = test::no_tool();
  p.pile.enabled = true;
  const double width = 0.2, bank = 0.06;
  TerrainWorld world(grid, 1000.0, BladeSpec{},
                     {test::box("box", {width, 0.1, 0.2}, 100.0, {0.5, kLayer + 0.05, 0.5})}, p);
  const SoilObstacle o = world.soil_obstacle(0);
  ASSERT_FALSE(o.cells.empty());
  std::vector<float> raised(std::size_t(100 * o.cells.r0), float(kLayer + bank));
  world.terrain_changed(grid.set_heights({0, 0, 100, o.cells.r0}, raised.data()));
  StepOutput out;
  out.changed = {0, 0, 100, 100};
  for (int i = 0; i < 50; ++i) world.step(out);
  // P = 0.5 K gamma h^2 per metre of face; the face is resolved to a sample
  // on each side (its width to 2 cells), h to the body's resting depth in
  // the sand (its collision margin).
  const double per_m = 0.5 * rankine_active(p.pile.friction_angle_deg) * p.pile.unit_weight_n_per_m3;
  const double expected = per_m * bank * bank * width;
  const double tolerance = expected * (2.0 * kCell / width + 2.0 * p.convex_margin_m / bank);
  EXPECT_NEAR(world.last().pile_force_n, expected, tolerance);
  // Far below the friction that holds 100 kg: it stays put and upright.
  const BodyState s = world.body_state(0);
  EXPECT_NEAR(s.position_m.z, 0.5, 1e-3);
  EXPECT_LT(tilt_deg(s.orientation), 0.1);
}

// A heavy box yawed yaw_deg about Y on the layer, and a bank `bank` metres
// high on the samples outside its ring in front of the face whose outward
// normal is the box's local -Z (its 0.24 m face), after 50 steps.
struct BankAgainstAYawedFace {
  TerrainWorldParams params = test::no_tool();
  std::unique_ptr<HeightGrid> grid;
  std::unique_ptr<TerrainWorld> world;
  Vec3 normal{};  // the face's outward normal, world
  static constexpr double kWidth = 0.24, kDepth = 0.12, kBank = 0.06;

  BankAgainstAYawedFace(double yaw_deg, double unit_weight_n_per_m3) {
    grid = std::make_unique<HeightGrid>(test::spec(100, 100, 1.0, 1.0),
                                        std::vector<float>(100 * 100, kLayer));
    params.pile.enabled = true;
    params.pile.unit_weight_n_per_m3 = unit_weight_n_per_m3;
    BodySpec box = test::box("box", {kWidth, 0.1, kDepth}, 100.0, {0.5, kLayer + 0.05, 0.5});
    box.rotation_deg = {0.0, yaw_deg, 0.0};
    world = std::make_unique<TerrainWorld>(*grid, 1000.0, BladeSpec{}, std::vector<BodySpec>{box}, params);
    normal = rotate(initial_orientation(box), {0.0, 0.0, -1.0});
    // The bank: every sample outside the ring beyond the face's plane.
    const Rect ring = world->soil_obstacle(0).cells;
    std::vector<float> h(grid->heights(), grid->heights() + 100 * 100);
    for (int r = 0; r < 100; ++r)
      for (int c = 0; c < 100; ++c) {
        const bool in_ring = c >= ring.c0 && c < ring.c1 && r >= ring.r0 && r < ring.r1;
        const double ahead = (grid->sample_x(c) - 0.5) * normal.x + (grid->sample_z(r) - 0.5) * normal.z;
        if (!in_ring && ahead > 0.5 * kDepth) h[std::size_t(r * 100 + c)] = float(kLayer + kBank);
      }
    world->terrain_changed(grid->set_heights({0, 0, 100, 100}, h.data()));
    StepOutput out;
    out.changed = {0, 0, 100, 100};
    for (int i = 0; i < 50; ++i) world->step(out);
  }
  // Rankine's active thrust on the whole face, newtons.
  double rankine_n() const {
    return 0.5 * rankine_active(params.pile.friction_angle_deg) * params.pile.unit_weight_n_per_m3 *
           kBank * kBank * kWidth;
  }
};

TEST(PilePressure, AYawedBoxIsPushedAlongItsFacesNormalWithRankinesThrust) {
  for (const double yaw : {0.0, 30.0, 45.0}) {
    SCOPED_TRACE(yaw);
    const BankAgainstAYawedFace b(yaw, 16.25e3);
    const Vec3 thrust = b.world->last().pile_thrust_n;
    // Horizontal, against the face's outward normal: off it by at most the
    // push of a cell's width at each end of the face (its pieces there may
    // take their height from a sample either side of the bank's edge).
    EXPECT_EQ(thrust.y, 0.0);
    const double along = -(thrust.x * b.normal.x + thrust.z * b.normal.z);
    const double across = std::fabs(thrust.x * b.normal.z - thrust.z * b.normal.x);
    ASSERT_GT(along, 0.0);
    EXPECT_LT(std::atan2(across, along), std::atan(2.0 * kCell / b.kWidth));
    // Its magnitude: the whole face's, to those two cells of width and the
    // body's resting depth (its collision margin) in the bank's height.
    const double expected = b.rankine_n();
    const double margin = b.params.convex_margin_m;
    EXPECT_NEAR(std::hypot(thrust.x, thrust.z), expected,
                expected * (2.0 * kCell / b.kWidth + 2.0 * margin / b.kBank));
    // 100 kg: held by its friction, it stays put and keeps its yaw.
    const BodyState s = b.world->body_state(0);
    EXPECT_NEAR(s.position_m.z, 0.5, 1e-3);
    const Vec3 n = rotate(s.orientation, {0.0, 0.0, -1.0});
    EXPECT_NEAR(n.x, b.normal.x, 1e-3);
    EXPECT_NEAR(n.z, b.normal.z, 1e-3);
  }
}

TEST(PilePressure, TheThrustScalesWithTheUnitWeightExactly) {
  // P = 0.5 K gamma h^2: doubling or halving gamma (exact in binary) doubles
  // or halves every piece of it, and nothing else changes.
  const BankAgainstAYawedFace one(30.0, 16.25e3), two(30.0, 32.5e3), half(30.0, 8.125e3);
  const WorldStepInfo &a = one.world->last(), &b = two.world->last(), &c = half.world->last();
  ASSERT_GT(a.pile_force_n, 0.0);
  EXPECT_EQ(b.pile_force_n, 2.0 * a.pile_force_n);
  EXPECT_EQ(c.pile_force_n, 0.5 * a.pile_force_n);
  EXPECT_EQ(b.pile_thrust_n.x, 2.0 * a.pile_thrust_n.x);
  EXPECT_EQ(b.pile_thrust_n.z, 2.0 * a.pile_thrust_n.z);
}

TEST(PilePressure, TheUnitWeightIsCheckedOnTheSoilModelsRange) {
  // (0, 1e9], SoilParams::unit_weight_n_per_m3's (a scenario's soil sets it).
  TerrainWorldParams p = test::no_tool();
  p.pile.enabled = true;
  for (const double ok : {1e-9, 16.25e3, 1e9}) {
    p.pile.unit_weight_n_per_m3 = ok;
    EXPECT_EQ(validate(p), "") << ok;
  }
  for (const double bad : {0.0, -1.0, 1.000001e9, std::nan("")}) {
    p.pile.unit_weight_n_per_m3 = bad;
    EXPECT_NE(validate(p).find("pile.unit_weight_n_per_m3"), std::string::npos) << bad;
  }
}

// A 0.4 m blade 5 cm deep pushes a pile along +Z toward a light box resting
// on the sand (face at z = 0.6 m); the blade stops at z = 0.55, short of it.
struct PushTowardBox {
  SimParams params = test::flow_on_1cm(0.4);
  std::unique_ptr<Simulation> sim;
  std::unique_ptr<BodiesListener> bodies;
  double most_tilt_deg = 0.0, highest_m = 0.0, furthest_z_m = 0.0;
  double soil_under_m3 = 0.0;  // the most soil above the layer under the box's footprint

  explicit PushTowardBox(double mass_kg) {
    sim = std::make_unique<Simulation>(params, std::vector<float>(100 * 100, kLayer));
    BodiesListenerOptions o;
    o.world = test::no_tool();
    bodies = std::make_unique<BodiesListener>(
        *sim, std::vector<BodySpec>{test::box("box", {0.2, 0.1, 0.2}, mass_kg, {0.5, kLayer + 0.05, 0.7})},
        o);
    const int steps = int(std::lround(0.35 / 0.0006));
    for (int i = 0; i <= steps + 500; ++i) {
      sim->step({{0.5, kLayer - 0.05, 0.2 + 0.35 * std::min(i, steps) / steps}, Quat{}});
      const BodyState s = bodies->world().body_state(0);
      most_tilt_deg = std::max(most_tilt_deg, tilt_deg(s.orientation));
      highest_m = std::max(highest_m, s.position_m.y);
      furthest_z_m = std::max(furthest_z_m, s.position_m.z);
      if (i % 25 == 0) soil_under_m3 = std::max(soil_under_m3, soil_under_box());
    }
  }
  double soil_under_box() const {
    const BodyState s = bodies->world().body_state(0);
    double v = 0.0;
    for (int r = 0; r < 100; ++r)
      for (int c = 0; c < 100; ++c) {
        const double x = sim->grid().sample_x(c), z = sim->grid().sample_z(r);
        if (std::fabs(x - s.position_m.x) < 0.1 && std::fabs(z - s.position_m.z) < 0.1)
          v += std::max(0.0, double(sim->grid().height(c, r)) - kLayer) * kCell * kCell;
      }
    return v;
  }
};

TEST(PilePressure, APileSlidesALightBoxWithoutLiftingOrTiltingIt) {
  // 0.5 kg: friction 0.6 x 0.8 x 0.5 x 9.81 = 2.4 N, while a 0.1 m pile on
  // its 0.2 m face thrusts 0.5 x 0.28 x 16250 x 0.01 x 0.2 = 4.6 N.
  PushTowardBox light(0.5);
  EXPECT_GT(light.furthest_z_m, 0.7 + kCell);  // pushed on by more than a cell
  // Not lifted past its resting depth (the collision margin), and tilted
  // less than one cell over its 0.2 m depth would tilt it.
  const double margin = TerrainWorldParams{}.convex_margin_m;
  EXPECT_LT(light.highest_m, kLayer + 0.05 + margin);
  EXPECT_LT(light.most_tilt_deg, std::atan(kCell / 0.2) * 180.0 / std::numbers::pi);
  // No soil under it (float rounding of its 400 heights), none lost.
  EXPECT_LT(light.soil_under_m3, 400 * kCell * kCell * kLayer * 1.2e-7);
  EXPECT_NEAR(light.sim->grid().volume_m3(), 1.0 * 1.0 * kLayer, 1e-6);
}

TEST(PilePressure, AHeavyBoxHoldsThePileAndStaysPut) {
  // 50 kg: friction 235 N, far above the pile's few newtons.
  PushTowardBox heavy(50.0);
  EXPECT_LT(heavy.furthest_z_m, 0.7 + 1e-3);
  EXPECT_LT(heavy.highest_m, kLayer + 0.05 + TerrainWorldParams{}.convex_margin_m);
  EXPECT_LT(heavy.most_tilt_deg, 0.5);
  EXPECT_NEAR(heavy.sim->grid().volume_m3(), 1.0 * 1.0 * kLayer, 1e-6);
}

TEST(PilePressure, APileGrowingAgainstASleepingBoxWakesAndPushesIt) {
  // A 0.5 kg box rests on the layer until Bullet puts it to sleep (the
  // blade held above the sand); then the blade, 5 cm deep, drives a pile
  // into it (its plate off: only the soil touches the box).
  Simulation sim(test::flow_on_1cm(0.4), std::vector<float>(100 * 100, kLayer));
  BodiesListenerOptions o;
  o.world = test::no_tool();
  BodiesListener bodies(sim, {test::box("box", {0.2, 0.1, 0.2}, 0.5, {0.5, kLayer + 0.05, 0.7})}, o);
  int waited = 0;
  for (; waited < 5000 && bodies.world().body_state(0).active; ++waited)
    sim.step({{0.5, kLayer + 0.05, 0.2}, Quat{}});
  ASSERT_FALSE(bodies.world().body_state(0).active) << "not asleep after " << waited << " steps";
  const double rest_z = bodies.world().body_state(0).position_m.z;
  const int steps = int(std::lround(0.35 / 0.0006));
  bool woke = false;
  for (int i = 0; i <= steps + 500; ++i) {
    sim.step({{0.5, kLayer - 0.05, 0.2 + 0.35 * std::min(i, steps) / steps}, Quat{}});
    woke = woke || bodies.world().body_state(0).active;
  }
  EXPECT_TRUE(woke);
  // Pushed on along +Z by more than a cell, as when it was awake
  // (APileSlidesALightBoxWithoutLiftingOrTiltingIt).
  EXPECT_GT(bodies.world().body_state(0).position_m.z, rest_z + kCell);
  EXPECT_NEAR(sim.grid().volume_m3(), 1.0 * 1.0 * kLayer, 1e-6);
}

TEST(PilePressure, TheSameRunGivesTheSameBits) {
  PushTowardBox a(0.5), b(0.5);
  const HeightGrid &ga = a.sim->grid(), &gb = b.sim->grid();
  EXPECT_EQ(std::memcmp(ga.heights(), gb.heights(), sizeof(float) * std::size_t(ga.spec().sample_count())), 0);
  const BodyState sa = a.bodies->world().body_state(0), sb = b.bodies->world().body_state(0);
  EXPECT_EQ(std::memcmp(&sa.position_m, &sb.position_m, sizeof(Vec3)), 0);
  EXPECT_EQ(std::memcmp(&sa.orientation, &sb.orientation, sizeof(Quat)), 0);
}

TEST(PilePressure, ABoxPushedIntoABankPushesItAsideInsteadOfRidingUpIt) {
  // The blade 1 cm above the layer pushes a 2 kg box with its plate along +Z
  // at 0.3 m/s, from z = 0.3 m into a bank 3 cm high that starts at z =
  // 0.4 m (the box's front face is at 0.35 m) and runs past the push.
  const SimParams params = test::flow_on_1cm(0.3);
  constexpr float kBank = 0.03f;
  std::vector<float> heights(100 * 100, kLayer);
  for (int r = 40; r < 100; ++r)
    for (int c = 0; c < 100; ++c) heights[std::size_t(r * 100 + c)] = kLayer + kBank;
  Simulation sim(params, heights);
  const double before = sim.grid().volume_m3();
  BodiesListener bodies(sim, {test::box("box", {0.1, 0.1, 0.1}, 2.0, {0.5, kLayer + 0.05, 0.3})});
  double most_tilt = 0.0, highest = 0.0, shed = 0.0;
  const int steps = 1000;  // 0.3 m at 0.3 mm per step
  for (int i = 0; i <= steps + 300; ++i) {
    sim.step({{0.5, kLayer + 0.01, 0.23 + 0.3 * std::min(i, steps) / steps}, Quat{}});
    const BodyState s = bodies.world().body_state(0);
    most_tilt = std::max(most_tilt, tilt_deg(s.orientation));
    highest = std::max(highest, s.position_m.y);
    shed += bodies.world().last().shed_m3;
  }
  const BodyState end = bodies.world().body_state(0);
  EXPECT_GT(end.position_m.z, 0.3 + 0.2);  // pushed well into the bank
  EXPECT_GT(shed, 0.0);                    // and pushed the bank's soil aside
  // Not lifted onto the bank (its 3 cm) past its resting depth, nor tipped
  // more than one cell over its 0.1 m depth would tip it.
  const double margin = TerrainWorldParams{}.convex_margin_m;
  EXPECT_LT(highest, kLayer + 0.05 + margin);
  EXPECT_LT(most_tilt, std::atan(kCell / 0.1) * 180.0 / std::numbers::pi);
  // The plate's cut of the bank is kept too: nothing lost.
  EXPECT_NEAR(sim.grid().volume_m3(), before, 1e-6);
}

TEST(PilePressure, ABoxWhoseSupportIsCutAwayStillFalls) {
  // A level pass 5 cm deep under a 5 kg box (the tool plate off: the blade
  // passes under it); the cut soil goes round it and the box drops the
  // cut's depth.
  Simulation sim(test::flow_on_1cm(0.4), std::vector<float>(100 * 100, kLayer));
  BodiesListenerOptions o;
  o.world = test::no_tool();
  BodiesListener bodies(sim, {test::box("box", {0.2, 0.05, 0.2}, 5.0, {0.5, kLayer + 0.025, 0.6})}, o);
  const double depth = 0.05;
  const int steps = 1500;
  for (int i = 0; i <= steps + 500; ++i)
    sim.step({{0.5, kLayer - depth, 0.2 + 0.75 * std::min(i, steps) / steps}, Quat{}});
  const BodyState s = bodies.world().body_state(0);
  const double margin = TerrainWorldParams{}.convex_margin_m;
  EXPECT_NEAR(s.position_m.y, kLayer + 0.025 - depth, margin);
  EXPECT_LT(tilt_deg(s.orientation), 2.0);
  EXPECT_NEAR(sim.grid().volume_m3(), 1.0 * 1.0 * kLayer, 1e-6);  // the cut soil is kept
}

}  // namespace
}  // namespace terracut::bullet
