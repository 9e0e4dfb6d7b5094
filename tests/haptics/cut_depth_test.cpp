// The depth of cut and the pile ahead of a moving edge (cut_depth.hpp): the
// depth reads the uncut soil ahead, a pile pushed by the blade counts as a
// surcharge height, not as depth.
#include "terracut/haptics/cut_depth.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace terracut::haptics {
namespace {

TEST(CutDepth, WithoutAPileTheDepthIsTheDepthAhead) {
  HeightGrid g(grid_of_cells(100, 100, 0.01), std::vector<float>(100 * 100, 0.2f));
  const Segment edge{{0.3, 0.15, 0.4}, {0.7, 0.15, 0.4}};
  const Vec3 v{0.0, 0.0, 0.5};
  const double look = depth_lookahead_m(g.spec());
  const SoilAhead a = soil_ahead(g, Representation::kSurface, edge, v, look);
  EXPECT_NEAR(a.depth_m, depth_ahead_m(g, Representation::kSurface, edge, v, look), 1e-12);
  EXPECT_NEAR(a.depth_m, 0.05, 1e-6);
  EXPECT_EQ(a.pile_m, 0.0);
}

TEST(CutDepth, APileAheadIsNotDepthButSurchargeHeight) {
  // The initial layer is 0.2 m; 0.1 m of soil is piled on it ahead of the
  // edge (from z = 0.40 m on, the edge at 0.40), over more than the failure
  // wedge's length.
  std::vector<float> initial(100 * 100, 0.2f);
  HeightGrid g(grid_of_cells(100, 100, 0.01), initial);
  std::vector<float> piled(100 * 100, 0.2f);
  for (int r = 40; r < 100; ++r)
    for (int c = 0; c < 100; ++c) piled[std::size_t(r) * 100 + c] = 0.3f;
  g.set_heights({0, 0, 100, 100}, piled.data());
  const Segment edge{{0.3, 0.15, 0.4}, {0.7, 0.15, 0.4}};
  const Vec3 v{0.0, 0.0, 0.5};
  const double look = depth_lookahead_m(g.spec());
  const SoilAhead a = soil_ahead(g, Representation::kSurface, edge, v, look);
  EXPECT_NEAR(a.depth_m, 0.05, 1e-6);  // below the undisturbed surface
  EXPECT_NEAR(a.pile_m, 0.1, 1e-6);
  // depth_ahead_m alone would read the pile as depth.
  EXPECT_NEAR(depth_ahead_m(g, Representation::kSurface, edge, v, look), 0.15, 1e-6);
  // No horizontal motion: nothing ahead.
  EXPECT_EQ(soil_ahead(g, Representation::kSurface, edge, {0.0, -1.0, 0.0}, look).depth_m, 0.0);
}

}  // namespace
}  // namespace terracut::haptics
