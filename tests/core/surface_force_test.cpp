// The surface height query (surface.hpp) the proxy reads, and the surface
// model's spring-damper (surface_force.hpp).
#include "terracut/core/surface_force.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "terracut/core/contact.hpp"
#include "terracut/core/surface.hpp"

namespace terracut {
namespace {


HeightGrid small_grid() {
  GridSpec spec;
  spec.cols = 4;
  spec.rows = 3;
  spec.size_x_m = 0.4;  // cells of 0.1 x 0.1
  spec.size_z_m = 0.3;
  spec.origin_m = {-1.0, 0.5, 2.0};
  spec.full_scale_m = 1.0;
  std::vector<float> h = {0.10f, 0.20f, 0.30f, 0.20f,  //
                          0.15f, 0.25f, 0.05f, 0.40f,  //
                          0.30f, 0.10f, 0.20f, 0.35f};
  return HeightGrid(spec, h);
}

TEST(SurfaceHeight, ColumnsAndSurfaceReadTheSamples) {
  HeightGrid g = small_grid();
  for (int r = 0; r < g.rows(); ++r) {
    for (int c = 0; c < g.cols(); ++c) {
      double x = g.sample_x(c), z = g.sample_z(r);
      double h = g.height(c, r);
      EXPECT_NEAR(surface_height_m(g, Representation::kSurface, x, z), h, 1e-12);
      // Columns: the whole cell is flat at its sample.
      EXPECT_NEAR(surface_height_m(g, Representation::kColumns, x + 0.049, z - 0.049), h, 1e-12);
      EXPECT_NEAR(surface_y_m(g, Representation::kColumns, x, z), 0.5 + h, 1e-12);
    }
  }
  // Midway between two neighbours along X: the average (on the shared edge).
  double mid = surface_height_m(g, Representation::kSurface, 0.5 * (g.sample_x(0) + g.sample_x(1)),
                                g.sample_z(1));
  EXPECT_NEAR(mid, 0.5 * (0.15 + 0.25), 1e-7);
  // Centre of square (1,0)-(2,1): on the diagonal from (2,0) to (1,1), the
  // average of those two samples.
  double centre =
      surface_height_m(g, Representation::kSurface, 0.5 * (g.sample_x(1) + g.sample_x(2)),
                       0.5 * (g.sample_z(0) + g.sample_z(1)));
  EXPECT_NEAR(centre, 0.5 * (0.30 + 0.25), 1e-7);
  // Half-cell border: flat at the outer sample.
  EXPECT_NEAR(surface_height_m(g, Representation::kSurface, -1.0 + 0.01, g.sample_z(2)), 0.30,
              1e-7);
  // Outside the terrain: the ground.
  EXPECT_EQ(surface_height_m(g, Representation::kSurface, -1.01, 2.1), 0.0);
  EXPECT_EQ(surface_height_m(g, Representation::kColumns, 0.0, 2.1), 0.0);
}

// The proxy's surface and measure_contact must describe the same solid: a
// tiny segment just below surface_y is in contact, just above it is not.
TEST(SurfaceHeight, AgreesWithMeasureContact) {
  HeightGrid g = small_grid();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> ux(-0.99, -0.61), uz(2.01, 2.29);
  for (Representation rep : {Representation::kSurface, Representation::kColumns}) {
    for (int k = 0; k < 300; ++k) {
      double x = ux(rng), z = uz(rng);
      double y = surface_y_m(g, rep, x, z);
      Segment below{{x - 1e-7, y - 1e-4, z}, {x + 1e-7, y - 1e-4, z}};
      Segment above{{x - 1e-7, y + 1e-4, z}, {x + 1e-7, y + 1e-4, z}};
      EXPECT_GT(measure_contact(g, rep, below).length_m, 0.0) << "x " << x << " z " << z;
      EXPECT_EQ(measure_contact(g, rep, above).length_m, 0.0) << "x " << x << " z " << z;
    }
  }
}

TEST(SurfaceForce, SpringDamperBelowTheSurfaceOnly) {
  SurfaceParams p;
  p.stiffness_n_per_m = 2000.0;
  p.damping_n_s_per_m = 5.0;
  // Above: nothing, proxy at the device.
  SurfaceForce above = surface_force(p, {0.1, 0.32, 0.0}, {0.0, -1.0, 0.0}, 0.3);
  EXPECT_FALSE(above.in_contact);
  EXPECT_EQ(length(above.force_n), 0.0);
  EXPECT_EQ(above.proxy_m.y, 0.32);
  // 1 cm below, moving down at 0.1 m/s: K d + B |v| up; proxy on the surface.
  SurfaceForce below = surface_force(p, {0.1, 0.29, -0.2}, {0.3, -0.1, 0.0}, 0.3);
  EXPECT_TRUE(below.in_contact);
  EXPECT_NEAR(below.penetration_m, 0.01, 1e-15);
  EXPECT_NEAR(below.force_n.y, 2000.0 * 0.01 + 5.0 * 0.1, 1e-12);
  EXPECT_EQ(below.force_n.x, 0.0);
  EXPECT_EQ(below.force_n.z, 0.0);
  EXPECT_EQ(below.proxy_m.x, 0.1);
  EXPECT_EQ(below.proxy_m.y, 0.3);
  EXPECT_EQ(below.proxy_m.z, -0.2);
  // Leaving fast: the damper would pull down; the surface never pulls.
  SurfaceForce leaving = surface_force(p, {0.0, 0.299, 0.0}, {0.0, 2.0, 0.0}, 0.3);
  EXPECT_EQ(leaving.force_n.y, 0.0);
  // The force is continuous across the surface.
  EXPECT_NEAR(surface_force(p, {0.0, 0.3 - 1e-12, 0.0}, {}, 0.3).force_n.y, 0.0, 1e-8);
}
}  // namespace
}  // namespace terracut
