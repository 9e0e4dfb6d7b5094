// A haptic session: a scenario with a `haptics:` section, a device backend,
// the loop run for a duration, and its outputs (what `terracut haptics` does):
//
//   haptics.csv   one row per tick (columns in kHapticsCsvColumns; docs/haptics.md)
//   summary.json  settings used, loop timing percentiles, missed deadlines,
//                 counters (loop, safety, rejected packets by reason), forces,
//                 cutting totals and warnings, and the engine's entry (e.g.
//                 "bodies") when SessionOptions::engine has one
#pragma once

#include <atomic>
#include <filesystem>
#include <iosfwd>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "terracut/core/haptic_settings.hpp"
#include "terracut/haptics/loop.hpp"
#include "terracut/io/scenario.hpp"

namespace terracut::haptics {

/// The columns of haptics.csv, in order.
inline constexpr const char* kHapticsCsvColumns =
    "t,tick,dev_x,dev_y,dev_z,tool_x,tool_y,tool_z,qw,qx,qy,qz,contact_length,cut_depth,"
    "removed_volume,vel_x,vel_y,vel_z,fw_x,fw_y,fw_z,fb_x,fb_y,fb_z,fd_x,fd_y,fd_z,clamped,"
    "rate_limited,watchdog,ramping,nonfinite,bad_sample,silent,missed_deadline,period,compute";

/// A scenario and its haptics settings.
struct HapticScenario {
  io::Scenario scenario;
  HapticSettings haptics;
};

/// Reads a scenario file with its `haptics:` section (the defaults when the
/// section is absent). Throws InputError ("FILE:LINE: field: what").
HapticScenario load_haptic_scenario(const std::filesystem::path& path);

/// How the loop is clocked.
enum class ClockMode {
  kReal,  ///< its own thread, paced at the rate by the wall clock
  kFake,  ///< synchronous, no sleeping, t = i / rate (reproducible)
};

/// Command-line choices over the scenario's settings.
struct SessionOptions {
  std::optional<DeviceKind> device;        ///< overrides haptics.device
  std::optional<std::string> udp_address;  ///< overrides haptics.udp.address
  std::optional<int> udp_port;             ///< overrides haptics.udp.port (0: any free port)
  std::optional<double> duration_s;        ///< overrides haptics.duration_s, (0, 86400]
  /// nullopt: kFake for script, kReal for sim and udp. kFake with udp is refused.
  std::optional<ClockMode> clock;
  bool realtime = true;  ///< ask for SCHED_FIFO and locked memory (kReal)
  /// Records kept, at most; a longer session keeps its newest records.
  std::size_t max_records = 600000;
  std::ostream* log = nullptr;           ///< one-line messages (e.g. &std::cerr), or nullptr
  SnapshotExchange* snapshot = nullptr;  ///< optional viewer feed
  /// Optional engine stepped with the simulation (LoopEngine, e.g. rigid
  /// bodies); must outlive the session. write_outputs() calls its finish()
  /// and summary.json holds its entry.
  LoopEngine* engine = nullptr;
  /// Polled every 10 ms while a real-time loop runs; true stops it (e.g. set by SIGINT).
  const std::atomic<bool>* interrupt = nullptr;
};

/// A built, ready-to-run session.
class Session {
 public:
  /// Builds the device and the loop. Throws InputError naming the field or
  /// option (an unknown cut, a port in use, udp with the fake clock, ...).
  Session(const HapticScenario& input, const SessionOptions& options);
  ~Session();

  /// Runs the loop to its end (or an interrupt). Call once.
  void run();

  /// Writes haptics.csv and summary.json into out_dir (created if missing),
  /// after finishing the engine (its own files, e.g. bodies.csv, are the
  /// engine's). Throws InputError naming the file when it cannot be written.
  void write_outputs(const std::filesystem::path& out_dir) const;

  /// One line: device, ticks, jitter and compute p99, max force, warnings.
  std::string summary_line() const;

  const HapticLoop& loop() const { return *loop_; }
  const Device& device() const { return *device_; }
  /// The UDP device's bound port (udp only; -1 otherwise).
  int udp_port() const;
  DeviceKind device_kind() const { return kind_; }
  ClockMode clock() const { return clock_; }
  double duration_s() const { return duration_s_; }
  /// Warnings collected at build and after the run (rendering limited,
  /// real-time refused, bad samples, missed deadlines, ...).
  std::vector<std::string> warnings() const;
  /// summary.json's text.
  std::string summary_json() const;

 private:
  std::filesystem::path source_;
  std::string name_;
  std::string cut_name_;
  DeviceKind kind_ = DeviceKind::kSim;
  ClockMode clock_ = ClockMode::kReal;
  double duration_s_ = 0.0;
  SessionOptions options_;
  std::vector<std::string> build_warnings_;
  std::unique_ptr<Device> device_;
  std::unique_ptr<HapticLoop> loop_;
  double wall_s_ = 0.0;
  bool interrupted_ = false;
};

/// A parsed --device value: "script", "sim", "udp", "udp:PORT",
/// "udp:ADDR:PORT" or "udp:[IPV6]:PORT".
struct DeviceOption {
  DeviceKind kind = DeviceKind::kSim;
  std::optional<std::string> address;  ///< given with udp
  std::optional<int> port;             ///< given with udp, in [0, 65535] (0: any free port)
};
/// Throws InputError naming --device when the text is none of the forms above.
DeviceOption parse_device_option(std::string_view text);

/// Parses "ADDR:PORT", "PORT" or "[IPV6]:PORT" (the part after "udp:"), for
/// --device and terracut-device's --connect. Throws InputError naming option.
void parse_endpoint(std::string_view text, std::string_view option,
                    std::optional<std::string>& address, std::optional<int>& port);

/// Writes records as haptics.csv text (kHapticsCsvColumns, then one row per record).
void write_haptics_csv(std::ostream& out, const std::vector<LoopRecord>& records);

}  // namespace terracut::haptics
