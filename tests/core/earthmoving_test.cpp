// The cutting force (earthmoving.hpp) against values derived independently:
// McKyes' factors written out again here (and by hand at angles where they
// are exact), Rankine's passive pressure for a smooth vertical wall,
// hydrostatics for frictionless soil, the free-body equilibrium of the
// wedge; the side crescents against McKyes & Ali's vertical-blade factors,
// a numerical integration of their elements, and the 2-D limit of a wide blade.
#include "terracut/core/earthmoving.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <tuple>
#include <vector>

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

// ---------------------------------------------------------------------------
// Earthmoving: factors
// ---------------------------------------------------------------------------

// A soil and blade for McKyes' 2-D equation (no side failure): the
// published factors and limiting cases are the 2-D ones.
EarthmovingParams fee(double alpha_deg, double delta_deg, double phi_deg, double gamma, double c,
                      double ca) {
  EarthmovingParams p;
  p.rake_angle_deg = alpha_deg;
  p.soil.soil_tool_friction_deg = delta_deg;
  p.soil.internal_friction_deg = phi_deg;
  p.soil.unit_weight_n_per_m3 = gamma;
  p.soil.cohesion_pa = c;
  p.soil.adhesion_pa = ca;
  p.side_failure = false;
  return p;
}

// McKyes (1985) factors written out again with tangents, independently of
// forces.cpp.
EarthmovingFactors reference_factors(double alpha, double delta, double phi, double beta) {
  double denom = std::cos(alpha + delta) + std::sin(alpha + delta) / std::tan(beta + phi);
  EarthmovingFactors f;
  f.n_gamma = (1.0 / std::tan(alpha) + 1.0 / std::tan(beta)) / (2.0 * denom);
  f.n_c = (1.0 + 1.0 / (std::tan(beta) * std::tan(beta + phi))) / denom;
  f.n_a = (1.0 - 1.0 / (std::tan(alpha) * std::tan(beta + phi))) / denom;
  f.n_q = (1.0 / std::tan(alpha) + 1.0 / std::tan(beta)) / denom;
  return f;
}

TEST(EarthmovingFactors, ExactByHandVerticalBlade) {
  // alpha 90, delta 0, phi 30, beta 30: cot a = 0, cot b = sqrt 3,
  // cot(b + phi) = 1/sqrt 3, D = 1/sqrt 3.
  EarthmovingParams p = fee(90, 0, 30, 1.0, 0.0, 0.0);
  EarthmovingFactors f = earthmoving_factors(p, 30 * kDeg, 1.0, 0.1);
  const double s3 = std::sqrt(3.0);
  expect_rel(f.n_gamma, 1.5, kRel, "N_gamma");
  expect_rel(f.n_c, 2.0 * s3, kRel, "N_c");
  expect_rel(f.n_a, s3, kRel, "N_a");
  expect_rel(f.n_q, 3.0, kRel, "N_q");
}

TEST(EarthmovingFactors, ExactByHandRakedBlade) {
  // alpha 45, delta 15, phi 30, beta 45: cot a = cot b = 1,
  // cot(75) = 2 - sqrt 3, D = 1/2 + (sqrt 3 / 2)(2 - sqrt 3) = sqrt 3 - 1.
  EarthmovingParams p = fee(45, 15, 30, 1.0, 0.0, 0.0);
  EarthmovingFactors f = earthmoving_factors(p, 45 * kDeg, 1.0, 0.1);
  const double s3 = std::sqrt(3.0);
  expect_rel(f.n_gamma, (s3 + 1.0) / 2.0, kRel, "N_gamma");
  expect_rel(f.n_c, s3, kRel, "N_c");
  expect_rel(f.n_a, 1.0, kRel, "N_a");
  expect_rel(f.n_q, s3 + 1.0, kRel, "N_q");
  // P at this beta for gamma 16 kN/m^3, c 2 kPa, ca 1 kPa, q 500 Pa, d 0.2, w 0.5.
  EarthmovingParams q = fee(45, 15, 30, 16e3, 2e3, 1e3);
  double expected = (16e3 * 0.04 * (s3 + 1.0) / 2.0 + 2e3 * 0.2 * s3 + 1e3 * 0.2 * 1.0 +
                     500.0 * 0.2 * (s3 + 1.0)) *
                    0.5;
  expect_rel(earthmoving_total_n(q, 0.5, 0.2, 45 * kDeg, 500.0), expected, kRel, "P");
}

