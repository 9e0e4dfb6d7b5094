// Model-mediated teleoperation (MMT): two stations joined by a delayed,
// lossy link (net/), built from a scenario's `mmt:` section
// (docs/teleoperation.md).
//
//  - RemoteStation: the "real" world, a terracut world of its own (its own
//    scenario: terrain, soil, hidden bodies). Its tool follows the
//    operator's commands at a limited speed (a real arm lags); it measures
//    the tool force and pose every tick and, every sensing period, the
//    heights around the tool and those it changed (a dirty rectangle, sent
//    reliably as a zstd patch), and it estimates its soil's material from
//    its physical cutting force (core/soil_estimator.hpp), sent with its
//    uncertainty.
//  - OperatorStation: the haptic loop (HapticRig) on the local model with a
//    device of the caller's. It sends the tool pose every tick and merges
//    what comes back without force jumps: patches blend in over blend_s,
//    its model's material moves to the remote's estimate at a bounded rate
//    of force change.
//  - MmtRun: both stations in one process over an in-memory link, stepped
//    in lock-step at the loop rate in simulated time (reproducible for a
//    seed), with per-tick records, the summary of `terracut mmt`, and its
//    outputs.
// Safety: a station that hears nothing for timeout_s stops: the remote
// tool holds still, and the operator's device is reported silent to its
// loop, whose watchdog fades the force out.
#pragma once

#include <cstdint>
#include <filesystem>
#include <iosfwd>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "terracut/core/forces.hpp"
#include "terracut/core/soil_estimator.hpp"
#include "terracut/core/wire.hpp"
#include "terracut/core/stats.hpp"
#include "terracut/haptics/device.hpp"
#include "terracut/io/recording.hpp"
#include "terracut/io/scenario.hpp"
#include "terracut/net/emulated_link.hpp"
#include "terracut/net/emulator.hpp"
#include "terracut/net/messages.hpp"
#include "terracut/net/transport.hpp"
#include "terracut/session/haptic.hpp"
#include "terracut/session/mmt_settings.hpp"

