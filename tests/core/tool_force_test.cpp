// The physical force on the tool as a result of every step (tool_force.hpp,
// StepOutput::force): a blade cutting a flat layer meets the cutting force
// of its width and depth against its motion, whatever its speed; nothing at
// rest or at a stroke's first step; the motion is the poses' change; a
// plunge meets the bearing; a pile ahead adds its surcharge; a bucket's load
// weighs on it and resists its acceleration.
#include "terracut/core/tool_force.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "terracut/core/simulation.hpp"
#include "terracut/core/soil_ahead.hpp"

namespace terracut {
namespace {

constexpr double kLayer = 0.3;  // metres of soil on the rigid floor

// A flat layer on 1 cm cells, 1 m x 1 m, a 0.4 m blade of the given rake.
SimParams flat_params(SoilModel model, double rake_deg = 90.0) {
  SimParams p;
  p.grid = grid_of_cells(100, 100, 0.01);
  p.blade.length_m = 0.4;
  p.blade.rake_angle_deg = rake_deg;
  p.soil.model = model;
  return p;
}

Simulation flat(SoilModel model, double rake_deg = 90.0) {
  return Simulation(flat_params(model, rake_deg), std::vector<float>(100 * 100, float(kLayer)));
}

BladePose at(double x, double y, double z) { return {{x, y, z}, Quat{}}; }

// The edge along X moving along +Z at `speed` through a layer, `depth` deep:
// steady, the step's force is the cutting force of the whole 0.4 m at that
// depth, against the motion, the vertical plate lifted (V < 0).
TEST(ToolForce, ASteadyCutMeetsTheCuttingForceOfItsWidthAndDepth) {
  for (double speed : {0.05, 0.5, 2.0}) {
    Simulation sim = flat(SoilModel::kVanish);
    const double depth = 0.06, y = kLayer - depth;
    for (int i = 0; i <= 200; ++i) sim.step(at(0.5, y, 0.2 + speed * i / sim.params().rate_hz));
    const ToolForce& f = sim.last().force;
    EarthmovingParams ep;
    ep.soil = sim.params().soil.material;
    const EarthmovingResult expected = earthmoving_force(ep, 0.4, depth);
    // The depth is read off the float32 layer.
    EXPECT_NEAR(f.cut_depth_m, depth, 1e-6) << speed;
    EXPECT_NEAR(f.engaged_width_m, 0.4, 1e-9) << speed;
    EXPECT_NEAR(f.total_n.z, -expected.horizontal_n, 1e-4 * expected.horizontal_n) << speed;
    EXPECT_NEAR(f.total_n.y, -expected.vertical_n, 1e-4 * expected.horizontal_n) << speed;
    EXPECT_GT(f.total_n.y, 0.0);  // a vertical rough plate is lifted
    EXPECT_EQ(f.total_n.x, 0.0);
    // With the soil vanishing there is no pile: no surcharge part.
    EXPECT_EQ(length(f.surcharge_n), 0.0);
    EXPECT_NEAR(sim.last().motion.velocity_m_per_s.z, speed, 1e-9 * speed);
  }
}

// The motion is the poses' change over the step; a stroke's first step, and
// the first after lift(), has none, and a tool at rest meets no force, but
// keeps the resistance it would meet along its last heading.
TEST(ToolForce, NoForceAtRestOrAtAStrokesFirstStep) {
  Simulation sim = flat(SoilModel::kVanish);
  const double y = kLayer - 0.05;
  const StepOutput& first = sim.step(at(0.5, y, 0.2));
  EXPECT_EQ(length(first.motion.velocity_m_per_s), 0.0);
  EXPECT_EQ(length(first.force.total_n), 0.0);
  for (int i = 1; i <= 50; ++i) sim.step(at(0.5, y, 0.2 + 0.001 * i));
  ASSERT_GT(length(sim.last().force.total_n), 100.0);
  // Held still: nothing, though the soil ahead still resists along the heading.
  const StepOutput& still = sim.step(at(0.5, y, 0.25));
  EXPECT_EQ(length(still.force.total_n), 0.0);
  EXPECT_GT(still.force.earthmoving.horizontal_n, 100.0);
  EXPECT_NEAR(still.motion.heading.z, 1.0, 1e-12);
  // A float rounding's worth of motion is rest too.
  EXPECT_EQ(length(sim.step(at(0.5, y, 0.25 + 1e-15)).force.total_n), 0.0);
  // Lifted: the next step starts a stroke.
  sim.lift();
  const StepOutput& after = sim.step(at(0.5, y, 0.3));
  EXPECT_EQ(length(after.force.total_n), 0.0);
  EXPECT_EQ(length(after.motion.heading), 0.0);
}

// A blade sliding along its own edge cuts nothing; at 45 degrees it cuts
// L / sqrt(2) of width.
TEST(ToolForce, TheWidthIsAcrossTheMotion) {
  for (double angle_deg : {0.0, 45.0, 90.0}) {
    Simulation sim = flat(SoilModel::kVanish);
    const double a = angle_deg * std::numbers::pi / 180.0, y = kLayer - 0.04;
    for (int i = 0; i <= 100; ++i) {
      const double s = 0.5e-3 * i;
      sim.step(at(0.5 + s * std::sin(a), y, 0.3 + s * std::cos(a)));
    }
    const ToolForce& f = sim.last().force;
    EXPECT_NEAR(f.engaged_width_m, 0.4 * std::cos(a), 0.02 * 0.4) << angle_deg;
    if (angle_deg == 90.0) {
      EXPECT_NEAR(std::hypot(f.total_n.x, f.total_n.z), 0.0, 1e-9);
    }
  }
}

// Pushed straight down: the bearing under the edge and the faces' friction,
// whole at any speed (no low-speed cap), up; pulled out, the faces only.
TEST(ToolForce, APlungeMeetsTheBearingAndAPullTheFacesFriction) {
  Simulation sim = flat(SoilModel::kVanish);
  for (int i = 0; i <= 60; ++i) sim.step(at(0.5, kLayer + 0.01 - 0.001 * i, 0.5));  // 5 cm in
  const ToolForce& down = sim.last().force;
  const PenetrationResult expected =
      penetration_resistance(sim.params().soil.material, sim.params().blade.edge_thickness_m, 0.4,
                             down.embedment_depth_m);
  EXPECT_NEAR(down.embedment_depth_m, 0.05, 0.011);  // read beside the edge: a cell's rounding
  EXPECT_NEAR(down.penetration_n.y, expected.down_n(), 1e-9 * expected.down_n());
  EXPECT_EQ(down.total_n.z, 0.0);
  sim.step(at(0.5, kLayer - 0.05 + 1e-4, 0.5));  // up, slowly
  const ToolForce& up = sim.last().force;
  EXPECT_NEAR(up.penetration_n.y, -up.penetration.up_n(), 1e-9);
  EXPECT_LT(up.penetration_n.y, 0.0);
}

// With soil that flows, the blade pushes a pile: its weight on the failure
// wedge is a surcharge, the surcharge part is what it adds, and the total is
// the sum of the parts.
TEST(ToolForce, APileAheadAddsItsSurcharge) {
  Simulation sim = flat(SoilModel::kFlow);
  const double y = kLayer - 0.04;
  for (int i = 0; i <= 500; ++i) sim.step(at(0.5, y, 0.1 + 0.001 * i));
  const ToolForce& f = sim.last().force;
  EXPECT_GT(f.pile_m, 0.01);
  EXPECT_NEAR(f.surcharge_pa, sim.params().soil.material.unit_weight_n_per_m3 * f.pile_m, 1e-9);
  EXPECT_LT(f.surcharge_n.z, 0.0);  // against the motion, like the cut
  EarthmovingParams ep;
  ep.soil = sim.params().soil.material;
  const EarthmovingResult bare = earthmoving_force(ep, f.engaged_width_m, f.cut_depth_m);
  EXPECT_NEAR(-f.cutting_n.z - bare.horizontal_n, 0.0, 0.5 * bare.horizontal_n);
  EXPECT_NEAR(-(f.cutting_n.z + f.surcharge_n.z), f.earthmoving.horizontal_n, 1e-9 * f.earthmoving.horizontal_n);
  const Vec3 sum = f.cutting_n + f.surcharge_n + f.penetration_n + f.twist_n + f.load_n + f.bodies_n;
  EXPECT_NEAR(length(sum - f.total_n), 0.0, 1e-9 * length(f.total_n));
}

// A bucket's load weighs unit weight x volume, down, and resists the
// tool's acceleration with its mass (weight / g), from the poses' second
// difference.
TEST(ToolForce, ABucketsLoadWeighsAndResistsAcceleration) {
  SimParams p = flat_params(SoilModel::kFlow);
  p.blade.bucket.depth_m = 0.3;
  p.blade.bucket.height_m = 0.15;
  Simulation sim(p, std::vector<float>(100 * 100, float(kLayer)));
  // Heel up 7 degrees, the lip plunging 3 cm while it drags along -Z.
  const Quat heel_up = quat_from_euler_deg({-7.0, 0.0, 0.0});
  for (int i = 0; i <= 400; ++i)
    sim.step({{0.5, kLayer + 0.005 - 0.035 * std::min(1.0, i / 300.0), 0.8 - 0.001 * i}, heel_up});
  ASSERT_GT(sim.last().soil.bucket_load_m3, 1e-4);
  // Lifted out, then accelerated upward at a constant rate: a = 2 m/s^2.
  for (int i = 0; i <= 200; ++i) sim.step({{0.5, kLayer + 0.2, 0.4}, heel_up});
  const double load_m3 = sim.last().soil.bucket_load_m3;
  const double weight = p.soil.material.unit_weight_n_per_m3 * load_m3;
  const double mass = weight / kStandardGravity_m_per_s2;
  EXPECT_NEAR(sim.last().force.load_n.y, -weight, 1e-9 * weight);
  EXPECT_NEAR(sim.last().force.load_mass_kg, mass, 1e-12 * mass);
  const double a = 2.0, dt = 1.0 / p.rate_hz;
  double y0 = kLayer + 0.2;
  for (int i = 1; i <= 10; ++i) sim.step({{0.5, y0 + 0.5 * a * (i * dt) * (i * dt), 0.4}, heel_up});
  EXPECT_NEAR(sim.last().motion.acceleration_m_per_s2.y, a, 1e-6);
  EXPECT_NEAR(sim.last().force.load_n.y, -weight - mass * a, 1e-6 * weight);
}

// The rake and the material are checked together: a planar wedge must exist.
TEST(ToolForce, TheBladesRakeIsCheckedWithTheMaterial) {
  SimParams p = flat_params(SoilModel::kVanish, 150.0);
  p.soil.material.internal_friction_deg = 25.0;
  p.soil.material.soil_tool_friction_deg = 10.0;
  EXPECT_NE(validate(p).find("no planar failure wedge"), std::string::npos) << validate(p);
  p.blade.rake_angle_deg = 0.0;
  EXPECT_EQ(validate(p).rfind("blade.rake_angle_deg", 0), 0u) << validate(p);
  p = flat_params(SoilModel::kVanish);
  p.blade.edge_thickness_m = 0.0;
  EXPECT_EQ(validate(p).rfind("blade.edge_thickness_m", 0), 0u) << validate(p);
}

}  // namespace
}  // namespace terracut