TEST(EarthmovingFactors, MatchThePublishedFormulas) {
  std::mt19937 rng(20240604);
  std::uniform_real_distribution<double> alpha_deg(20.0, 120.0), delta_deg(0.0, 30.0),
      phi_deg(0.0, 40.0), unit(0.02, 0.98);
  for (int k = 0; k < 200; ++k) {
    double a = alpha_deg(rng) * kDeg, d = delta_deg(rng) * kDeg, f = phi_deg(rng) * kDeg;
    if (a + d + f > 170 * kDeg) continue;
    EarthmovingParams p = fee(a / kDeg, d / kDeg, f / kDeg, 16e3, 0.0, 0.0);
    BetaRange range = earthmoving_beta_range(p);
    double beta = range.lo_rad + unit(rng) * (range.hi_rad - range.lo_rad);
    EarthmovingFactors got = earthmoving_factors(p, beta, 0.5, 0.1);
    EarthmovingFactors want = reference_factors(a, d, f, beta);
    // The factors grow like 1/D near the range end; compare relatively.
    expect_rel(got.n_gamma, want.n_gamma, 1e-10, "N_gamma");
    expect_rel(got.n_c, want.n_c, 1e-10, "N_c");
    expect_rel(got.n_a, want.n_a, 1e-10, "N_a");
    expect_rel(got.n_q, want.n_q, 1e-10, "N_q");
  }
}

// ---------------------------------------------------------------------------
// Earthmoving: the minimiser and limiting cases
// ---------------------------------------------------------------------------

TEST(Earthmoving, MinimiserFindsTheMinimum) {
  // Every preset at rakes from 30 to 110 degrees, with and without side
  // failure, with and without a surcharge.
  std::vector<std::pair<EarthmovingParams, double>> cases;
  for (const auto& [s, preset_name] : kSoilPresetNames) {
    for (double alpha : {30.0, 45.0, 60.0, 75.0, 90.0, 110.0}) {
      for (bool side : {false, true}) {
        EarthmovingParams p;
        p.soil = soil_preset(s);
        p.rake_angle_deg = alpha;
        p.side_failure = side;
        cases.push_back({p, 0.0});
        cases.push_back({p, 1500.0});
      }
    }
  }
  cases.push_back({fee(60, 10, 35, 17e3, 0.0, 0.0), 2e3});  // surcharge only besides weight
  cases.push_back({fee(80, 25, 45, 18e3, 8e3, 4e3), 0.0});
  for (const auto& [p, q] : cases) {
    ASSERT_TRUE(validate(p).empty()) << validate(p);
    for (double depth : {0.02, 0.1, 0.3}) {
      EarthmovingResult r = earthmoving_force(p, 0.6, depth, q);
      BetaRange range = earthmoving_beta_range(p);
      ASSERT_GT(r.beta_rad, range.lo_rad);
      ASSERT_LE(r.beta_rad, range.hi_rad);
      expect_rel(r.total_n, earthmoving_total_n(p, 0.6, depth, r.beta_rad, q), kRel, "P(beta*)");
      // Neighbours at +-0.01 rad (where inside the range) are not lower.
      for (double db : {-0.01, 0.01}) {
        double b = r.beta_rad + db;
        if (b <= range.lo_rad || b >= range.hi_rad) continue;
        EXPECT_LE(r.total_n, earthmoving_total_n(p, 0.6, depth, b, q));
      }
      // Nor is any point of a dense grid over the whole range (global minimum).
      const int n = 2000;
      for (int k = 1; k < n; ++k) {
        double b = range.lo_rad + (range.hi_rad - range.lo_rad) * k / n;
        EXPECT_LE(r.total_n, earthmoving_total_n(p, 0.6, depth, b, q) * (1.0 + 1e-12))
            << "alpha " << p.rake_angle_deg << " beta " << b / kDeg;
      }
      // The reported factors are those at beta*.
      EarthmovingFactors f = earthmoving_factors(p, r.beta_rad, 0.6, depth);
      EXPECT_EQ(r.factors.n_gamma, f.n_gamma);
      EXPECT_EQ(r.factors.n_c, f.n_c);
    }
  }
}