namespace terracut::session {

/// The remote world of a scenario with an `mmt:` section (its remote
/// scenario loaded, the soil override applied). Throws InputError naming
/// mmt.remote.scenario when it cannot be loaded or its grid differs.
Scenario load_remote_scenario(const Scenario& operator_scenario);

/// One remote tick.
struct RemoteRecord {
  double t_s = 0.0;
  std::uint32_t command_sequence = 0;  ///< newest command followed
  Vec3 commanded_m{};                  ///< its position, world
  Vec3 tool_m{};                       ///< the follower's position, world
  /// Measured force on the tool: the physical force (StepOutput::force),
  /// world N; nothing rendered, nothing capped.
  Vec3 force_world_n{};
  double contact_length_m = 0.0;
  double cut_depth_m = 0.0;
  /// The estimate of the soil at this tick (its material and uncertainty).
  SoilEstimate estimate{};
  /// |H(estimate) - H| / H at this tick's cut: how far the estimate's
  /// horizontal cutting force is from the one measured; -1 without a cut.
  double estimate_error = -1.0;
  bool in_changed_soil = false;  ///< the remote blade is in mmt.remote.soil_change's soil
  bool stalled = false;          ///< the arm's force limit held the tool
  bool holding = false;      ///< link silent: holding still
  bool active = false;       ///< a command has arrived
  double compute_s = 0.0;    ///< the whole tick (receiving, the loop, sensing, sending), s
};

/// One operator tick.
struct OperatorRecord {
  double t_s = 0.0;
  Vec3 tool_m{};               ///< commanded tool position, world
  Vec3 device_m{};             ///< device handle, device frame
  /// The local model's physical force (MMT's prediction of the remote's),
  /// world N: StepOutput::force, nothing rendered or capped.
  Vec3 force_world_n{};
  Vec3 force_device_n{};       ///< rendered, device frame, device N
  Vec3 remote_force_world_n{}; ///< newest measured force received (direct reflection), world N
  double contact_length_m = 0.0;
  /// The material the local model's force uses (moving to the remote's
  /// estimate), and how far along its blend from the previous one, [0, 1].
  SoilMaterial material{};
  double material_blend = 1.0;
  bool updating = false;      ///< an update was being merged this tick
  bool link_silent = false;
  double passivity_j = 0.0;      ///< energy into the hand over the last window, MMT, J
  double passivity_dfr_j = 0.0;  ///< the same for direct force reflection, J
  double compute_s = 0.0;        ///< the whole tick (receiving, merging, the loop, sending), s
  std::uint32_t command_sequence = 0;  ///< the command sent this tick
  double round_trip_s = 0.0;   ///< newest measured round trip, s (0: none yet)
  double command_loss = 0.0;   ///< commands the remote did not receive over about the last second, fraction
};

/// Counts of what a station received.
struct StationCounters {
  net::RejectCounts rejected{};
  std::int64_t accepted = 0;
  std::int64_t patches = 0;    ///< patches sent (remote) / merged (operator)
  std::int64_t estimates = 0;  ///< estimates sent / applied
  std::int64_t sessions = 0;   ///< sessions of the peer seen
  std::int64_t silent_ticks = 0;
};

class FollowerDevice;
class LinkGuardDevice;
class ArmModelDevice;
class MaterialBlend;

/// What a remote station does beyond its settings.
struct RemoteOptions {
  /// One record per tick (records()); false: only the newest
  /// (last_record()), for a session without a set end (the viewer's, the
  /// live stations of `terracut mmt --role`, which stream them to a file).
  bool keep_records = true;
};

class RemoteStation {
 public:
  /// remote: the remote world (load_remote_scenario); nominal: the
  /// operator's soil material (where the soil estimate starts); mirror: the
  /// operator's initial heights (what the deadband compares against).
  /// Throws InputError naming the field.
  RemoteStation(const Scenario& remote, const MmtSettings& settings,
                const SoilMaterial& nominal, const HeightGrid& operator_initial,
                net::Endpoint& link, std::uint32_t session, const RemoteOptions& options = {});
  ~RemoteStation();
  /// One tick at station time t_s. Allocates nothing in steady state once
  /// the records have room (reserve_records) and the link's buffers have
  /// met their working sizes.
  void tick(double t_s);
  /// Room for `ticks` records, made now.
  void reserve_records(std::size_t ticks) { records_.reserve(ticks); }

  const std::vector<RemoteRecord>& records() const { return records_; }
  /// The newest tick's record (kept with or without keep_records).
  const RemoteRecord& last_record() const { return last_; }
  const StationCounters& counters() const { return counters_; }
  const Simulation& simulation() const;
  const HapticRig& rig() const { return *rig_; }
  /// Every sample the remote changed so far.
  const Rect& worked() const { return worked_; }
  /// The newest estimate of the soil.
  const SoilEstimate& estimate() const { return estimator_->estimate(); }
  /// The material the remote's force uses now (its soil, or soil_change's).
  const SoilMaterial& true_material() const;
  /// The remote's soil before mmt.remote.soil_change, and beyond it (the
  /// same without a change).
  const SoilMaterial& base_material() const { return base_material_; }
  const SoilMaterial& changed_material() const { return changed_material_; }
  /// Ticks the arm's force limit held the tool.
  std::int64_t stalled_ticks() const { return stalled_ticks_; }
  /// Packets sent that carried model updates (patches + estimates).
  std::int64_t update_packets() const { return counters_.patches + counters_.estimates; }
  /// Commands of the current operator session that arrived (accepted, or
  /// refused only as older than the newest: what each measurement reports
  /// back), and those the accepted sequence numbers skipped.
  std::int64_t commands_received() const { return commands_received_; }
  std::int64_t commands_missed() const { return commands_.lost(); }
  /// The round trip the operator measured and sent, s (0: none yet).
  double round_trip_s() const { return round_trip_s_; }
  /// When the newest command was accepted (station time), s.
  double last_command_s() const { return last_command_s_; }

