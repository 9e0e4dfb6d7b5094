// Twist (twist.hpp): the resistance to turning a buried blade, by hand.
#include "terracut/core/twist.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace terracut {
namespace {


// Relative tolerance for closed forms evaluated in double: a few dozen
// roundings of O(1) trigonometric terms.
constexpr double kRel = 1e-12;

void expect_rel(double actual, double expected, double rel, const char* what) {
  EXPECT_NEAR(actual, expected, rel * std::max(1.0, std::abs(expected))) << what;
}


// A straight edge engaged from s0 to s1 (signed distances from the axis).
TwistEngagement engaged_between(double s0, double s1) {
  TwistEngagement e;
  // integral of |s|, sign(s), s^2 over [s0, s1], split at 0.
  auto part = [&](double a, double b, double sign) {
    e.engaged_length_m += b - a;
    e.abs_moment_m2 += sign * 0.5 * (b * b - a * a);
    e.signed_length_m += sign * (b - a);
    e.second_moment_m3 += (b * b * b - a * a * a) / 3.0;
  };
  if (s0 < 0.0) part(s0, std::min(s1, 0.0), -1.0);
  if (s1 > 0.0) part(std::max(s0, 0.0), s1, 1.0);
  return e;
}

TEST(Twist, CentredBladeFeelsATorqueAndNoNetForce) {
  const double f = 400.0, L = 0.5, beta = 1000.0;
  const TwistEngagement e = engaged_between(-0.25, 0.25);
  // Fast turning: the saturated torque f L^2 / 4 against the yaw rate.
  const TwistResult t = twist_resistance(f, e, 10.0, beta, L);
  expect_rel(t.torque_n_m, -f * L * L / 4.0, kRel, "torque");
  EXPECT_NEAR(t.net_force_n, 0.0, 1e-12);
  // The other way: the opposite torque.
  expect_rel(twist_resistance(f, e, -10.0, beta, L).torque_n_m, f * L * L / 4.0, kRel, "sign");
}

TEST(Twist, ZeroRateOrNoEngagementGivesZero) {
  const TwistEngagement e = engaged_between(-0.25, 0.25);
  EXPECT_EQ(twist_resistance(400.0, e, 0.0, 1000.0, 0.5).torque_n_m, 0.0);
  EXPECT_EQ(twist_resistance(400.0, TwistEngagement{}, 3.0, 1000.0, 0.5).torque_n_m, 0.0);
  EXPECT_EQ(twist_resistance(0.0, e, 3.0, 1000.0, 0.5).torque_n_m, 0.0);
  EXPECT_TRUE(std::isnan(twist_resistance(400.0, e, std::nan(""), 1000.0, 0.5).torque_n_m));
}

TEST(Twist, ScalesWithTheSquareOfTheLengthAndIsADamperWhenSlow) {
  const double f = 400.0, beta = 1000.0, L = 1.0;
  const TwistResult a = twist_resistance(f, engaged_between(-0.2, 0.2), 50.0, beta, L);
  const TwistResult b = twist_resistance(f, engaged_between(-0.4, 0.4), 50.0, beta, L);
  expect_rel(b.torque_n_m, 4.0 * a.torque_n_m, kRel, "L^2");
  // Slowly: each metre of edge a damper of beta / L_blade: T = beta w integral s^2 / L.
  const TwistEngagement e = engaged_between(-0.4, 0.4);
  const double w = 1e-4;
  expect_rel(twist_resistance(f, e, w, beta, L).torque_n_m, -beta * w * e.second_moment_m3 / L,
             kRel, "damper");
}

TEST(Twist, UncappedIsTheWholeResistanceAtAnyRate) {
  const TwistEngagement e = engaged_between(-0.1, 0.3);
  for (double w : {1e-9, 0.1, 30.0}) {
    const TwistResult t = twist_resistance(400.0, e, w, kUncapped_n_s_per_m, 0.4);
    expect_rel(t.torque_n_m, -400.0 * e.abs_moment_m2, kRel, "torque");
    expect_rel(t.net_force_n, -400.0 * e.signed_length_m, kRel, "net");
  }
}

TEST(Twist, OneSidedEngagementGivesANetForceAgainstTheMotion) {
  // Only the +s half in soil: turning at +w moves it along +n, so the soil
  // pushes it along -n; the net force is f L_half and the torque f L_half^2 / 2.
  const double f = 300.0;
  const TwistResult t = twist_resistance(f, engaged_between(0.0, 0.3), 20.0, 1000.0, 0.6);
  expect_rel(t.net_force_n, -f * 0.3, kRel, "net");
  expect_rel(t.torque_n_m, -f * 0.09 / 2.0, kRel, "torque");
  // Mirrored engagement: the mirrored force, the same torque.
  const TwistResult m = twist_resistance(f, engaged_between(-0.3, 0.0), 20.0, 1000.0, 0.6);
  expect_rel(m.net_force_n, -t.net_force_n, kRel, "mirror net");
  expect_rel(m.torque_n_m, t.torque_n_m, kRel, "mirror torque");
}
}  // namespace
}  // namespace terracut
