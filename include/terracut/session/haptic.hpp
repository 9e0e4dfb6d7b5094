// Haptic runs of a scenario, assembled once here for every program:
//
//  - HapticRig: the scenario's world (simulation + listeners, world.hpp) and
//    a HapticLoop over it, with the loop's parameters validated once
//    (haptics::LoopParams) and a device of the caller's. The viewer builds
//    its rig with its own virtual device.
//  - HapticSession: what `terracut haptics` does: a device backend from the
//    settings (script, sim, udp), a rig, the loop run for a duration, and
//    its outputs:
//
//   haptics.csv   one row per tick (haptics/haptics_csv.hpp; docs/haptics.md)
//   bodies.csv    only when the scenario has bodies
//   summary.json  settings used, loop timing percentiles, missed deadlines,
//                 counters (loop, safety, rejected packets by reason), forces,
//                 cutting totals and warnings, and the bodies' entry
#pragma once

#include <atomic>
#include <filesystem>
#include <iosfwd>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "terracut/haptics/settings.hpp"
#include "terracut/haptics/device.hpp"
#include "terracut/haptics/loop.hpp"
#include "terracut/haptics/script_device.hpp"
#include "terracut/session/scenario.hpp"
#include "terracut/session/world.hpp"

namespace terracut::session {

/// Which cuts a device follows (indices into scenario.base.cuts, in order):
/// the one settings.cut names, or else every cut of the scenario's
/// sequence. Empty when the named cut is not in the scenario or the
/// scenario has none (followed_path says which). The one answer of the
/// device factory, the MMT stations' starting orientation and
/// terracut-device.
std::vector<int> followed_cuts(const Scenario& scenario, const haptics::HapticSettings& settings);

/// The path a scripted or simulated device follows (`terracut haptics`, the
/// MMT operator): the cut named by haptics.cut, or else every cut of the
/// scenario's sequence, played as `terracut run` steps them (the tool
/// lifted between them) by the script device; the sim hand, a hand that
/// cannot jump between strokes, follows only the first. source: the name
/// errors give; rate_hz: the loop's rate, nullopt: the scenario's rate_hz.
/// Throws InputError "SOURCE: haptics.cut: ..." when the cut named is not in
/// the scenario or the scenario has none.
haptics::DevicePath followed_path(const Scenario& scenario, const haptics::HapticSettings& settings,
                                  const std::string& source,
                                  std::optional<double> rate_hz = std::nullopt);

/// The device of settings.device over the scenario (the one factory every
/// program uses): script or sim along followed_path, or the UDP bridge at
/// settings.udp (udp_port: the port to bind, 0 for any free one); rate_hz
/// as followed_path's. Throws InputError as followed_path.
std::unique_ptr<haptics::Device> make_device(const Scenario& scenario,
                                             const haptics::HapticSettings& settings, int udp_port,
                                             const std::string& source,
                                             std::optional<double> rate_hz = std::nullopt);

/// How a rig is built.
struct RigOptions {
  /// The loop's options (ticks, records, real time, clock, snapshot). Its
  /// `bodies` is set by the rig from the world.
  haptics::LoopOptions loop;
  /// bodies.csv of the world's bodies; empty: not written.
  std::filesystem::path bodies_csv;
  /// The arm's force limit at the tool, N (WorldOptions::arm_force_limit_n); 0 = none.
  double arm_force_limit_n = 0.0;
};

/// A haptic loop over a scenario's world.
class HapticRig {
 public:
  /// params: the loop's parameters (validated once, by their constructor);
  /// the world's simulation runs at params.rate_hz(). default_orientation:
  /// the tool orientation when neither the settings nor the device give one.
  /// The device must outlive the rig. Throws InputError naming the field.
  HapticRig(const Scenario& scenario, const haptics::LoopParams& params,
            Quat default_orientation, haptics::Device& device, const RigOptions& options);
  ~HapticRig();

  World& world() { return *world_; }
  const World& world() const { return *world_; }
  haptics::HapticLoop& loop() { return *loop_; }
  const haptics::HapticLoop& loop() const { return *loop_; }

  /// What the device check of the force model changed, one sentence each
  /// (e.g. "forces.surface.stiffness_n_per_m lowered to ..."); empty when
  /// nothing was lowered.
  std::vector<std::string> rendering_changes() const;

