// A scenario with all its sections: each section is read by the reader of
// the layer that owns it (bodies:, haptics:), and its errors still name the
// file and the line.
#include "terracut/session/scenario.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "../support/scenario_text.hpp"
#include "terracut/core/error.hpp"

namespace terracut::session {
namespace {

namespace fs = std::filesystem;

using test::line_of;
using test::replace;

// Expects an InputError naming the file, the line and the field, with a fragment.
void expect_error(const std::string& text, int line, const std::string& field,
                  const std::string& fragment) {
  std::string message;
  try {
    parse_scenario(text, "/some/folder/bad.yaml");
  } catch (const InputError& e) {
    message = e.what();
  }
  const std::string where = "/some/folder/bad.yaml:" + std::to_string(line) + ": ";
  EXPECT_EQ(message.rfind(where, 0), 0u) << "message: " << message << "\nexpected start: " << where;
  EXPECT_NE(message.find(field), std::string::npos) << "message: " << message;
  EXPECT_NE(message.find(fragment), std::string::npos) << "message: " << message;
}

const std::string kGood = R"(name: small
terrain: {generator: plane, resolution: 8, size_m: [1.0, 1.0], full_scale_m: 0.2}
blade: {length_m: 0.5}
cuts:
  - name: A
    keyframes:
      - {t_s: 0.0, position_m: [0.5, 0.1, 0.0]}
      - {t_s: 0.5, position_m: [0.5, 0.1, 1.0]}
)";

TEST(ScenarioBodies, BodiesAreParsedAndTheirErrorsNameFileAndLine) {
  const std::string text = kGood + R"(bodies:
  - name: rock
    shape: sphere
    radius_m: 0.1
    mass_kg: 2
    position_m: [0.0, 0.4, 3.5]
)";
  const Scenario sc = parse_scenario(text, "/some/folder/bad.yaml");
  ASSERT_EQ(sc.bodies.size(), 1u);
  EXPECT_EQ(sc.bodies[0].name, "rock");
  EXPECT_EQ(sc.bodies[0].shape, BodyShape::kSphere);
  EXPECT_DOUBLE_EQ(sc.bodies[0].radius_m, 0.1);
  const std::string bad = replace(text, "radius_m: 0.1\n", "radius_m: -0.1\n");
  expect_error(bad, line_of(bad, "radius_m: -0.1"), "bodies[0]", "radius_m");
  EXPECT_TRUE(parse_scenario(kGood, "x.yaml").bodies.empty());
}

TEST(ScenarioSections, EachSectionIsReadByItsOwnLayer) {
  // The haptics section by the haptics reader; absent, its defaults.
  const Scenario plain = parse_scenario(kGood, "x.yaml");
  EXPECT_EQ(plain.haptics.settle_s, haptics::HapticSettings{}.settle_s);
  const Scenario with = parse_scenario(kGood + "haptics: {settle_s: 2, device: script}\n", "x.yaml");
  EXPECT_EQ(with.haptics.settle_s, 2.0);
  EXPECT_EQ(with.haptics.device, haptics::DeviceKind::kScript);
  // A key no layer reads is refused, and the message lists every section.
  const std::string unknown = kGood + "soil_typo: 1\n";
  expect_error(unknown, line_of(unknown, "soil_typo"), "soil_typo", "haptics");
  // An error inside a section names the section's field at its line.
  const std::string bad = kGood + "haptics:\n  settle_s: -1\n";
  expect_error(bad, line_of(bad, "settle_s: -1"), "haptics.settle_s", "[0, 3600]");
  // The loop's rate is the scenario's one rate_hz: the old key names its home.
  const std::string old = kGood + "haptics:\n  rate_hz: 500\n";
  expect_error(old, line_of(old, "rate_hz: 500"), "haptics.rate_hz", "moved to the top-level rate_hz");
}

// Every shipped scenario loads, with all its sections.
TEST(ShippedScenarios, EveryScenarioFileLoads) {
  int count = 0;
  for (const auto& entry : fs::directory_iterator(fs::path(TERRACUT_SOURCE_DIR) / "scenarios")) {
    if (entry.path().extension() != ".yaml") continue;
    EXPECT_NO_THROW(load_scenario(entry.path())) << entry.path();
    ++count;
  }
  EXPECT_GE(count, 3);
}

// docs/scenario-format.md lists every shipped scenario, one row each (a new
// user reads there what each is for).
TEST(ShippedScenarios, EveryScenarioFileIsListedInTheFormatDoc) {
  const std::string doc =
      test::read_text(fs::path(TERRACUT_SOURCE_DIR) / "docs" / "scenario-format.md");
  ASSERT_FALSE(doc.empty());
  for (const auto& entry : fs::directory_iterator(fs::path(TERRACUT_SOURCE_DIR) / "scenarios")) {
    if (entry.path().extension() != ".yaml") continue;
    const std::string row = "| `" + entry.path().filename().string() + "` | ";
    EXPECT_NE(doc.find(row), std::string::npos) << "docs/scenario-format.md has no row " << row;
  }
}

}  // namespace
}  // namespace terracut::session