TEST(Earthmoving, FrictionlessSoilIsHydrostatic) {
  // phi = delta = 0, c = c_a = q = 0: D = sin(alpha + beta) / sin(beta), so
  // N_gamma = (cot a + cot b) sin b / (2 sin(a + b)) = 1 / (2 sin a) for every
  // beta: P = gamma d^2 w / (2 sin a), the hydrostatic thrust on a face of
  // length d / sin a, normal to it. H = P sin a = gamma d^2 w / 2 and
  // V = P cos a = (gamma d^2 w / 2) cot a (the weight of soil over the face).
  const double gamma = 15e3, d = 0.25, w = 0.8;
  for (double alpha : {20.0, 45.0, 70.0, 90.0, 120.0}) {
    EarthmovingParams p = fee(alpha, 0, 0, gamma, 0.0, 0.0);
    EarthmovingResult r = earthmoving_force(p, w, d);
    double a = alpha * kDeg;
    expect_rel(r.total_n, gamma * d * d * w / (2.0 * std::sin(a)), 1e-10, "P");
    expect_rel(r.horizontal_n, gamma * d * d * w / 2.0, 1e-10, "H");
    EXPECT_NEAR(r.vertical_n, gamma * d * d * w / 2.0 / std::tan(a), 1e-10 * gamma * d * d * w)
        << "V at alpha " << alpha;
    expect_rel(r.factors.n_gamma, 1.0 / (2.0 * std::sin(a)), 1e-10, "N_gamma");
  }
}

TEST(Earthmoving, SmoothVerticalWallIsRankinePassive) {
  // alpha = 90, delta = 0: Coulomb's wedge on a smooth vertical wall gives
  // Rankine's passive thrust P = (gamma d^2 Kp / 2 + 2 c d sqrt(Kp) + q d Kp) w,
  // Kp = tan^2(45 + phi/2), on the plane beta* = 45 - phi/2; H = P, V = 0.
  const double d = 0.15, w = 0.5;
  for (double phi : {5.0, 15.0, 28.0, 35.0, 45.0}) {
    for (auto [gamma, c, q] :
         {std::tuple{16e3, 0.0, 0.0}, std::tuple{16e3, 3e3, 0.0}, std::tuple{18e3, 1e3, 800.0}}) {
      EarthmovingParams p = fee(90, 0, phi, gamma, c, 0.0);
      EarthmovingResult r = earthmoving_force(p, w, d, q);
      double kp = std::pow(std::tan((45.0 + phi / 2.0) * kDeg), 2);
      double expected = (0.5 * gamma * d * d * kp + 2.0 * c * d * std::sqrt(kp) + q * d * kp) * w;
      expect_rel(r.total_n, expected, 1e-12, "P");
      // The minimum is flat (quadratic), so beta* is known to ~sqrt(eps).
      EXPECT_NEAR(r.beta_rad, (45.0 - phi / 2.0) * kDeg, 1e-6) << "phi " << phi;
      expect_rel(r.horizontal_n, expected, 1e-12, "H");
      EXPECT_NEAR(r.vertical_n, 0.0, 1e-12 * expected);
    }
  }
  // phi = 0: P = gamma d^2 w / 2 + 2 c d w (Kp = 1).
  EarthmovingResult r = earthmoving_force(fee(90, 0, 0, 16e3, 2e3, 0.0), w, d);
  expect_rel(r.total_n, 0.5 * 16e3 * d * d * w + 2.0 * 2e3 * d * w, 1e-12, "phi = 0");
}

