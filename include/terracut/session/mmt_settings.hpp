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
  /// A change of the remote's soil along the path: where the remote
  /// blade's centre is at z below change_z_m the remote's soil is
  /// change_soil (a line across the trench; the failure wedge is not split).
  std::optional<SoilPreset> change_soil;
  double change_z_m = 0.0;  ///< world m, finite
  /// The remote estimates its soil's material (core/soil_estimator.hpp) and
  /// sends it.
  bool estimate = true;
  /// Forgetting of the estimate per loop tick, (0, 1]: a memory of about
  /// 1 / (1 - forgetting) ticks (0.999: a second at 1 kHz).
  double forgetting = 0.999;
  /// The estimate takes a sample of the physical cutting force every
  /// estimate_period_s, s, [loop period, 1]; the work on one sample is
  /// spread over the ticks to the next.
  double estimate_period_s = 0.01;
  /// The estimate travels unreliably, newest wins (a lost one is not
  /// waited for): besides every change it goes out again when none has gone
  /// for estimate_resend_s, so that a lost one is replaced within that
  /// time even when the deadband sends nothing new, s, (0, 60].
  double estimate_resend_s = 0.5;
  /// The largest force the remote's arm exerts, N, (0, 1e7]: when the tool
  /// force on it exceeds this the arm stalls (holds its pose) instead of
  /// pushing on. 1e7: no limit.
  double arm_force_limit_n = 1e7;
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
  /// The operator's local model moves its tool as the remote's arm moves
  /// its own: the same first-order servo (follower_time_constant_s) and
  /// speed limit (follower_speed_m_per_s) toward the hand, so that both
  /// blades make the same motion (the command sent is the hand's pose).
  /// false: the local tool is the hand.
  bool models_arm = true;
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