 private:
  void receive(double t_s);
  void update_estimate();
  void choose_material();
  void sense(double t_s, const haptics::LoopRecord& r);
  void send_estimate(double t_s);
  Rect window_around(Vec3 p) const;

  MmtSettings settings_;
  net::Endpoint& link_;
  std::uint32_t session_;
  std::unique_ptr<FollowerDevice> device_;
  std::unique_ptr<HapticRig> rig_;
  std::vector<float> mirror_;  // what the operator was sent (starts as its initial heights)
  std::vector<float> sensed_;  // the sensed rectangle: soil, or a body's top over it
  wire::SequenceFilter commands_;
  std::int64_t commands_received_ = 0;  // in the current operator session
  double round_trip_s_ = 0.0;
  std::uint32_t command_sequence_ = 0;
  Vec3 commanded_m_{};
  bool has_command_ = false;
  double last_command_s_ = 0.0;
  std::uint32_t seq_measurement_ = 0, seq_patch_ = 0, seq_estimate_ = 0;
  double next_sense_s_ = 0.0;
  Rect dirty_{};
  Rect worked_{};
  std::unique_ptr<SoilEstimator> estimator_;
  int estimate_slice_ = 1;           // candidates per tick
  std::int64_t estimate_every_ = 1;  // ticks per sample
  std::int64_t ticks_ = 0;
  SoilMaterial sent_{};              // the material last sent
  bool estimate_sent_ = false;
  double estimate_sent_s_ = 0.0;     // when the estimate last went
  bool plate_limits_ = false;        // a force-limited Bullet plate holds the arm's limit
  SoilMaterial base_material_{}, changed_material_{};
  bool in_changed_soil_ = false;
  double estimate_error_ = -1.0;
  std::int64_t stalled_ticks_ = 0;
  SoilSample last_sample_{};  // the newest cut with a force
  bool has_sample_ = false;
  double previous_t_s_ = 0.0;
  bool ticked_ = false;
  std::vector<RemoteRecord> records_;
  RemoteRecord last_{};
  RemoteOptions options_;
  StationCounters counters_{};
  net::Inbox inbox_;
  std::vector<std::uint8_t> buffer_;
  net::Patch patch_;
  net::PatchCodec codec_;
};

/// What an operator station does beyond its settings.
struct OperatorOptions {
  /// The viewer's frame exchange: the loop publishes every tick's frame
  /// there, and each merged patch notes its rectangle, so that a drawing
  /// thread sees the remote's updates; nullptr: none.
  haptics::SnapshotExchange* snapshot = nullptr;
  /// One record per tick (records()); false: only the newest (last_record()),
  /// for a session without a set end (the viewer's, the live stations of
  /// `terracut mmt --role`, which stream them to a file).
  bool keep_records = true;
  /// Measure the round trip on the wall clock (a station in real time: its
  /// tick times may lag the wall clock's while it catches up); false: on the
  /// station's time (simulated time, where the wall clock means nothing).
  bool wall_clock = false;
};

class OperatorStation {
 public:
  /// The operator's haptic loop over op's world with device (which must
  /// outlive the station). Throws InputError naming the field.
  OperatorStation(const Scenario& op, const MmtSettings& settings, haptics::Device& device,
                  net::Endpoint& link, std::uint32_t session, const OperatorOptions& options = {});
  ~OperatorStation();
  /// One tick at station time t_s. Allocates nothing in steady state once
  /// the records have room (reserve_records) and the link's buffers and
  /// the pool of blends have met their working sizes.
  void tick(double t_s);
  /// Room for `ticks` records, made now.
  void reserve_records(std::size_t ticks) { records_.reserve(ticks); }