// The wedge's free body, resolved independently of forces.cpp: blade on soil
// (H forward, V up), weight and surcharge down, cohesion c w d / sin b down
// the failure plane, and the reaction R at phi to the plane's normal. R from
// the horizontal balance; the vertical balance must then close.
TEST(Earthmoving, HorizontalAndVerticalBalanceTheWedge) {
  std::vector<std::pair<EarthmovingParams, double>> cases = {
      {fee(90, 20, 30, 16e3, 1e3, 0.0), 0.0}, {fee(50, 15, 28, 15e3, 2e3, 1.5e3), 400.0},
      {fee(70, 8, 13, 18e3, 4e3, 2e3), 0.0}, {fee(110, 10, 25, 17e3, 0.0, 1e3), 1e3}};
  for (const auto& [s, preset_name] : kSoilPresetNames) {
    EarthmovingParams p = fee(60, 0, 0, 1.0, 0.0, 0.0);
    p.soil = soil_preset(s);
    cases.push_back({p, 0.0});
  }
  const double d = 0.2, w = 0.7;
  for (const auto& [p, q] : cases) {
    EarthmovingResult r = earthmoving_force(p, w, d, q);
    double a = p.rake_angle_deg * kDeg, b = r.beta_rad, phi = p.soil.internal_friction_deg * kDeg;
    double weight =
        p.soil.unit_weight_n_per_m3 * w * d * d * (1 / std::tan(a) + 1 / std::tan(b)) / 2;
    double surcharge = q * w * d * (1 / std::tan(a) + 1 / std::tan(b));
    double cohesion = p.soil.cohesion_pa * w * d / std::sin(b);
    double reaction = (r.horizontal_n - cohesion * std::cos(b)) / std::sin(b + phi);
    double vertical =
        r.vertical_n + reaction * std::cos(b + phi) - cohesion * std::sin(b) - weight - surcharge;
    EXPECT_NEAR(vertical, 0.0, 1e-9 * r.total_n) << "alpha " << a / kDeg;
    EXPECT_GT(reaction, 0.0);
    // And the blade's own balance: face force P at delta to the normal plus
    // adhesion c_a w d / sin a along the face.
    double delta = p.soil.soil_tool_friction_deg * kDeg;
    double adhesion = p.soil.adhesion_pa * w * d / std::sin(a);
    expect_rel(r.horizontal_n, r.total_n * std::sin(a + delta) + adhesion * std::cos(a), 1e-12,
               "H");
    expect_rel(r.vertical_n, r.total_n * std::cos(a + delta) - adhesion * std::sin(a), 1e-12, "V");
  }
}

TEST(Earthmoving, ScalesWithWidthAndDepth) {
  EarthmovingParams p = fee(60, 15, 30, 16e3, 0.0, 0.0);  // gamma only: P ~ d^2 w
  EarthmovingResult r1 = earthmoving_force(p, 0.5, 0.1);
  EarthmovingResult r2 = earthmoving_force(p, 1.0, 0.2);
  expect_rel(r2.total_n, 8.0 * r1.total_n, 1e-12, "gamma: w d^2");
  EXPECT_NEAR(r2.beta_rad, r1.beta_rad, 1e-6);
  EarthmovingParams c = fee(60, 15, 30, 1e-9, 5e3, 0.0);  // cohesion only: P ~ d w
  expect_rel(earthmoving_force(c, 1.0, 0.2).total_n, 4.0 * earthmoving_force(c, 0.5, 0.1).total_n,
             1e-9, "c: w d");
  // No width or no depth: nothing.
  EXPECT_EQ(earthmoving_force(p, 0.0, 0.1).total_n, 0.0);
  EXPECT_EQ(earthmoving_force(p, 0.5, 0.0).total_n, 0.0);
  EXPECT_EQ(earthmoving_force(p, 0.5, -0.1).horizontal_n, 0.0);
}

