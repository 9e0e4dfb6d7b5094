// The `haptics:` section reader: defaults, every block, units (degrees in the
// file, radians in the structs) and errors that name the file, line and field.
#include "terracut/haptics/settings_yaml.hpp"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>

#include "terracut/core/error.hpp"

namespace terracut::haptics {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

HapticSettings parse(const std::string& text) {
  const YAML::Node root = YAML::Load(text);
  return parse_haptics(root["haptics"], "test.yaml");
}

// The message of the InputError that parsing text throws ("" if none).
std::string error_of(const std::string& text) {
  try {
    parse(text);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(HapticsYaml, EmptySectionGivesTheDefaults) {
  const HapticSettings s = parse("haptics:\n");
  const HapticSettings d;
  EXPECT_EQ(s.device, DeviceKind::kSim);
  EXPECT_EQ(s.safety.max_force_n, d.forces.device.max_force_n);
  EXPECT_EQ(s.forces.cutting, d.forces.cutting);
  EXPECT_EQ(s.udp.address, "127.0.0.1");
  EXPECT_FALSE(s.duration_s.has_value());
  EXPECT_FALSE(s.tool_rotation_deg.has_value());
  EXPECT_EQ(validate(s), "");
}

TEST(HapticsYaml, ReadsEveryBlock) {
  const HapticSettings s = parse(R"(
haptics:
  device: udp
  cut: pass2
  duration_s: 12.5
  settle_s: 0.25
  workspace: {scale: 12, offset_m: [0.5, 0.1, -0.2], yaw_deg: -90}
  tool: {rotation_deg: [0, 30, 0]}
  velocity_cutoff_hz: 50
  surface_reference: terrain
  forces:
    cutting: earthmoving
    force_scale: 0.01
    low_speed_damping_n_s_per_m: 80
    policy: refuse
    contact_drag: {drag_n_per_m: 300, viscous_n_s_per_m2: 2}
    surface: {enabled: false, stiffness_n_per_m: 9000, damping_n_s_per_m: 3}
    device: {max_force_n: 6, max_stiffness_n_per_m: 2000, max_damping_n_s_per_m: 10,
             inherent_damping_n_s_per_m: 2}
  safety: {max_force_rate_n_per_s: 500, rise_time_s: 0, watchdog_timeout_s: 0.1,
           watchdog_ramp_s: 0.2}
  hand: {mass_kg: 0.3, stiffness_n_per_m: 250, damping_n_s_per_m: 4, substeps: 10,
         start_offset_m: [0, 0.01, 0]}
  udp: {address: "::1", port: 50001}
)");
  EXPECT_EQ(s.device, DeviceKind::kUdp);
  EXPECT_EQ(s.cut, "pass2");
  EXPECT_EQ(*s.duration_s, 12.5);
  EXPECT_EQ(s.settle_s, 0.25);
  EXPECT_EQ(s.workspace.scale, 12.0);
  EXPECT_EQ(s.workspace.offset_m.z, -0.2);
  EXPECT_EQ(s.workspace.yaw_deg, -90.0);
  EXPECT_EQ(s.tool_rotation_deg->y, 30.0);
  EXPECT_EQ(s.velocity_cutoff_hz, 50.0);
  EXPECT_EQ(s.surface_reference, SurfaceReference::kTerrain);
  EXPECT_EQ(s.forces.cutting, CuttingModel::kEarthmoving);
  EXPECT_EQ(s.forces.force_scale, 0.01);
  EXPECT_EQ(s.forces.low_speed_damping_n_s_per_m, 80.0);
  EXPECT_EQ(s.forces.policy, LimitPolicy::kRefuse);
  EXPECT_EQ(s.forces.contact_drag.drag_n_per_m, 300.0);
  EXPECT_EQ(s.forces.contact_drag.viscous_n_s_per_m2, 2.0);
  EXPECT_FALSE(s.forces.surface_enabled);
  EXPECT_EQ(s.forces.surface.stiffness_n_per_m, 9000.0);
  EXPECT_EQ(s.forces.device.max_force_n, 6.0);
  EXPECT_EQ(s.forces.device.inherent_damping_n_s_per_m, 2.0);
  // safety.max_force_n follows the device's maximum when not given.
  EXPECT_EQ(s.safety.max_force_n, 6.0);
  EXPECT_EQ(s.safety.rise_time_s, 0.0);
  EXPECT_EQ(s.safety.watchdog_ramp_s, 0.2);
  EXPECT_EQ(s.hand.mass_kg, 0.3);
  EXPECT_EQ(s.hand.substeps, 10);
  EXPECT_EQ(s.hand.start_offset_m.y, 0.01);
  EXPECT_EQ(s.udp.address, "::1");
  EXPECT_EQ(s.udp.port, 50001);
}

// A file of the old layout, where the soil's material and the blade's shape
// were haptic settings, is refused at the field, naming where it went.
TEST(HapticsYaml, TheOldLayoutNamesTheNewField) {
  EXPECT_NE(error_of("haptics:\n  forces:\n    earthmoving:\n      soil: loose_sand\n")
                .find("test.yaml:4: haptics.forces.earthmoving.soil: moved to the top-level soil: section"),
            std::string::npos);
  EXPECT_NE(error_of("haptics:\n  forces:\n    earthmoving:\n      rake_angle_deg: 60\n")
                .find("haptics.forces.earthmoving.rake_angle_deg: moved to blade.rake_angle_deg"),
            std::string::npos);
  EXPECT_NE(error_of("haptics:\n  forces:\n    penetration: {edge_thickness_m: 0.01}\n")
                .find("moved to blade.edge_thickness_m"),
            std::string::npos);
  EXPECT_NE(error_of("haptics:\n  cut_depth: section\n").find("haptics.cut_depth: removed"),
            std::string::npos);
  EXPECT_NE(error_of("haptics:\n  forces:\n    project_width_on_motion: false\n")
                .find("project_width_on_motion: removed"),
            std::string::npos);
  // The loop's rate is the scenario's one rate_hz: the old key names it.
  EXPECT_NE(error_of("haptics:\n  rate_hz: 500\n")
                .find("test.yaml:2: haptics.rate_hz: moved to the top-level rate_hz"),
            std::string::npos);
}

TEST(HapticsYaml, ErrorsNameFileLineAndField) {
  // Unknown key, at its own line.
  EXPECT_EQ(error_of("haptics:\n  settle_s: 1\n  rat_hz: 3\n")
                .rfind("test.yaml:3: haptics.rat_hz: unknown key 'rat_hz'", 0),
            0u);
  // Wrong type.
  EXPECT_NE(error_of("haptics:\n  workspace:\n    scale: big\n")
                .find("test.yaml:3: haptics.workspace.scale: expected a number, got 'big'"),
            std::string::npos);
  // A list of the wrong length.
  EXPECT_NE(error_of("haptics:\n  workspace: {offset_m: [1, 2]}\n")
                .find("haptics.workspace.offset_m: expected a list of 3 numbers"),
            std::string::npos);
  // Unknown enumerated values list the allowed ones.
  EXPECT_NE(
      error_of("haptics:\n  device: falcon\n")
          .find("test.yaml:2: haptics.device: unknown value 'falcon'; allowed: script, sim, udp"),
      std::string::npos);
  EXPECT_NE(error_of("haptics:\n  forces: {cutting: drag}\n")
                .find("allowed: none, contact_drag, earthmoving"),
            std::string::npos);
  // Out of range (found by validate), reported at the field's line.
  EXPECT_NE(error_of("haptics:\n  hand:\n    mass_kg: 0.1\n    stiffness_n_per_m: -5\n")
                .find("test.yaml:4: haptics.hand.stiffness_n_per_m: must be finite and > 0"),
            std::string::npos);
  EXPECT_NE(error_of("haptics:\n  settle_s: -1\n").find("test.yaml:2: haptics.settle_s: must be"),
            std::string::npos);
  // Nested force fields keep their path.
  EXPECT_NE(error_of("haptics:\n  forces:\n    surface:\n      stiffness_n_per_m: -1\n")
                .find("test.yaml:4: haptics.forces.surface.stiffness_n_per_m: must be"),
            std::string::npos);
  // safety.max_force_n above the device's maximum.
  EXPECT_NE(error_of("haptics:\n  safety: {max_force_n: 9}\n")
                .find("haptics.safety.max_force_n: must not exceed forces.device.max_force_n"),
            std::string::npos);
  // A repeated key.
  EXPECT_NE(error_of("haptics:\n  settle_s: 1\n  settle_s: 2\n").find("key given twice"),
            std::string::npos);
  // Not a mapping.
  EXPECT_NE(error_of("haptics: [1, 2]\n").find("haptics: expected a mapping"), std::string::npos);
  // A fraction where a whole number is needed.
  EXPECT_NE(error_of("haptics:\n  hand: {substeps: 2.5}\n").find("expected a whole number"),
            std::string::npos);
  EXPECT_NE(error_of("haptics:\n  forces: {twist_enabled: maybe}\n")
                .find("expected true or false"),
            std::string::npos);
}

TEST(HapticsYaml, LoadHapticsReadsTheTrenchScenario) {
  const HapticSettings s =
      load_haptics(std::filesystem::path(TERRACUT_SOURCE_DIR) / "scenarios/trench_dry_sand.yaml");
  EXPECT_EQ(s.device, DeviceKind::kSim);
  EXPECT_EQ(s.cut, "trench");
  EXPECT_EQ(s.forces.cutting, CuttingModel::kEarthmoving);
  EXPECT_EQ(s.forces.policy, LimitPolicy::kRefuse);
  EXPECT_EQ(s.workspace.scale, 15.0);
  EXPECT_EQ(validate(s), "");
}

TEST(HapticsYaml, LoadHapticsErrors) {
  const auto dir = std::filesystem::temp_directory_path() / "terracut_haptics_yaml_test";
  std::filesystem::create_directories(dir);
  // No haptics key: the defaults.
  {
    std::ofstream(dir / "none.yaml") << "name: x\n";
    EXPECT_EQ(load_haptics(dir / "none.yaml").settle_s, HapticSettings{}.settle_s);
  }
  // Malformed YAML: the file and line.
  {
    std::ofstream(dir / "bad.yaml") << "name: x\nhaptics: {settle_s: [\n";
    try {
      load_haptics(dir / "bad.yaml");
      ADD_FAILURE() << "no error";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("bad.yaml:"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("not valid YAML"), std::string::npos) << e.what();
    }
  }
  // A missing file.
  EXPECT_THROW(load_haptics(dir / "missing.yaml"), InputError);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace terracut::haptics