 private:
  std::unique_ptr<World> world_;
  std::unique_ptr<haptics::HapticLoop> loop_;
};

/// How the loop is clocked.
enum class ClockMode {
  kReal,  ///< its own thread, paced at the rate by the wall clock
  kFake,  ///< synchronous, no sleeping, t = i / rate (reproducible)
};

/// Command-line choices over the scenario's settings.
/// Silence after which SessionOptions::end_with_device ends a session, seconds:
/// well past the watchdog's default 0.05 s and any network hiccup.
inline constexpr double kDeviceEndSilence_s = 0.5;

struct SessionOptions {
  std::optional<haptics::DeviceKind> device;        ///< overrides haptics.device
  std::optional<std::string> udp_address;  ///< overrides haptics.udp.address
  std::optional<int> udp_port;             ///< overrides haptics.udp.port (0: any free port)
  std::optional<double> duration_s;        ///< overrides haptics.duration_s, (0, 86400]
  /// Overrides the scenario's rate_hz for the session's loop and its
  /// simulation, Hz, in haptics::kLoopRateRange (`terracut haptics --rate`).
  std::optional<double> rate_hz;
  /// nullopt: kFake for script, kReal for sim and udp. kFake with udp is refused.
  std::optional<ClockMode> clock;
  bool realtime = true;  ///< ask for SCHED_FIFO and locked memory (kReal)
  /// Records kept, at most; a longer session keeps its newest records.
  std::size_t max_records = 600000;
  std::ostream* log = nullptr;           ///< one-line messages (e.g. &std::cerr), or nullptr
  haptics::SnapshotExchange* snapshot = nullptr;  ///< optional viewer feed
  /// Where bodies.csv goes when the scenario has bodies (the folder must
  /// exist); empty: not written.
  std::filesystem::path bodies_csv;
  /// End the session when the device stops sending: after its first sample,
  /// kDeviceEndSilence_s without one (a UDP device whose own session ended).
  /// The duration still bounds the session.
  bool end_with_device = false;
  /// Polled every 10 ms while a real-time loop runs; true stops it (e.g. set by SIGINT).
  const std::atomic<bool>* interrupt = nullptr;
};

/// A built, ready-to-run session of `terracut haptics`.
class HapticSession {
 public:
  /// Builds the device and the rig. Throws InputError naming the field or
  /// option (an unknown cut, a port in use, udp with the fake clock, ...).
  HapticSession(const Scenario& scenario, const SessionOptions& options);
  ~HapticSession();

  /// Runs the loop to its end (or an interrupt). Call once.
  void run();

  /// Writes haptics.csv and summary.json into out_dir (created if missing),
  /// after closing the world's files (bodies.csv). Throws InputError naming
  /// the file when it cannot be written.
  void write_outputs(const std::filesystem::path& out_dir);

  /// One line: device, ticks, jitter and compute p99, max force, warnings.
  std::string summary_line() const;

  const haptics::HapticLoop& loop() const { return rig_->loop(); }
  const World& world() const { return rig_->world(); }
  const haptics::Device& device() const { return *device_; }
  /// The UDP device's bound port (udp only; -1 otherwise).
  int udp_port() const;
  haptics::DeviceKind device_kind() const { return kind_; }
  ClockMode clock() const { return clock_; }
  double duration_s() const { return duration_s_; }
  /// Warnings collected at build and after the run (rendering limited,
  /// real-time refused, bad samples, missed deadlines, ...): summary.json's.
  std::vector<std::string> warnings() const;
  /// What the device check changed at build (said once on SessionOptions::log
  /// when the session is built).
  const std::vector<std::string>& build_warnings() const { return build_warnings_; }
  /// The warnings the run found (warnings() less build_warnings()): what a
  /// program says at the end.
  std::vector<std::string> run_warnings() const;
  /// summary.json's text.
  std::string summary_json() const;

 private:
  std::filesystem::path source_;
  std::string name_;
  std::string cut_name_;
  haptics::DeviceKind kind_ = haptics::DeviceKind::kSim;
  ClockMode clock_ = ClockMode::kReal;
  double duration_s_ = 0.0;
  SessionOptions options_;
  std::vector<std::string> build_warnings_;
  std::unique_ptr<haptics::Device> device_;
  std::unique_ptr<HapticRig> rig_;
  double wall_s_ = 0.0;
  bool interrupted_ = false;
};

}  // namespace terracut::session
