// The arm's force limit (ToolPlateSpec::force_limit_n): the tool plate as a
// force-limited servo against a block jammed on the rigid terrain, and a
// buried body's break-out force (break_out_resistance_n) against it.
#include <gtest/gtest.h>

#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "terracut/core/error.hpp"
#include "test_scene.hpp"

namespace terracut::bullet {
namespace {

using test::box;
using test::spec;

constexpr double kDt = 0.001;  // 1 kHz

BladePose edge_at(double y, double z) {
  BladePose p;
  p.position_m = {0.5, y, z};
  return p;
}

double plate_speed(TerrainWorld& w) { return double(w.tool_body().getLinearVelocity().length()); }

// 1 m x 1 m, 2 cm cells: bare floor (height 0) for z > 0.4 and a 0.3 m wall
// of rigid terrain for z < 0.4 (its face a ramp between the samples at
// z = 0.39 and 0.41). A 0.1 m, 2 kg block on the floor 1 cm from the
// ramp's foot; the plate's edge 2 cm over the floor pushes it along -Z at
// 0.5 m/s into the wall, runs on to z = 0.3 (through the wall) until
// t = 1 s, then goes back to z = 0.8.
struct Jam {
  HeightGrid grid;
  TerrainWorld world;
  static std::vector<float> heights() {
    std::vector<float> h(2500, 0.0f);
    for (int r = 0; r < 50; ++r)
      for (int c = 0; c < 50; ++c)
        if ((r + 0.5) * 0.02 < 0.4) h[std::size_t(r * 50 + c)] = 0.3f;
    return h;
  }
  static TerrainWorldParams params(double limit_n) {
    TerrainWorldParams p;
    p.tool.force_limit_n = limit_n;
    return p;
  }
  explicit Jam(double limit_n)
      : grid(spec(50, 50, 1.0, 1.0), heights()),
        world(grid, 1.0 / kDt, BladeSpec{0.4},
              {box("block", {0.1, 0.1, 0.1}, 2.0, {0.5, 0.05, 0.47})}, params(limit_n)) {}
  static double command_z(int step) {
    const double t = step * kDt;
    if (t <= 0.8) return 0.7 - 0.5 * t;
    if (t <= 1.0) return 0.3;
    return std::min(0.3 + 0.5 * (t - 1.0), 0.8);
  }
};

TEST(ArmLimit, ThePlateStallsAgainstAJammedBlockAtTheLimit) {
  const double limit = 1000.0, mass = ToolPlateSpec{}.mass_kg;
  Jam jam(limit);
  TerrainWorld& w = jam.world;
  ASSERT_TRUE(w.tool_limited());
  double worst_excess = -1e300, stall_sum = 0.0;
  int stall_steps = 0, stalled_flags = 0;
  for (int i = 0; i <= 2000; ++i) {
    // The plate's speed after the last step: what the drive starts from.
    const double v_prev = i == 0 ? 0.0 : plate_speed(w);
    w.set_tool_pose(edge_at(0.02, Jam::command_z(i)));
    w.advance();
    const double f = length(w.last().tool_force_n);
    // Contacts only stop the plate (no restitution, gravity off): the
    // bodies' force on it is at most what stops it within a step, its
    // speed after the drive's clamped impulse: limit + m v_prev / dt.
    // Bullet's floats: 1e-4 of that.
    const double bound = limit + mass * v_prev / kDt;
    worst_excess = std::max(worst_excess, f - bound * (1.0 + 1e-4));
    if (w.last().tool_stalled) ++stalled_flags;
    const double t = i * kDt;
    if (t >= 0.7 && t <= 1.0) {
      // Jammed: the plate stops short at the block's back face (the block
      // against the wall's foot, 0.41 .. 0.51, the plate 1 cm thick), 15 cm
      // or more from the command (at 0.35 .. 0.3).
      const double edge_z = w.tool_blade_pose().position_m.z;
      ASSERT_GT(edge_z, 0.5) << t;
      ASSERT_GT(edge_z - Jam::command_z(i), 0.15) << t;
      ASSERT_TRUE(w.last().tool_stalled) << t;
      stall_sum += f;
      ++stall_steps;
    }
  }
  EXPECT_LE(worst_excess, 0.0);
  // Stopped against it, the plate pushes with the whole limit each step.
  ASSERT_GT(stall_steps, 0);
  EXPECT_NEAR(stall_sum / stall_steps, limit, 0.05 * limit);
  EXPECT_GE(stalled_flags, stall_steps);
  // The command came back: the plate follows it again.
  const BladePose end = w.tool_blade_pose();
  EXPECT_NEAR(end.position_m.z, 0.8, 1e-3);
  EXPECT_NEAR(end.position_m.y, 0.02, 1e-3);
  EXPECT_FALSE(w.last().tool_stalled);
}

TEST(ArmLimit, WithoutALimitTheKinematicPlateCrushesTheJam) {
  // The same jam with today's kinematic plate: Bullet's impulses push the
  // block out of the wall whatever it costs, far above the limit above.
  Jam jam(0.0);
  TerrainWorld& w = jam.world;
  EXPECT_FALSE(w.tool_limited());
  double peak = 0.0;
  for (int i = 0; i <= 1000; ++i) {
    w.set_tool_pose(edge_at(0.02, Jam::command_z(i)));
    w.advance();
    peak = std::max(peak, length(w.last().tool_force_n));
    // It goes where the blade goes.
    ASSERT_NEAR(w.tool_blade_pose().position_m.z, Jam::command_z(i), 1e-5);
  }
  EXPECT_GT(peak, 10.0 * 1000.0);
}

// The arm held back (the soil alone at the limit: the plate stops where it
// is) while the command runs 10 cm on at 0.5 m/s and stops; then the soil
// lets go. The servo must brake for the pose it is driven to: with the
// limit's 200 m/s^2 it reaches it and stays, as an arm would, instead of
// arriving at 6 m/s and swinging 10 cm past it, back and forth for most of
// a second (the one-step velocity target, clamped, never brakes in time).
TEST(ArmLimit, ReleasedFromAStallThePlateBrakesOntoItsPose) {
  const double limit = 1000.0;
  Jam jam(limit);
  TerrainWorld& w = jam.world;
  w.set_tool_pose(edge_at(0.2, 0.8));  // over the block and the wall: it meets nothing
  w.advance();
  int i = 1;
  w.set_tool_load({0.0, 0.0, 2.0 * limit});
  for (; i <= 200; ++i) {
    w.set_tool_pose(edge_at(0.2, 0.8 - 0.5 * std::min(i * kDt, 0.2)));
    w.advance();
  }
  ASSERT_NEAR(w.tool_blade_pose().position_m.z, 0.8, 1e-6);  // held where it was
  w.set_tool_load({});
  double overshoot = 0.0;
  int settled_at = -1;
  for (; i <= 1200; ++i) {
    w.set_tool_pose(edge_at(0.2, 0.7));
    w.advance();
    const double z = w.tool_blade_pose().position_m.z;
    overshoot = std::max(overshoot, 0.7 - z);
    if (std::fabs(z - 0.7) > 1e-3) settled_at = -1;
    else if (settled_at < 0) settled_at = i;
  }
  // Braking from 200 m/s^2 the 10 cm take about 45 ms.
  EXPECT_LT(overshoot, 1e-3);
  ASSERT_GE(settled_at, 0);
  EXPECT_LT((settled_at - 200) * kDt, 0.1);
}

// The break-out force by hand, for sand of gamma = 16 kN/m^3, phi = 30 deg
// (K_p = tan^2 60 = 3 exactly), c = 0 and then 2 kPa: rock_buried.yaml's
// block (0.3 x 0.2 x 0.25 m, 40 kg), top 2 cm under the surface, pushed
// along Z (its 0.3 m face forward).
BreakOutSpec sand(double c) { return {16e3, c, 30.0}; }
BreakOutGeometry block_geometry() {
  BreakOutGeometry g;
  g.width_m = 0.3;
  g.top_depth_m = 0.02;
  g.bottom_depth_m = 0.22;
  g.footprint_m2 = 0.3 * 0.25;
  g.overburden_m = 0.02;
  g.weight_n = 40.0 * 9.81;
  return g;
}

TEST(ArmLimit, BreakOutForceByHand) {
  // Passive: 0.3 x 3 x 16000 x (0.22^2 - 0.02^2) / 2 = 345.6 N.
  // Base: (392.4 + 16000 x 0.02 x 0.075) x tan 30 = 416.4 x 0.577350 = 240.409 N.
  const double base = 416.4 / std::sqrt(3.0);
  EXPECT_NEAR(break_out_resistance_n(sand(0.0), block_geometry()), 345.6 + base, 1e-9);
  // Cohesion adds 2 c sqrt(K_p) (z_b - z_t) w = 2 x 2000 x sqrt 3 x 0.2 x 0.3
  // on the face and c A = 2000 x 0.075 = 150 N under the base.
  EXPECT_NEAR(break_out_resistance_n(sand(2000.0), block_geometry()),
              345.6 + base + 240.0 * std::sqrt(3.0) + 150.0, 1e-9);
  // A downward push of 100 N adds its friction; lifting needs W + gamma d A.
  BreakOutGeometry pressed = block_geometry();
  pressed.down_push_n = 100.0;
  EXPECT_NEAR(break_out_resistance_n(sand(0.0), pressed), 345.6 + 516.4 / std::sqrt(3.0), 1e-9);
  EXPECT_NEAR(lift_out_resistance_n(sand(0.0), block_geometry()), 416.4, 1e-9);
}

// The block buried in sand 0.3 m deep (its back face at z = 0.725), the
// plate's edge 4 cm deep (2 cm under the block's top) creeping along -Z at
// 1 cm/s from 5 mm short of it.
struct Buried {
  HeightGrid grid;
  TerrainWorld world;
  static constexpr double kSpeed = 0.01;
  static TerrainWorldParams params(double limit_n) {
    TerrainWorldParams p;
    p.tool.force_limit_n = limit_n;
    p.break_out = sand(0.0);
    return p;
  }
  static BodySpec rock() {
    BodySpec b = box("rock", {0.3, 0.2, 0.25}, 40.0, {0.5, 0.18, 0.6});
    b.buried = true;
    return b;
  }
  explicit Buried(double limit_n)
      : grid(spec(50, 50, 1.0, 1.0), std::vector<float>(2500, 0.3f)),
        world(grid, 1.0 / kDt, BladeSpec{0.4}, {rock()}, params(limit_n)) {}
  static BladePose command(int step) { return edge_at(0.26, 0.74 - kSpeed * step * kDt); }
  // One step as the simulation's listener makes it (no cut, no soil force):
  // held bodies are released in step(), before Bullet advances.
  void step(int i) {
    StepOutput out;
    out.pose = command(i);
    world.step(out);
  }
};

TEST(ArmLimit, TheWorldMeasuresTheBuriedBlocksGeometry) {
  Buried b(400.0);
  // Pushed along -Z: the face ahead is 0.3 m wide; the sand beside it and
  // over it at 0.3 m; Bullet's float box (1e-6 m).
  const BreakOutGeometry g = b.world.break_out_geometry(0, {0.0, 0.0, -1.0}, 0.0);
  const BreakOutGeometry h = block_geometry();
  EXPECT_NEAR(g.width_m, h.width_m, 1e-6);
  EXPECT_NEAR(g.top_depth_m, h.top_depth_m, 1e-6);
  EXPECT_NEAR(g.bottom_depth_m, h.bottom_depth_m, 1e-6);
  EXPECT_NEAR(g.footprint_m2, h.footprint_m2, 1e-6);
  EXPECT_NEAR(g.overburden_m, h.overburden_m, 1e-6);
  EXPECT_NEAR(g.weight_n, h.weight_n, 1e-9);
  // Along X the 0.25 m face goes ahead.
  EXPECT_NEAR(b.world.break_out_geometry(0, {1.0, 0.0, 0.0}, 0.0).width_m, 0.25, 1e-6);
}

TEST(ArmLimit, ABuriedBlockStaysHeldUnderItsBreakOutForce) {
  // 400 N < 586 N: the plate presses on it and stalls; it stays held. The
  // first touch at 1 cm/s adds m v / dt = 50 N: 450 N at most.
  const double limit = 400.0, mass = ToolPlateSpec{}.mass_kg;
  Buried b(limit);
  TerrainWorld& w = b.world;
  double peak_push = 0.0;
  for (int i = 0; i <= 2000; ++i) {
    b.step(i);
    peak_push = std::max(peak_push, w.last().held_push_n);
    ASSERT_EQ(w.held_count(), 1) << i;
  }
  EXPECT_GT(peak_push, 0.9 * limit);
  EXPECT_LE(peak_push, limit + mass * Buried::kSpeed / kDt + 1.0);
  // Stopped at its back face (z = 0.725; the plate's front face 1 cm ahead
  // of its edge), 1.5 cm behind the command at the end.
  EXPECT_NEAR(w.tool_blade_pose().position_m.z, 0.735, 0.002);
  EXPECT_TRUE(w.last().tool_stalled);
}

TEST(ArmLimit, ABuriedBlockBreaksOutAtItsBreakOutForce) {
  // 2000 N > 586 N. Stopped against the block, the plate's push grows each
  // step by m v / dt (the command runs v dt further ahead: 50 N), so it
  // breaks out the first step the push passes the resistance, by at most
  // that much.
  const double limit = 2000.0, mass = ToolPlateSpec{}.mass_kg;
  const double step_n = mass * Buried::kSpeed / kDt;
  const double hand = 345.6 + 416.4 / std::sqrt(3.0);
  Buried b(limit);
  TerrainWorld& w = b.world;
  double before = 0.0, at = 0.0, resistance = 0.0;
  int released_at = -1;
  for (int i = 0; i <= 2000 && released_at < 0; ++i) {
    const double last_push = w.last().held_push_n, last_resistance = w.last().held_resistance_n;
    b.step(i);
    if (w.held_count() == 0) {
      released_at = i;
      at = last_push;
      resistance = last_resistance;
    } else if (w.last().held_push_n > 0.0 && w.last().held_push_n <= w.last().held_resistance_n) {
      before = w.last().held_push_n;
    }
  }
  ASSERT_GE(released_at, 0) << "never broke out";
  EXPECT_EQ(w.last().bodies_released, 1);
  // The resistance is the formula's with the world's geometry (flat sand).
  EXPECT_NEAR(resistance, hand, 1e-3 * hand);
  EXPECT_GT(at, resistance);
  EXPECT_LE(at, resistance + step_n + 1.0);
  EXPECT_LE(before, resistance);
  // Released, it is dynamic and the plate pushes it on.
  EXPECT_FALSE(w.body_state(0).held);
}

TEST(ArmLimit, BadInputIsRefusedNamingTheField) {
  HeightGrid grid(spec(50, 50, 1.0, 1.0), std::vector<float>(2500, 0.3f));
  const auto message = [&](const TerrainWorldParams& p) {
    try {
      TerrainWorld w(grid, 1000.0, BladeSpec{0.4}, {}, p);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  TerrainWorldParams p;
  p.tool.force_limit_n = -1.0;
  EXPECT_NE(message(p).find("tool.force_limit_n"), std::string::npos) << message(p);
  p.tool.force_limit_n = std::nan("");
  EXPECT_NE(message(p).find("tool.force_limit_n"), std::string::npos) << message(p);
  p = {};
  p.tool.mass_kg = 0.0;
  EXPECT_NE(message(p).find("tool.mass_kg"), std::string::npos) << message(p);
  p = {};
  p.break_out.unit_weight_n_per_m3 = 0.0;
  EXPECT_NE(message(p).find("break_out.unit_weight_n_per_m3"), std::string::npos) << message(p);
  p = {};
  p.break_out.cohesion_pa = -1.0;
  EXPECT_NE(message(p).find("break_out.cohesion_pa"), std::string::npos) << message(p);
  p = {};
  p.break_out.friction_angle_deg = 90.0;
  EXPECT_NE(message(p).find("break_out.friction_angle_deg"), std::string::npos) << message(p);
  p = {};
  EXPECT_EQ(message(p), "accepted");
}

}  // namespace
}  // namespace terracut::bullet
