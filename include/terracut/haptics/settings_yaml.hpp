// The `haptics:` section of a scenario file -> HapticSettings
// (terracut/haptics/settings.hpp). Every key is optional; what is not
// given keeps the default of HapticSettings. Full reference: docs/haptics.md.
//
//   haptics:
//     device: sim                    # script | sim | udp
//     cut: trench                    # cut followed by script/sim (default: first of the sequence)
//     duration_s: 6                  # default: the cut's duration + settle_s (udp: 30)
//     settle_s: 0.5
//     workspace: {scale: 12, offset_m: [0.5, 0.1, 1.0], yaw_deg: 0}
//     tool: {rotation_deg: [0, 0, 0]}   # fixed tool orientation (default: from the device)
//     velocity_cutoff_hz: 100        # low-pass on the velocity estimate, 0 = off
//     surface_reference: ground      # ground | terrain
//     cut_depth: ahead               # ahead | section (depth given to the earthmoving model)
//     forces:
//       cutting: earthmoving         # none | contact_drag | earthmoving
//       force_scale: 0.02            # device N per world N
//       low_speed_damping_n_s_per_m: 60
//       project_width_on_motion: true
//       twist_enabled: true            # resistance to turning the buried blade
//       penetration: {enabled: true, edge_thickness_m: 0.02}
//       policy: clamp                # clamp | refuse
//       contact_drag: {drag_n_per_m: 400, viscous_n_s_per_m2: 0}
//       earthmoving:
//         soil: dry_sand             # a preset, or a mapping: {preset: dry_sand,
//                                    #   unit_weight_n_per_m3, cohesion_pa, adhesion_pa,
//                                    #   internal_friction_deg, soil_tool_friction_deg,
//                                    surcharge_pa}
//         rake_angle_deg: 90
//       surface: {enabled: true, stiffness_n_per_m: 10000, damping_n_s_per_m: 1}
//       device: {max_force_n: 8, max_stiffness_n_per_m: 3000, max_damping_n_s_per_m: 20,
//                inherent_damping_n_s_per_m: 1.5}
//     safety: {max_force_n: 8, max_force_rate_n_per_s: 1000, rise_time_s: 1,
//              watchdog_timeout_s: 0.05, watchdog_ramp_s: 0.1}
//     hand: {mass_kg: 0.15, stiffness_n_per_m: 400, damping_n_s_per_m: 8, substeps: 20,
//            start_offset_m: [0, 0, 0]}
//     udp: {address: 127.0.0.1, port: 47000}
//
// safety.max_force_n defaults to forces.device.max_force_n. Angles are in
// degrees in the file (radians in the structs).
#pragma once

#include <filesystem>
#include <string>

#include "terracut/haptics/settings.hpp"
#include "terracut/io/scenario.hpp"

namespace YAML {
class Node;
}

namespace terracut::haptics {

/// Parses the value of a scenario's `haptics:` key (a mapping; null gives the
/// defaults). `file` names the scenario in error messages. Every error is a
/// terracut::InputError reading "FILE:LINE: haptics.field: what is wrong"
/// (LINE 1-based): unknown or repeated keys, wrong types, out-of-range values
/// (validate(HapticSettings)). The result passes validate(HapticSettings).
HapticSettings parse_haptics(const YAML::Node& node, const std::string& file);

/// Reads only the `haptics:` key of a scenario file (the rest of the file is
/// not checked); the defaults when the key is absent. Throws InputError
/// ("FILE: ..." or "FILE:LINE: ...") when the file cannot be read or is not
/// valid YAML, or as parse_haptics.
HapticSettings load_haptics(const std::filesystem::path& scenario_path);

/// The `haptics:` section's reader for io::load_scenario: after the load,
/// settings holds the section (parse_haptics), or the defaults when the file
/// has none.
class SettingsReader final : public io::SectionReader {
 public:
  std::string_view key() const override { return "haptics"; }
  void read(const YAML::Node& value, const std::string& file) override {
    settings = parse_haptics(value, file);
  }
  HapticSettings settings{};
};

}  // namespace terracut::haptics
