// The world a run builds from a scenario (session::World): the piles of
// soil that flows press on the bodies with the scenario's own soil material
// (soil:), the one every force reads.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "terracut/session/scenario.hpp"
#include "terracut/session/world.hpp"
#include "../support/scenario_text.hpp"

#ifdef TERRACUT_HAVE_BULLET
#include "terracut/bullet/bodies_listener.hpp"
#endif

namespace terracut::session {
namespace {

namespace fs = std::filesystem;

const fs::path kRockPush = fs::path(TERRACUT_SOURCE_DIR) / "scenarios" / "rock_push.yaml";

std::string rock_push_text() { return test::read_text(kRockPush); }

#ifdef TERRACUT_HAVE_BULLET
// The unit weight the piles of scenarios/rock_push.yaml (soil: flow, a rock)
// press with when its soil material is `material` (the soil: section's
// preset line replaced).
double pile_unit_weight(const std::string& material) {
  const std::string text = test::replace(rock_push_text(), "preset: dry_sand", material);
  const World world(parse_scenario(text, kRockPush));
  EXPECT_NE(world.bodies_listener(), nullptr);
  const bullet::PilePressureSpec& pile = world.bodies_listener()->world().params().pile;
  EXPECT_TRUE(pile.enabled);
  return pile.unit_weight_n_per_m3;
}

TEST(World, PilesPressWithTheScenariosSoilUnitWeight) {
  EXPECT_EQ(pile_unit_weight("preset: dry_sand"), soil_preset(SoilPreset::kDrySand).unit_weight_n_per_m3);
  EXPECT_EQ(pile_unit_weight("preset: clay"), soil_preset(SoilPreset::kClay).unit_weight_n_per_m3);
  EXPECT_EQ(pile_unit_weight("unit_weight_n_per_m3: 18000"), 18000.0);
}
#endif

}  // namespace
}  // namespace terracut::session
