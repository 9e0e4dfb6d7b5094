// The `mmt:` section of a scenario: the settings of model-mediated
// teleoperation (session/mmt.hpp; docs/teleoperation.md), and its reader.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string>

#include "terracut/core/forces.hpp"
#include "terracut/core/ranges.hpp"
#include "terracut/io/scenario.hpp"
#include "terracut/net/emulator.hpp"

namespace terracut::session {

/// The `mmt:` section. Read-only during a run.
struct MmtSettings {
  /// The remote world: a scenario file (resolved against the operator's
  /// scenario's folder); empty: the operator's own scenario.
  std::filesystem::path remote_scenario;
  /// Replaces the remote's soil material (its scenario's soil:) when given.
  std::optional<SoilPreset> remote_soil;
  /// Largest speed of the remote tool following the commands, m/s, (0, 100].
  double follower_speed_m_per_s = 1.5;
  /// Time constant of the remote tool's servo toward the command, s, [0, 10]
  /// (0: it reaches each command at once, within the speed limit).
  double follower_time_constant_s = 0.02;
  /// Period of the remote's terrain sensing and estimate updates, s, (0, 10].
  double sense_period_s = 0.05;
  /// Half side of the square sensed around the remote tool, m, (0, 100].
  double sense_radius_m = 0.3;
  /// The remote estimates the soil factor and sends it.
  bool estimate = true;
  /// RLS forgetting factor, (0, 1].
  double forgetting = 0.999;
  /// Conditions operator -> remote and remote -> operator.
  net::LinkConditions to_remote{};
  net::LinkConditions to_operator{};
  /// Time over which a patch is blended into the local terrain, s, [0, 10]
  /// (0: at once).
  double blend_s = 0.1;
  /// Largest change of the device force an estimate update may cause per
  /// tick, device N, (0, 100].
  double max_update_step_n = 0.01;
  /// While the operator's tool is in contact, patches leave the samples
  /// within this distance of its edge (horizontally) for later, m, [0, 100].
  double exclusion_m = 0.15;
  /// Perceptual deadband: send an update only when it changes the predicted
  /// force by more than this fraction, [0, 1); 0 sends every change.
  double deadband = 0.0;
  /// Silence after which a station stops (remote holds, operator fades), s, (0, 60].
  double timeout_s = 0.2;
  /// Two processes: silence after which the link is dead, s, (timeout_s,
  /// 3600]: the operator ends its session with an error (exit code 4), and
  /// the remote lets another operator open a session. A shorter silence
  /// (a network drop) is survived: the operator reconnects and resumes.
  double link_lost_s = 5.0;
  /// Identifies the pair of stations: packets of another link are "foreign".
  std::uint32_t link_id = 0x31504354u;
  /// Two-process mode: the remote listens here (IPv4); the operator connects.
  std::string address = "127.0.0.1";
  int port = 47100;  ///< [1, 65535]
};

/// Empty when valid, else a message starting with the field's path.
std::string validate(const MmtSettings& s);
/// The ranges of the `mmt:` section's own numbers, by their paths in it
/// (core/ranges.hpp): validate() checks them, the reader reads link.seed and
/// link_id through them. link:'s conditions: net::link_ranges().
std::span<const Range> mmt_ranges();

/// Reads `mmt:` (registered by load_scenario).
class MmtReader final : public io::SectionReader {
 public:
  std::string_view key() const override { return "mmt"; }
  void read(const YAML::Node& value, const std::string& file) override;
  std::optional<MmtSettings> settings;
};

}  // namespace terracut::session
