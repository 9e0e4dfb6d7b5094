// A scenario with every section read, for the programs: the terrain,
// representation, rate, blade and cuts (the io layer's reader), the haptic
// loop's settings (`haptics:`, the haptics layer's reader) and the rigid
// bodies (`bodies:`, the Bullet layer's reader). Each section is read by the
// layer that owns it; the session layer puts them together once.
#pragma once

#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "terracut/core/bodies.hpp"
#include "terracut/haptics/settings.hpp"
#include "terracut/io/scenario.hpp"
#include "terracut/session/mmt_settings.hpp"

namespace terracut::session {

/// A loaded, validated scenario.
struct Scenario {
  /// Terrain, representation, step rate, blade and cuts (io/scenario.hpp).
  io::Scenario base;
  /// The `haptics:` section (docs/haptics.md), or HapticSettings' defaults.
  haptics::HapticSettings haptics{};
  /// The `bodies:` list (docs/bullet.md); empty when not given.
  std::vector<BodySpec> bodies;
  /// The `mmt:` section (docs/teleoperation.md); nullopt when not given.
  std::optional<MmtSettings> mmt;
};

/// Reads and validates a scenario file with all its sections. Throws
/// InputError ("FILE:LINE: field.path: what").
Scenario load_scenario(const std::filesystem::path& path);

/// Parses scenario text with all its sections as if it were the file
/// source_name (used in messages; relative image paths are resolved against
/// its folder). Throws InputError as load_scenario.
Scenario parse_scenario(const std::string& text, const std::filesystem::path& source_name);

/// Every ranged number of a scenario file, by its path from the file's top
/// level, in the file's units (angles in degrees): the io reader's table
/// (io::scenario_ranges()) and the tables of the structs the `haptics:`,
/// `bodies:` and `mmt:` sections fill ("haptics.safety.max_force_n",
/// "bodies[].mass_kg", "mmt.link.loss"), gathered from the layers that
/// declare them. The boundary tests and docs/scenarios.md's table of ranges
/// are generated from it.
std::span<const Range> scenario_ranges();

/// A bare heightmap as a scenario (the viewer's PNG input): the image at its
/// own resolution over extent_m x extent_m, a white pixel full_scale_m high,
/// a blade half the extent long, no cuts, default haptic settings. Throws
/// InputError naming the file, or e.g. "--extent must be > 0, got 0".
Scenario heightmap_scenario(const std::filesystem::path& png, double extent_m,
                            double full_scale_m);

}  // namespace terracut::session
