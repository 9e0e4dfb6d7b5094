// Penetration (penetration.hpp): the bearing-capacity factors against
// Vesic's table, Prandtl's punch, the overburden of a frictionless soil, and
// the faces' friction by hand.
#include "terracut/core/penetration.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "terracut/core/material.hpp"

namespace terracut {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180.0;

// Relative tolerance for closed forms evaluated in double: a few dozen
// roundings of O(1) trigonometric terms.
constexpr double kRel = 1e-12;

void expect_rel(double actual, double expected, double rel, const char* what) {
  EXPECT_NEAR(actual, expected, rel * std::max(1.0, std::abs(expected))) << what;
}

TEST(Bearing, FactorsMatchVesicsTable) {
  // Vesic (1973), as tabulated in Das, Principles of Foundation Engineering
  // (N_c, N_q, N_gamma to two decimals).
  struct Row {
    double phi_deg, n_c, n_q, n_gamma;
  };
  for (const Row& r : {Row{0, 5.14, 1.00, 0.00}, Row{10, 8.35, 2.47, 1.22},
                       Row{20, 14.83, 6.40, 5.39}, Row{30, 30.14, 18.40, 22.40},
                       Row{40, 75.31, 64.20, 109.41}}) {
    const BearingFactors f = bearing_capacity_factors(r.phi_deg);
    EXPECT_NEAR(f.n_c, r.n_c, 0.006 * std::max(1.0, r.n_c)) << r.phi_deg;
    EXPECT_NEAR(f.n_q, r.n_q, 0.006 * std::max(1.0, r.n_q)) << r.phi_deg;
    EXPECT_NEAR(f.n_gamma, r.n_gamma, 0.006 * std::max(1.0, r.n_gamma)) << r.phi_deg;
  }
  // Frictionless: Prandtl's pi + 2, continuous as phi -> 0.
  EXPECT_EQ(bearing_capacity_factors(0.0).n_c, kPi + 2.0);
  EXPECT_NEAR(bearing_capacity_factors(1e-6).n_c, kPi + 2.0, 1e-4);
  EXPECT_NEAR(bearing_capacity_factors(0.0).n_q, 1.0, 1e-15);
  EXPECT_EQ(bearing_capacity_factors(0.0).n_gamma, 0.0);
}

SoilMaterial frictionless_soil(double cohesion_pa) {
  SoilMaterial s;
  s.internal_friction_deg = 0.0;
  s.soil_tool_friction_deg = 0.0;
  s.cohesion_pa = cohesion_pa;
  s.adhesion_pa = 0.0;
  return s;
}

constexpr double kEdge = 0.02;  // a 2 cm cutting edge (BladeSpec's default)

TEST(Penetration, ZeroDepthOrLengthGivesZero) {
  const SoilMaterial soil = soil_preset(SoilPreset::kClay);  // cohesion and adhesion
  for (double d : {0.0, -0.01}) {
    const PenetrationResult r = penetration_resistance(soil, kEdge, 0.5, d);
    EXPECT_EQ(r.down_n(), 0.0);
    EXPECT_EQ(r.up_n(), 0.0);
  }
  EXPECT_EQ(penetration_resistance(soil, kEdge, 0.0, 0.1).down_n(), 0.0);
  // Continuous at zero depth: the tip is mobilised over the first B.
  const PenetrationResult tiny = penetration_resistance(soil, kEdge, 0.5, 1e-9);
  EXPECT_LT(tiny.down_n(), 1e-3);
}

TEST(Penetration, FrictionlessCohesionlessSoilBearsItsOverburden) {
  // phi = delta = c = c_a = 0: N_q = 1, N_gamma = 0, no face friction: the
  // edge carries the weight of the soil column over its strip, gamma D B L.
  const SoilMaterial soil = frictionless_soil(0.0);
  for (double d : {0.02, 0.05, 0.2}) {
    const PenetrationResult r = penetration_resistance(soil, kEdge, 0.5, d);
    expect_rel(r.tip_n, soil.unit_weight_n_per_m3 * d * 0.02 * 0.5, kRel, "tip");
    EXPECT_EQ(r.side_n, 0.0);
  }
  // Shallower than B: mobilised in proportion to the depth.
  const PenetrationResult half = penetration_resistance(soil, kEdge, 0.5, 0.01);
  expect_rel(half.tip_n, soil.unit_weight_n_per_m3 * 0.01 * 0.02 * 0.5 * 0.5, kRel, "half");
}

TEST(Penetration, FrictionlessCohesiveSoilIsPrandtlsPunch) {
  // phi = 0, c > 0: q_ult = (pi + 2) c + gamma D (Prandtl 1921).
  const SoilMaterial soil = frictionless_soil(4000.0);
  const PenetrationResult r = penetration_resistance(soil, kEdge, 0.4, 0.1);
  expect_rel(r.bearing_pa, (kPi + 2.0) * 4000.0 + soil.unit_weight_n_per_m3 * 0.1, kRel, "q_ult");
  expect_rel(r.tip_n, r.bearing_pa * kEdge * 0.4, kRel, "tip");
}

TEST(Penetration, ScalesWithLengthAndDepth) {
  const SoilMaterial soil = soil_preset(SoilPreset::kDrySand);
  const PenetrationResult a = penetration_resistance(soil, kEdge, 0.2, 0.1);
  const PenetrationResult b = penetration_resistance(soil, kEdge, 0.6, 0.1);
  expect_rel(b.tip_n, 3.0 * a.tip_n, kRel, "tip linear in L");
  expect_rel(b.side_n, 3.0 * a.side_n, kRel, "side linear in L");
  // Dry sand has no adhesion: the faces' friction grows as D^2 (K0 gamma z tan delta).
  const PenetrationResult deep = penetration_resistance(soil, kEdge, 0.2, 0.2);
  expect_rel(deep.side_n, 4.0 * a.side_n, kRel, "side as D^2");
  const double k0 = 1.0 - std::sin(soil.internal_friction_deg * kDeg);
  expect_rel(a.side_n,
             2.0 * 0.2 * 0.5 * k0 * soil.unit_weight_n_per_m3 * 0.01 *
                 std::tan(soil.soil_tool_friction_deg * kDeg),
             kRel, "side by hand");
  // Below B the tip grows with depth through q = gamma D only: linear, with
  // the slope gamma N_q B L.
  const BearingFactors f = bearing_capacity_factors(soil.internal_friction_deg);
  const double slope = (deep.tip_n - a.tip_n) / 0.1;
  expect_rel(slope, soil.unit_weight_n_per_m3 * f.n_q * kEdge * 0.2, 1e-9, "slope");
}

TEST(Penetration, WorldForceOpposesVerticalMotionOnly) {
  const SoilMaterial soil = soil_preset(SoilPreset::kClay);
  const PenetrationResult r = penetration_resistance(soil, kEdge, 0.5, 0.08);
  ASSERT_GT(r.up_n(), 0.0);
  ASSERT_GT(r.down_n(), r.up_n());
  const double beta = 1000.0;
  // At rest, and sliding horizontally: nothing.
  EXPECT_EQ(length(penetration_world_force(r, {0, 0, 0}, beta)), 0.0);
  EXPECT_EQ(length(penetration_world_force(r, {0.7, 0, -0.3}, beta)), 0.0);
  // Pushed down fast: the whole resistance, up; pulled out: the faces, down.
  const Vec3 down = penetration_world_force(r, {0.0, -5.0, 0.0}, beta);
  EXPECT_EQ(down.x, 0.0);
  EXPECT_EQ(down.z, 0.0);
  expect_rel(down.y, r.down_n(), kRel, "down");
  expect_rel(penetration_world_force(r, {0.0, 5.0, 0.0}, beta).y, -r.up_n(), kRel, "up");
  // The same for any horizontal velocity, either sign (symmetry).
  expect_rel(penetration_world_force(r, {-3.0, -5.0, 2.0}, beta).y, r.down_n(), kRel, "mirror");
  // Slowly: a damper of slope beta.
  expect_rel(penetration_world_force(r, {0.0, -1e-4, 0.0}, beta).y, 0.1, kRel, "damper");
  EXPECT_TRUE(std::isnan(penetration_world_force(r, {0.0, std::nan(""), 0.0}, beta).y));
  // Uncapped: the physical resistance whole at any vertical speed.
  expect_rel(penetration_world_force(r, {0.0, -1e-9, 0.0}, kUncapped_n_s_per_m).y, r.down_n(), kRel, "physical");
}

}  // namespace
}  // namespace terracut
