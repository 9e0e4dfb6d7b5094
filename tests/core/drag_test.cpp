// The saturated damper and the paper's contact drag (drag.hpp), against
// their closed forms.
#include "terracut/core/drag.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>

#include "terracut/core/forces.hpp"

namespace terracut {
namespace {


// Relative tolerance for closed forms evaluated in double: a few dozen
// roundings of O(1) trigonometric terms.
constexpr double kRel = 1e-12;

void expect_rel(double actual, double expected, double rel, const char* what) {
  EXPECT_NEAR(actual, expected, rel * std::max(1.0, std::abs(expected))) << what;
}

TEST(ContactDrag, ZeroVelocityGivesZeroForce) {
  ContactDragParams p;
  p.viscous_n_s_per_m2 = 50.0;
  Vec3 f = contact_drag_force(p, 0.7, {0.0, 0.0, 0.0}, 1000.0);
  EXPECT_EQ(f.x, 0.0);
  EXPECT_EQ(f.y, 0.0);
  EXPECT_EQ(f.z, 0.0);
}

TEST(ContactDrag, OpposesTheVelocity) {
  ContactDragParams p;
  Vec3 v{0.3, -0.1, 0.2};
  Vec3 f = contact_drag_force(p, 0.5, v, 1000.0);
  Vec3 c = cross(f, v);
  EXPECT_LT(dot(f, v), 0.0);
  EXPECT_NEAR(length(c), 0.0, 1e-12 * length(f) * length(v));
  // Saturated: |F| = k_drag * L.
  EXPECT_NEAR(length(f), p.drag_n_per_m * 0.5, 1e-12 * p.drag_n_per_m);
}

TEST(ContactDrag, LinearInContactLength) {
  ContactDragParams p;
  p.drag_n_per_m = 350.0;
  p.viscous_n_s_per_m2 = 40.0;
  // Fast enough that k L < low-speed damping * |v| for every L below (saturated).
  Vec3 v{1.2, 0.0, -0.5};
  const double beta = 1000.0;
  Vec3 unit = contact_drag_force(p, 1.0, v, beta);
  for (double l : {0.0, 0.05, 0.2, 0.5, 0.75, 1.0}) {
    Vec3 f = contact_drag_force(p, l, v, beta);
    expect_rel(f.x, l * unit.x, kRel, "x");
    expect_rel(f.y, l * unit.y, kRel, "y");
    expect_rel(f.z, l * unit.z, kRel, "z");
  }
  // The magnitude is k L + c L |v|.
  double speed = length(v);
  expect_rel(length(unit), p.drag_n_per_m + p.viscous_n_s_per_m2 * speed, kRel, "magnitude");
}

TEST(ContactDrag, LowSpeedIsASaturatedDamper) {
  ContactDragParams p;
  p.drag_n_per_m = 400.0;
  const double beta = 1000.0, l = 0.5;  // saturation at k L / beta = 0.2 m/s
  for (double speed : {1e-6, 0.01, 0.1, 0.19}) {
    Vec3 f = contact_drag_force(p, l, {0.0, 0.0, speed}, beta);
    expect_rel(f.z, -beta * speed, kRel, "below saturation");
  }
  for (double speed : {0.21, 1.0, 10.0}) {
    Vec3 f = contact_drag_force(p, l, {0.0, 0.0, speed}, beta);
    expect_rel(f.z, -p.drag_n_per_m * l, kRel, "above saturation");
  }
  EXPECT_DOUBLE_EQ(saturated_drag_n(200.0, 0.2, 1000.0), 200.0);
  EXPECT_EQ(saturated_drag_n(200.0, 0.0, 1000.0), 0.0);
}

TEST(ContactDrag, NegativeLengthIsNoContactAndNanPropagates) {
  ContactDragParams p;
  Vec3 f = contact_drag_force(p, -0.3, {1.0, 0.0, 0.0}, 1000.0);
  EXPECT_EQ(length(f), 0.0);
  Vec3 g = contact_drag_force(p, std::nan(""), {1.0, 0.0, 0.0}, 1000.0);
  EXPECT_FALSE(is_finite(g));  // for the safety limiter to catch
}


TEST(ContactDrag, ValidateNamesTheField) {
  ForceModelParams p;
  p.contact_drag.drag_n_per_m = -1.0;
  EXPECT_NE(validate(p).find("contact_drag.drag_n_per_m"), std::string::npos);
  p = {};
  p.contact_drag.viscous_n_s_per_m2 = std::numeric_limits<double>::infinity();
  EXPECT_NE(validate(p).find("contact_drag.viscous_n_s_per_m2"), std::string::npos);
  EXPECT_TRUE(validate(ForceModelParams{}).empty());
}

// Uncapped, the saturated damper is the physical force: all of it whenever
// the tool moves, however slowly, and nothing at rest (never NaN).
TEST(SaturatedDrag, UncappedIsTheWholeForceWhenMoving) {
  for (double speed : {1e-12, 1e-3, 1.0, 1e6}) EXPECT_EQ(saturated_drag_n(250.0, speed, kUncapped_n_s_per_m), 250.0);
  EXPECT_EQ(saturated_drag_n(250.0, 0.0, kUncapped_n_s_per_m), 0.0);
  EXPECT_EQ(saturated_drag_n(0.0, 1.0, kUncapped_n_s_per_m), 0.0);
}

}  // namespace
}  // namespace terracut