TEST(Earthmoving, SurchargeRatioIsExactForACohesionlessSoil) {
  // McKyes: N_q = 2 N_gamma at the same failure angle, so with c = c_a = 0
  // P(q) / P(0) = (gamma d^2 / 2 + q d) / (gamma d^2 / 2) = 1 + 2 q / (gamma d),
  // and the minimising beta does not depend on q. A pile of height h on the
  // wedge gives q = gamma h.
  EarthmovingParams p = fee(90, 20, 35, 16e3, 0.0, 0.0);
  const double d = 0.05, w = 1.0;
  const EarthmovingResult bare = earthmoving_force(p, w, d);
  for (const double pile_m : {0.05, 0.2, 0.5}) {
    const double q = p.soil.unit_weight_n_per_m3 * pile_m;
    const EarthmovingResult r = earthmoving_force(p, w, d, q);
    const double ratio = 1.0 + 2.0 * q / (p.soil.unit_weight_n_per_m3 * d);
    expect_rel(r.total_n, ratio * bare.total_n, 1e-9, "P(q) / P(0)");
    expect_rel(r.horizontal_n, ratio * bare.horizontal_n, 1e-9, "H(q) / H(0)");
    EXPECT_NEAR(r.beta_rad, bare.beta_rad, 1e-7) << pile_m;
    // The surcharge's part is what the pile adds.
    expect_rel(r.surcharge_total_n, r.total_n - bare.total_n, 1e-9, "the pile's part of P");
    expect_rel(r.surcharge_horizontal_n, r.horizontal_n - bare.horizontal_n, 1e-9, "its part of H");
  }
}

// The surcharge's part is the q terms of the same solution, with side
// failure too: P(beta*; q) minus P(beta*; 0) at the same failure plane.
TEST(Earthmoving, TheSurchargePartIsTheQTermsAtTheSameWedge) {
  for (const auto& [s, preset_name] : kSoilPresetNames) {
    EarthmovingParams p;
    p.soil = soil_preset(s);
    p.rake_angle_deg = 70.0;
    const double w = 0.3, d = 0.08, q = 2500.0;
    const EarthmovingResult r = earthmoving_force(p, w, d, q);
    const double without = earthmoving_total_n(p, w, d, r.beta_rad, 0.0);
    expect_rel(r.surcharge_total_n, r.total_n - without, 1e-10, "P_q");
    EXPECT_GT(r.surcharge_total_n, 0.0);
    expect_rel(r.surcharge_horizontal_n / r.surcharge_total_n,
               std::sin((p.rake_angle_deg + p.soil.soil_tool_friction_deg) * kDeg), 1e-12, "along the face force");
  }
}

TEST(Earthmoving, WorldForceOpposesHorizontalMotion) {
  EarthmovingParams p;
  p.soil = soil_preset(SoilPreset::kDrySand);
  p.rake_angle_deg = 60;
  EarthmovingResult r = earthmoving_force(p, 0.5, 0.1);
  ASSERT_GT(r.horizontal_n, 0.0);
  // Uncapped: the physical force, whole at any horizontal speed.
  Vec3 slow = earthmoving_world_force(r, {1e-9, 0.0, 0.0}, kUncapped_n_s_per_m);
  expect_rel(slow.x, -r.horizontal_n, kRel, "physical, slowly");
  expect_rel(slow.y, -r.vertical_n, kRel, "physical V");
  const double fast = 1e6;  // low-speed damping high enough to saturate at once
  Vec3 f = earthmoving_world_force(r, {0.4, -0.3, 0.0}, fast);
  expect_rel(f.x, -r.horizontal_n, kRel, "against +X");
  expect_rel(f.y, -r.vertical_n, kRel, "V down");
  EXPECT_EQ(f.z, 0.0);
  Vec3 g = earthmoving_world_force(r, {0.0, 0.0, -2.0}, fast);
  expect_rel(g.z, r.horizontal_n, kRel, "against -Z");
  // Vertical motion alone, or none: no cutting force.
  EXPECT_EQ(length(earthmoving_world_force(r, {0.0, -1.0, 0.0}, fast)), 0.0);
  EXPECT_EQ(length(earthmoving_world_force(r, {0.0, 0.0, 0.0}, fast)), 0.0);
  // Low speed: both components scale by beta |v| / H, keeping the direction.
  const double beta = 1000.0, speed = 0.5 * r.horizontal_n / beta;
  Vec3 s = earthmoving_world_force(r, {speed, 0.0, 0.0}, beta);
  expect_rel(s.x, -0.5 * r.horizontal_n, kRel, "H at half saturation");
  expect_rel(s.y, -0.5 * r.vertical_n, kRel, "V at half saturation");
}

