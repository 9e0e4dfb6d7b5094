// The device-to-world mapping: CHAI3D's device axes (x toward the operator,
// y right, z up) onto the world's (Y up), scale, offset and yaw.
#include "terracut/haptics/workspace.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace terracut::haptics {
namespace {

constexpr double kTol = 1e-12;

void expect_near(Vec3 a, Vec3 b, double tol = kTol) {
  EXPECT_NEAR(a.x, b.x, tol);
  EXPECT_NEAR(a.y, b.y, tol);
  EXPECT_NEAR(a.z, b.z, tol);
}

TEST(Workspace, DeviceAxesMapOntoWorldAxes) {
  const Workspace w(WorkspaceMapping{1.0, {}, 0.0});
  // Toward the operator -> +Z (the operator stands on the +Z side, looking along -Z).
  expect_near(w.direction_to_world({1, 0, 0}), {0, 0, 1});
  // Right -> +X: looking along -Z with Y up, the right hand points to +X.
  expect_near(w.direction_to_world({0, 1, 0}), {1, 0, 0});
  // Up -> up.
  expect_near(w.direction_to_world({0, 0, 1}), {0, 1, 0});
  // A proper rotation: right-handed frames stay right-handed.
  const Vec3 x = w.direction_to_world({1, 0, 0});
  const Vec3 y = w.direction_to_world({0, 1, 0});
  expect_near(cross(x, y), w.direction_to_world({0, 0, 1}));
}

TEST(Workspace, ScaleOffsetAndInverse) {
  const Workspace w(WorkspaceMapping{12.0, {0.5, 0.2, -1.0}, 0.0});
  expect_near(w.to_world({0, 0, 0}), {0.5, 0.2, -1.0});
  // 1 cm up on the device is 12 cm up in the world.
  expect_near(w.to_world({0, 0, 0.01}), {0.5, 0.32, -1.0});
  for (Vec3 d : {Vec3{0.01, -0.02, 0.03}, Vec3{-0.04, 0.0, 0.04}}) {
    expect_near(w.to_device(w.to_world(d)), d);
    expect_near(w.direction_to_device(w.direction_to_world(d)), d);
  }
}

TEST(Workspace, YawTurnsTheOperatorAboutWorldUp) {
  // Yaw 90: +X turns toward -Z, so "toward the operator" (+Z at yaw 0) becomes +X.
  const Workspace w(WorkspaceMapping{1.0, {}, 90.0});
  expect_near(w.direction_to_world({1, 0, 0}), {1, 0, 0});
  expect_near(w.direction_to_world({0, 1, 0}), {0, 0, -1});
  expect_near(w.direction_to_world({0, 0, 1}), {0, 1, 0});
}

TEST(Workspace, OrientationsAreTheSameTurnAboutTheMatchingAxis) {
  const Workspace w(WorkspaceMapping{3.0, {1, 2, 3}, 30.0});
  // Identity on the device is identity in the world.
  const Quat id = w.orientation_to_world(Quat{});
  EXPECT_NEAR(std::abs(id.w), 1.0, kTol);
  // A turn about device z (up) is the same turn about world Y.
  const Quat dev = quat_from_axis_angle({0, 0, 1}, 0.7);
  const Quat world = w.orientation_to_world(dev);
  const Quat want = quat_from_axis_angle({0, 1, 0}, 0.7);
  EXPECT_NEAR(std::abs(world.w * want.w + world.x * want.x + world.y * want.y + world.z * want.z),
              1.0, kTol);
  // Round trip.
  const Quat back = w.orientation_to_device(world);
  EXPECT_NEAR(std::abs(back.w * dev.w + back.x * dev.x + back.y * dev.y + back.z * dev.z), 1.0,
              kTol);
}

}  // namespace
}  // namespace terracut::haptics
