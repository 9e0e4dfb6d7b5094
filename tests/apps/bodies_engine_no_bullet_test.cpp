// apps/terracut/bodies_engine.cpp compiled as a build without Bullet has it
// (no TERRACUT_HAVE_BULLET): a scenario with bodies is refused with a message
// that says why and what to do, before any loop is built.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "bodies_engine.hpp"
#include "terracut/core/error.hpp"
#include "terracut/haptics/session.hpp"

namespace terracut::apps {
namespace {

TEST(BodiesEngineWithoutBullet, IsNotAvailable) { EXPECT_FALSE(bodies_engine_available()); }

TEST(BodiesEngineWithoutBullet, AScenarioWithBodiesIsRefusedWithAClearMessage) {
  const haptics::HapticScenario input = haptics::load_haptic_scenario(
      std::filesystem::path(TERRACUT_SOURCE_DIR) / "scenarios/rock_push.yaml");
  ASSERT_FALSE(input.scenario.bodies.empty());
  try {
    (void)make_bodies_engine(input.scenario.bodies, {});
    FAIL() << "a build without Bullet made a bodies engine";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_EQ(m, bodies_engine_unavailable_message());
    // What is wrong (bodies need Bullet), and what to do about it.
    for (const char* word : {"bodies", "built without Bullet", "libbullet-dev", "rebuild"})
      EXPECT_NE(m.find(word), std::string::npos) << word << " in: " << m;
  }
}

}  // namespace
}  // namespace terracut::apps
