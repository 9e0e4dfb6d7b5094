// The session layer built as a build without Bullet has it (no
// TERRACUT_HAVE_BULLET; the library terracut_session_nobullet): a scenario
// with bodies is refused with a message that says why and what to do, before
// any loop is built.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "terracut/core/error.hpp"
#include "terracut/session/world.hpp"

namespace terracut::session {
namespace {

TEST(BodiesEngineWithoutBullet, IsNotAvailable) { EXPECT_FALSE(bodies_available()); }

TEST(BodiesEngineWithoutBullet, AScenarioWithBodiesIsRefusedWithAClearMessage) {
  const Scenario input =
      load_scenario(std::filesystem::path(TERRACUT_SOURCE_DIR) / "scenarios/rock_push.yaml");
  ASSERT_FALSE(input.bodies.empty());
  try {
    World world(input);
    FAIL() << "a build without Bullet made a world with bodies";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_EQ(m, bodies_unavailable_message());
    // What is wrong (bodies need Bullet), and what to do about it.
    for (const char* word : {"bodies", "built without Bullet", "libbullet-dev", "rebuild"})
      EXPECT_NE(m.find(word), std::string::npos) << word << " in: " << m;
  }
}

}  // namespace
}  // namespace terracut::session