  const std::vector<OperatorRecord>& records() const { return records_; }
  /// The newest tick's record.
  const OperatorRecord& last_record() const { return last_; }
  /// The newest measured round trip: from sending a command to receiving
  /// the first measurement of the remote following it, s; 0 before one.
  double rtt_s() const { return rtt_s_; }
  /// The round trip a station must allow for: the largest measured over
  /// the last one to two seconds; before the first, the configured delays
  /// and jitters both ways. The protection window, the command's
  /// round_trip_us and the emulator's retransmissions use it.
  double round_trip_bound_s() const;
  bool round_trip_measured() const { return rtt_known_; }
  /// Commands sent; the newest command the remote followed and how many of
  /// the commands up to it it received (both from its newest measurement).
  std::int64_t commands_sent() const { return std::int64_t(seq_command_); }
  std::int64_t commands_followed() const { return ack_known_ ? std::int64_t(ack_sequence_) + 1 : 0; }
  std::int64_t commands_received_by_remote() const { return ack_received_; }
  /// Fraction of the commands up to the newest followed one that the remote
  /// did not receive: over the session, and over about the last second.
  double command_loss() const;
  double command_loss_recent() const { return loss_recent_; }
  /// When the newest datagram was accepted (station time), and whether any was.
  double last_heard_s() const { return last_heard_s_; }
  bool heard() const { return heard_; }
  /// Silences longer than timeout_s (the force faded), and the longest, s.
  std::int64_t silences() const { return silences_; }
  double longest_silence_s() const { return longest_silence_s_; }
  const StationCounters& counters() const { return counters_; }
  const HapticRig& rig() const { return *rig_; }
  const Simulation& simulation() const;
  const Rect& worked() const { return worked_; }
  /// Largest change of the device force an update caused in one tick,
  /// device N: the material's (bounded by max_update_step_n); terrain
  /// patches do not touch the samples the tool feels while in contact.
  double max_update_step_n() const { return max_update_step_n_; }
  /// Largest tick-to-tick change of the device force (whatever its cause:
  /// motion included) on ticks while an update was being merged, device N.
  double max_step_while_updating_n() const { return max_step_while_updating_n_; }
  /// The newest estimate received from the remote (its material, the
  /// uncertainty, what is identifiable); samples 0 before one.
  const net::Estimate& last_estimate() const { return last_estimate_; }
  /// Ticks of the run, duration (path + settle).
  std::int64_t ticks() const { return ticks_; }
  double rate_hz() const;

 private:
  struct Blend {
    Rect rect;
    std::vector<float> t0_s;  // per sample: when its ramp started, s
    std::vector<float> from, to, scratch;
    bool done = false;
  };
  void receive(double t_s);
  void merge(double t_s);
  void measure_link(double t_s);
  double round_trip_clock_s(double t_s) const;
  double protection_s() const;