TEST(Earthmoving, ValidateNamesTheField) {
  EarthmovingParams p;
  p.soil.cohesion_pa = -1.0;
  EXPECT_NE(validate(p).find("soil.cohesion_pa"), std::string::npos);
  p = {};
  p.soil.internal_friction_deg = 95;
  EXPECT_NE(validate(p).find("soil.internal_friction_deg"), std::string::npos);
  p = {};
  p.rake_angle_deg = 0.0;
  EXPECT_NE(validate(p).find("rake_angle_deg"), std::string::npos);
  p = fee(130, 30, 25, 16e3, 0, 0);  // 185 deg: no wedge
  EXPECT_NE(validate(p).find("no planar failure wedge"), std::string::npos);
  p.soil.unit_weight_n_per_m3 = 0.0;
  EXPECT_NE(validate(p).find("unit_weight_n_per_m3"), std::string::npos);
}


// ---------------------------------------------------------------------------
// Side failure: the crescents beyond a blade's ends (McKyes & Ali 1977)
// ---------------------------------------------------------------------------

// McKyes & Ali's factors of a vertical blade (crescent angle 90 degrees),
// written out in their own form with r = d cot(beta), the crescent's radius:
//   N_gamma = (r / 2d) (1 + 2 r / (3 w)) / D,  N_c = (1 + cot b cot(b + phi)) (1 + r / w) / D,
//   N_q = (r / d) (1 + r / w) / D,  D = cos(90 + delta) + sin(90 + delta) cot(b + phi).
TEST(SideFailure, AVerticalBladeHasMcKyesAndAlisFactors) {
  std::mt19937 rng(1977);
  std::uniform_real_distribution<double> phi_deg(5.0, 45.0), delta_deg(0.0, 30.0), unit(0.05, 0.95),
      width(0.02, 2.0), depth(0.01, 0.3);
  for (int k = 0; k < 300; ++k) {
    EarthmovingParams p;
    p.rake_angle_deg = 90.0;
    p.soil.internal_friction_deg = phi_deg(rng);
    p.soil.soil_tool_friction_deg = delta_deg(rng);
    const BetaRange range = earthmoving_beta_range(p);
    const double b = range.lo_rad + unit(rng) * (range.hi_rad - range.lo_rad);
    const double w = width(rng), d = depth(rng);
    const double phi = p.soil.internal_friction_deg * kDeg, delta = p.soil.soil_tool_friction_deg * kDeg;
    const double r = d / std::tan(b);
    const double D = std::cos(kPi / 2 + delta) + std::sin(kPi / 2 + delta) / std::tan(b + phi);
    const EarthmovingFactors f = earthmoving_factors(p, b, w, d);
    expect_rel(f.n_gamma, r / (2.0 * d) * (1.0 + 2.0 * r / (3.0 * w)) / D, 1e-10, "N_gamma");
    expect_rel(f.n_c, (1.0 + 1.0 / (std::tan(b) * std::tan(b + phi))) * (1.0 + r / w) / D, 1e-10, "N_c");
    expect_rel(f.n_q, r / d * (1.0 + r / w) / D, 1e-10, "N_q");
  }
}