  MmtSettings settings_;
  net::Endpoint& link_;
  std::uint32_t session_;
  std::unique_ptr<ArmModelDevice> arm_;  // the remote's arm in the local model (models_arm)
  std::unique_ptr<LinkGuardDevice> guard_;
  std::unique_ptr<HapticRig> rig_;
  std::unique_ptr<MaterialBlend> blend_;
  net::Estimate last_estimate_{};
  std::vector<float> stamp_s_;  // time each sample was last changed by the local tool
  double protect_s_ = 0.0;      // a local cut this recent is not yet in what the remote sends
  // The blends in arrival order: [0, active_blends_) are merging, the rest
  // are kept (with their buffers) for the next patches.
  std::vector<Blend> blends_;
  std::size_t active_blends_ = 0;
  wire::SequenceFilter measurements_, patches_, estimates_;
  std::uint32_t seq_command_ = 0;
  Vec3 remote_force_{};
  double last_heard_s_ = 0.0;
  bool heard_ = false;
  Rect worked_{};
  std::int64_t ticks_ = 0;
  double previous_t_s_ = 0.0;
  Vec3 previous_device_m_{};
  Vec3 previous_force_device_n_{};
  Vec3 previous_dfr_device_n_{};
  bool has_previous_ = false;
  std::vector<double> power_, power_dfr_;  // ring over the passivity window
  std::size_t power_at_ = 0;
  double window_j_ = 0.0, window_dfr_j_ = 0.0;
  double max_update_step_n_ = 0.0;
  double max_step_while_updating_n_ = 0.0;
  std::vector<OperatorRecord> records_;
  OperatorRecord last_{};
  OperatorOptions options_;
  // When each command was sent (station time, or the wall clock's with
  // OperatorOptions::wall_clock), s, by sequence modulo the ring's size.
  std::vector<double> command_sent_s_;
  std::uint32_t rtt_sequence_ = 0;  // the command the newest round trip is of
  double rtt_s_ = 0.0;
  bool rtt_known_ = false;
  // The largest round trip of the current and the previous second.
  double rtt_max_now_s_ = 0.0, rtt_max_before_s_ = 0.0, rtt_bucket_s_ = 0.0;
  // The remote's newest report: the command it follows, the commands it received.
  std::uint32_t ack_sequence_ = 0;
  std::int64_t ack_received_ = 0;
  bool ack_known_ = false;
  // The report as it was at each of the last second's ticks (ring by tick).
  std::vector<std::uint32_t> loss_sequence_;
  std::vector<std::int64_t> loss_received_;
  double loss_recent_ = 0.0;
  std::int64_t silences_ = 0;
  double longest_silence_s_ = 0.0;
  bool was_silent_ = false;
  StationCounters counters_{};
  net::Inbox inbox_;
  net::Patch patch_;
  net::PatchCodec codec_;
};

/// Command-line choices over the `mmt:` section.
struct MmtOverrides {
  std::optional<double> rtt_s;     ///< round trip: each way's delay = rtt / 2
  std::optional<double> loss;      ///< independent loss each way, [0, 1)
  std::optional<double> jitter_s;  ///< each way
  std::optional<std::uint64_t> seed;
  std::optional<double> deadband;
  std::optional<double> blend_s;
  std::optional<double> duration_s;
};
/// The settings with the overrides applied (validated). Throws InputError
/// naming the option.
MmtSettings apply_overrides(MmtSettings s, const MmtOverrides& o);

/// The figures of one run (summary.json), the same for both stations in
/// one process and for the report of two (write_two_process_report).
struct MmtSummary {
  double duration_s = 0.0;
  double rtt_s = 0.0;           ///< emulated round trip (the configured delays)
  double rtt_measured_s = 0.0;  ///< the operator's newest measured round trip
  double loss = 0.0;
  double deadband = 0.0;
  double force_rms_remote_n = 0.0;  ///< RMS of the remote's measured force
  double force_error_rms_mmt_n = 0.0;
  double force_error_max_mmt_n = 0.0;
  double force_error_rms_dfr_n = 0.0;  ///< direct force reflection
  double force_error_max_dfr_n = 0.0;
  /// Each operator tick meets the remote's tick that followed its command
  /// this much later (the remote arm's time constant), s.
  double aligned_after_s = 0.0;
  double terrain_rms_max_m = 0.0;    ///< local - remote over the worked region, largest
  double terrain_rms_final_m = 0.0;  ///< at the end
  double tracking_rms_m = 0.0;
  double tracking_max_m = 0.0;
  double packets_per_s_to_remote = 0.0, bytes_per_s_to_remote = 0.0;
  double packets_per_s_to_operator = 0.0, bytes_per_s_to_operator = 0.0;
  double update_packets_per_s = 0.0;
  std::int64_t patches = 0, estimates = 0;
  double max_update_step_n = 0.0;
  double max_step_while_updating_n = 0.0;
  double passivity_max_mmt_j = 0.0, passivity_max_dfr_j = 0.0;
  /// The force error after the first second of the remote's cutting (the
  /// study's targets): RMS of |F_op - F_remote| and of the remote's force
  /// over the ticks from the remote's first cut + 1 s on, N, and their
  /// ratio (-1 when the window holds less than 0.1 s of the remote
  /// cutting); the same for direct reflection. settle_excluded_s: a window
  /// after a change of soil left out (a round trip plus 0.5 s: the soil no
  /// model could know yet), 0 without one.
  double cutting_from_s = 0.0;
  double settle_excluded_from_s = 0.0, settle_excluded_to_s = 0.0;
  double force_rms_remote_after_1s_n = 0.0;
  double force_error_rms_mmt_after_1s_n = 0.0;
  double force_error_rms_dfr_after_1s_n = 0.0;
  double force_error_rel_mmt_after_1s = 0.0;
  double force_error_rel_dfr_after_1s = 0.0;
  /// The remote's final estimate and the material its force used then.
  SoilEstimate estimate{};
  SoilMaterial remote_material{};
  SoilMaterial material_applied{};  ///< what the operator's model used at the end
  /// For a change of soil: the time from the remote blade entering the new
  /// soil to the estimate's horizontal force staying within 5 % of the
  /// measured one (s; -1: never, or no change).
  double reidentified_after_s = -1.0;
  double arm_force_limit_n = 0.0;  ///< the remote arm's (mmt.remote.arm_force_limit_n)
  std::int64_t stalled_ticks = 0;  ///< ticks the remote arm's force limit held it
  std::int64_t patches_merged = 0, estimates_applied = 0;  ///< by the operator
  std::int64_t lost_to_remote = 0, lost_to_operator = 0;   ///< emulated losses
  net::RejectCounts rejected_operator{}, rejected_remote{};
  TimingStats operator_compute{}, remote_compute{};
};

/// The figures of a session that its two stations' records give: the force
/// errors (over the whole run and after the first second of cutting), the
/// remote's force, tracking, passivity, the material applied at the end,
/// the re-identification time of a change of soil and the tick timing,
/// into s (s.rtt_s set: a change of soil leaves out a round trip plus
/// 0.5 s). Each operator tick is compared with the remote's first tick that
/// followed its command or a newer one (the same commanded motion, by
/// command sequence: the measured delay, not a configured one), then
/// follower_lag_s later (the remote arm, a first-order servo, follows a
/// steady motion one time constant behind: 0 for none), over the ticks
/// where some force is felt or measured. rate_hz: the stations' tick rate.
void compare_records(const std::vector<OperatorRecord>& op, const std::vector<RemoteRecord>& rm,
                     double rate_hz, double follower_lag_s, MmtSummary& s);

/// "SCENARIO: mmt: the scenario has no mmt: section ...": the one refusal
/// of every MMT entry point.
std::string no_mmt_section(const Scenario& sc);

/// How long an operator station runs when no --duration is given, s: its
/// path (path_s), then a round trip (round_trip_s), a sensing period and a
/// blend for the last updates to land, and on a lossy link back three
/// retransmissions more (each retransmit_s). The one rule of the one-process
/// run (the emulated round trip) and of the operator process (the measured).
double mmt_run_length_s(const MmtSettings& settings, double path_s, double round_trip_s,
                        double retransmit_s);

/// The teleoperation pair of one process: the emulated link and both
/// stations on it.
struct StationPair {
  std::unique_ptr<net::EmulatedLink> link;
  std::unique_ptr<OperatorStation> operator_station;
  std::unique_ptr<RemoteStation> remote_station;
};
/// The pair as the single-process run and the viewer's operator mode build
/// it: the link of settings.to_remote and to_operator, the operator station
/// (session 1) over op's world with device, and the remote station (session
/// 2) in the remote world (load_remote_scenario), its estimate starting from
/// the operator's soil material and its deadband from the operator's
/// initial heights. device and remote must outlive the pair. Throws
/// InputError naming the field.
StationPair make_station_pair(const Scenario& op, const Scenario& remote, const MmtSettings& settings,
                              haptics::Device& device, const OperatorOptions& operator_options = {},
                              const RemoteOptions& remote_options = {});

/// Both stations in one process.
class MmtRun {
 public:
  /// Builds both stations over an in-memory link from a scenario with an
  /// `mmt:` section. Throws InputError naming the field.
  MmtRun(const Scenario& op, const MmtOverrides& overrides = {});
  ~MmtRun();
  /// Runs to the end: the operator's path and settle time, plus a round
  /// trip and the blend for the last updates to land.
  void run();
  /// Or one tick at a time (t = i / rate).
  void tick();
  std::int64_t ticks_run() const { return tick_; }
  std::int64_t total_ticks() const { return total_ticks_; }

  /// Figures over the run so far.
  MmtSummary summary() const;
  /// operator.csv, remote.csv, terrain_error.csv, summary.json into dir.
  void write_outputs(const std::filesystem::path& dir) const;

  const MmtSettings& settings() const { return settings_; }
  OperatorStation& operator_station() { return *operator_; }
  RemoteStation& remote_station() { return *remote_; }
  net::EmulatedLink& link() { return *link_; }
  /// RMS of local - remote heights over the worked region, sampled every 50 ms: (t, rms).
  const std::vector<std::pair<double, double>>& terrain_error() const { return terrain_error_; }

 private:
  double terrain_rms() const;
  MmtSettings settings_;
  std::unique_ptr<Scenario> op_, remote_scn_;
  std::unique_ptr<haptics::Device> device_;
  std::unique_ptr<net::EmulatedLink> link_;
  std::unique_ptr<OperatorStation> operator_;
  std::unique_ptr<RemoteStation> remote_;
  std::int64_t tick_ = 0, total_ticks_ = 0;
  double rate_hz_ = 1000.0;
  std::vector<std::pair<double, double>> terrain_error_;
  mutable std::vector<float> sensed_;  // terrain_rms's remote surface, reserved for the grid
};

/// The per-tick files (docs/teleoperation.md lists the columns). Throw
/// InputError naming the file when it cannot be written.
void write_operator_csv(const std::vector<OperatorRecord>& records,
                        const std::filesystem::path& path);
void write_remote_csv(const std::vector<RemoteRecord>& records, const std::filesystem::path& path);

/// The same files written a tick at a time, for a live station whose
/// records are not kept (an hour at 1 kHz is about 1.1 GB of them): the
/// header on opening, a row per add(), buffered (a write to the file about
/// every 400 rows; an io::CsvFile, the one CSV writer). Throws InputError
/// naming the file when it cannot be created, and from add() or finish()
/// when a write failed.
class StationCsv {
 public:
  static StationCsv operator_csv(const std::filesystem::path& path);
  static StationCsv remote_csv(const std::filesystem::path& path);
  void add(const OperatorRecord& r);
  void add(const RemoteRecord& r);
  /// Flushes and closes; checks that every row reached the file.
  void finish();
  StationCsv(StationCsv&&) noexcept;
  StationCsv& operator=(StationCsv&&) noexcept;
  ~StationCsv();

 private:
  StationCsv(const std::filesystem::path& path, const char* header);
  std::unique_ptr<io::CsvFile> file_;
};

/// The operator's device of an mmt run: the scenario's script, sim or udp
/// (bridge) device, haptics.device. repeat: the script device replays its
/// cut over and over (its duration and half a second a round; a soak's
/// hand). Throws InputError (e.g. a port in use, repeat with another device).
std::unique_ptr<haptics::Device> make_operator_device(const Scenario& op, bool repeat = false);
/// haptics.duration_s, else the operator's path plus settle_s (udp: 30 s), s.
double operator_duration_s(const Scenario& op);

}  // namespace terracut::session