// The crescents' closed forms against a numerical integration of their
// elements: the wedge's section ahead of the tip (a right triangle of height
// d and base r = d cot beta at the surface) turned about the vertical
// through the tip's end by theta in [0, 90] degrees; an element d(theta)
// pushes radially, its weight, surcharge and the cohesion on its failure
// surface resolved along the travel by cos(theta). Both ends together.
TEST(SideFailure, TheCrescentsAreTheirElementsSummed) {
  const double gamma = 17e3, c = 2e3, q = 900.0, d = 0.07, w = 0.25, beta = 0.5, phi = 0.55;
  const double r = d / std::tan(beta);
  // Midpoint rule over theta, radius and depth.
  const int n = 400;
  double weight = 0.0, surcharge = 0.0, cohesion_area = 0.0;
  for (int i = 0; i < n; ++i) {
    const double theta = (i + 0.5) * (kPi / 2) / n, dtheta = (kPi / 2) / n;
    const double resolved = std::cos(theta) * dtheta;
    for (int j = 0; j < n; ++j) {
      const double rho = (j + 0.5) * r / n, drho = r / n;
      // The section's height at rho: from the failure line up to the surface.
      const double height = d * (1.0 - rho / r);
      weight += 2.0 * gamma * height * rho * drho * resolved;
      surcharge += 2.0 * q * rho * drho * resolved;
      // The failure surface above this ring: slant length drho / cos(beta).
      cohesion_area += 2.0 * rho * drho / std::cos(beta) * resolved;
    }
  }
  EXPECT_NEAR(weight, gamma * d * d * d / (std::tan(beta) * std::tan(beta)) / 3.0, 1e-4 * weight);
  EXPECT_NEAR(surcharge, q * d * d / (std::tan(beta) * std::tan(beta)), 1e-4 * surcharge);
  // Cohesion c A on a plane at beta enters the balance as c A sin(beta) (1 + cot b cot(b + phi)).
  EXPECT_NEAR(c * cohesion_area * std::sin(beta), c * d * d / std::tan(beta), 1e-4 * c * d * d);
  // And the force: P(beta) with side failure is the 2-D one plus these loads over D.
  EarthmovingParams p;
  p.rake_angle_deg = 90.0;
  p.soil.unit_weight_n_per_m3 = gamma;
  p.soil.cohesion_pa = c;
  p.soil.adhesion_pa = 0.0;
  p.soil.internal_friction_deg = phi / kDeg;
  p.soil.soil_tool_friction_deg = 20.0;
  EarthmovingParams flat = p;
  flat.side_failure = false;
  const double D = std::cos(kPi / 2 + 20.0 * kDeg) + std::sin(kPi / 2 + 20.0 * kDeg) / std::tan(beta + phi);
  const double side = (weight + surcharge + c * cohesion_area * std::sin(beta) *
                                                (1.0 + 1.0 / (std::tan(beta) * std::tan(beta + phi)))) /
                      D;
  EXPECT_NEAR(earthmoving_total_n(p, w, d, beta, q) - earthmoving_total_n(flat, w, d, beta, q), side,
              2e-4 * side);
}

// A blade wide against its depth tends to the 2-D equation: the crescents
// add a fixed load at each end, so the excess over the 2-D force falls as
// d / w; a narrow blade feels more per metre of width.
TEST(SideFailure, AWideBladeTendsToTheTwoDimensionalEquation) {
  for (const auto& [s, preset_name] : kSoilPresetNames) {
    for (double alpha : {45.0, 90.0}) {
      EarthmovingParams p;
      p.soil = soil_preset(s);
      p.rake_angle_deg = alpha;
      EarthmovingParams flat = p;
      flat.side_failure = false;
      const double d = 0.05;
      double previous_excess = 1e300, previous_per_width = 1e300;
      for (double w : {0.05, 0.2, 1.0, 5.0, 50.0, 500.0}) {
        const double h3 = earthmoving_force(p, w, d).horizontal_n;
        const double h2 = earthmoving_force(flat, w, d).horizontal_n;
        const double excess = (h3 - h2) / h2;
        EXPECT_GT(excess, 0.0) << to_string(s) << " alpha " << alpha << " w " << w;
        EXPECT_LT(excess, previous_excess);
        EXPECT_LT(h3 / w, previous_per_width);  // narrower: more per metre
        // O(d / w): the excess times w / d stays bounded (by the crescents'
        // load at the most favourable wedge over the 2-D wedge's per metre).
        EXPECT_LT(excess * w / d, 3.0) << to_string(s) << " alpha " << alpha << " w " << w;
        previous_excess = excess;
        previous_per_width = h3 / w;
      }
      EXPECT_LT(previous_excess, 1e-3);  // 500 m against 5 cm: the 2-D force
    }
  }
  // A blade of no width still meets the crescents' resistance at its ends.
  EarthmovingParams p;
  EXPECT_GT(earthmoving_force(p, 1e-6, 0.1).horizontal_n, 10.0);
}

}  // namespace
}  // namespace terracut
