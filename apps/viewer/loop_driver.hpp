// The viewer's session with the haptic loop: builds the scenario's haptic rig
// (session::HapticRig: the world with its step listeners, and the loop, as
// `terracut haptics` builds them) with the viewer's virtual device
// (viewer_device.hpp) and a haptics::SnapshotExchange, and runs it on the
// loop's thread. The drawing
// thread only acquires frames from the exchange (wait-free) and posts
// controls and targets to the device (atomics, a wait-free mailbox): it never
// blocks the loop.
//
// Two ways to run:
//  - paced (the window, the benchmark): HapticLoop::start(), its own thread
//    at the loop rate with absolute deadlines (and SCHED_FIFO / locked memory
//    where the system permits);
//  - lock-step (headless screenshots): a thread of this class ticks the loop
//    (step1 at t = i / rate, step2), as fast as it can, up to the tick the
//    drawing thread asks for, then waits; frame k shows exactly the state
//    after the ticks it asked for, the same on every run.
//
// MMT (DriverOptions::mmt, `terracut-viewer --mmt`): the scenario's `mmt:`
// section runs as teleoperation: the viewer's device drives the operator
// station (session::OperatorStation) on the local model, the remote station
// (its own world: soil, terrain and hidden bodies the operator does not
// know) runs in the same thread over the emulated link (delay, jitter, loss),
// and the frames show the local model as the remote's patches correct it.
// Both ways to run tick the two stations in turn on this class's thread
// (paced: at the loop rate by absolute deadlines). MmtLive carries the
// link's figures to the panel. With DriverOptions::remote the remote station
// is another process (`terracut mmt --role remote`) over UDP: only the
// operator station ticks here, on the wall clock in both ways to run (the
// remote does not wait for lock-step), and the panel's loss and rejections
// are the operator's side's.
//
// A scenario with rigid bodies (`bodies:`) gets the world's Bullet listener
// (the one `terracut run` and `terracut haptics` use): the bodies are stepped
// with the terrain, their force on the blade joins the force, and every
// frame carries their poses.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "terracut/haptics/settings.hpp"
#include "terracut/haptics/loop.hpp"
#include "terracut/haptics/snapshot.hpp"
#include "terracut/io/scenario.hpp"
#include "terracut/net/secure.hpp"
#include "terracut/net/transport.hpp"
#include "terracut/session/haptic.hpp"
#include "terracut/session/mmt.hpp"
#include "terracut/session/mmt_process.hpp"
#include "viewer_device.hpp"

namespace terracut::viewer {

/// How the session runs.
struct DriverOptions {
  bool paced = true;                       ///< real time (true) or lock-step (false)
  ToolSource source = ToolSource::kScript;
  bool playing = true;                     ///< the device's clock starts running
  double speed = 1.0;                      ///< device clock per loop second, [0, 16]
  bool pause_at_end = true;                ///< stop playing when the script ends
  /// Loop records kept (the newest), for the loop's own percentiles after
  /// stop(); 0 keeps none.
  std::size_t record_capacity = 0;
  bool realtime = true;                    ///< paced: ask for SCHED_FIFO and locked memory
  /// The script is the benchmark's plough (plough_tour) instead of the
  /// scenario's cut sequence.
  bool plough = false;
  /// Teleoperation: run the scenario's `mmt:` section (operator and remote
  /// stations over the emulated link) instead of the plain haptic loop.
  bool mmt = false;
  /// With mmt: the remote station is another process (`terracut mmt
  /// --role remote`) at this "ADDR:PORT" or "PORT" (IPv4), reached over UDP
  /// with the scenario's mmt.link conditions at this sender; empty: the
  /// remote runs here over the emulated in-memory link.
  std::string remote;
  /// How long to wait for that remote station to answer, s.
  double connect_timeout_s = 5.0;
  /// With remote: the key both stations share (net::insecure_key() for
  /// --insecure-loopback).
  net::LinkKey key;
};

/// The teleoperation link as the panel shows it, written by the driver's
/// thread after every tick, read by the drawing thread.
struct MmtLive {
  std::atomic<double> rtt_s{0.0};             ///< newest measured round trip (wall clock), s
  std::atomic<double> emulated_rtt_s{0.0};    ///< the emulator's delays, both ways, s
  /// Commands that did not reach the remote over about the last second.
  std::atomic<double> command_loss{0.0};
  /// With a remote in another process: UDP datagrams dropped before the
  /// station (no peer's, oversize, by the kernel) and peers refused.
  std::atomic<std::int64_t> udp_dropped{0};
  std::atomic<std::int64_t> peers_refused{0};
  std::atomic<double> loss_to_remote{0.0};    ///< datagrams lost / sent, operator -> remote
  std::atomic<double> loss_to_operator{0.0};  ///< datagrams lost / sent, remote -> operator
  std::atomic<std::int64_t> patches{0};       ///< patches merged by the operator
  std::atomic<std::int64_t> estimates{0};     ///< soil estimates applied
  std::atomic<std::int64_t> rejected{0};      ///< datagrams rejected, both stations
  /// RMS over the last second of |local model's force - remote's newest
  /// measured force|, world N (not time-aligned: the live view; the study's
  /// aligned figure is `terracut mmt`'s).
  std::atomic<double> force_error_rms_n{0.0};
  std::atomic<double> remote_force_n{0.0};  ///< |remote's newest measured force|, world N
  /// The material of the operator's model (moving to the remote's
  /// estimate) and the remote's newest estimate with its standard
  /// uncertainties, by SoilField (unit weight N/m^3, cohesion Pa, adhesion
  /// Pa, phi deg, delta deg); identifiable: SoilEstimate's bits.
  std::array<std::atomic<double>, 5> material_applied{};
  std::array<std::atomic<double>, 5> estimate{};
  std::array<std::atomic<double>, 5> estimate_sd{};
  std::atomic<std::uint32_t> identifiable{0};
  std::atomic<bool> link_silent{false};
};

class LoopDriver {
 public:
  /// Throws InputError naming the field when the scenario or settings are
  /// invalid (the haptic loop's checks, including a refused force rendering).
  /// timing: where the device records the loop's period and compute time
  /// (paced mode; may be shared by successive sessions), or nullptr.
  /// settings: the haptic settings to run with (the viewer's, which may
  /// differ from scenario.haptics after the panel's edits).
  LoopDriver(const session::Scenario& scenario, const haptics::HapticSettings& settings,
             const DriverOptions& options, LoopTiming* timing);
  ~LoopDriver();
  LoopDriver(const LoopDriver&) = delete;
  LoopDriver& operator=(const LoopDriver&) = delete;

  void start();
  /// Stops and joins the loop's thread (idempotent); the loop's results
  /// (loop().period() etc.) may be read afterwards.
  void stop();
  /// With a remote station in another process: tells it the session is
  /// over (it ends, as when `terracut mmt --role operator` finishes). After
  /// stop(); nothing otherwise.
  void end_session();

  // --- fixed after construction ---
  const GridSpec& spec() const { return spec_; }
  Representation representation() const { return representation_; }
  double rate_hz() const { return params_.rate_hz(); }
  double blade_length_m() const { return blade_length_m_; }
  /// The blade's bucket (BucketSpec::enabled() false for a flat blade).
  const BucketSpec& bucket() const { return bucket_; }
  /// The blade's top above its edge, metres (infinity: unbounded).
  double blade_height_m() const { return blade_height_m_; }
  /// The soil's angle of repose, degrees (what a tilted bucket holds).
  double repose_deg() const { return repose_deg_; }
  /// Initial heights, rows x cols, row-major, metres.
  const std::vector<float>& initial_heights() const { return initial_; }
  /// The loop's force model (const after construction).
  const ForceModel& force_model() const { return params_.force_model(); }
  /// The settings in use (validated, derived fields filled in).
  const haptics::HapticSettings& settings() const { return params_.settings(); }
  const Tour& tour() const { return tour_; }
  /// Ticks that play the whole script once: round(duration * rate) + 1.
  std::int64_t script_ticks() const { return script_ticks_; }

  haptics::SnapshotExchange& exchange() { return *exchange_; }
  ViewerDevice& device() { return *device_; }
  /// The loop (the operator station's in MMT); its results only after stop().
  const haptics::HapticLoop& loop() const;
  /// How the loop's thread is scheduled, in the words `terracut haptics`
  /// uses ("real-time: SCHED_FIFO priority 80, ..."); in MMT the stations
  /// tick on this driver's own thread, which asks for no real-time.
  std::string realtime_line() const;
  /// Teleoperation: the stations run (DriverOptions::mmt).
  bool mmt() const { return operator_ != nullptr; }
  /// The link's figures (zeros when not mmt()).
  const MmtLive& mmt_live() const { return mmt_live_; }
  /// MMT: the stations, for the tests (read them only while stopped, or
  /// in lock-step after ticks_done() reached the target).
  const session::OperatorStation* operator_station() const { return operator_.get(); }
  const session::RemoteStation* remote_station() const { return remote_.get(); }
  /// Rigid bodies of the scenario (simulated by the world's listener).
  int body_count() const { return int(scenario_.bodies.size()); }

  /// Lock-step: run until `ticks` ticks are done in all.
  void run_until_tick(std::int64_t ticks) { target_ticks_.store(ticks); }
  /// Lock-step: ticks done, counted once the tick's frame is published.
  std::int64_t ticks_done() const { return ticks_done_.load(); }

 private:
  void lockstep_main();
  void paced_mmt_main();
  void tick(std::int64_t i);  // tick i (t = i / rate) of the loop or of both stations
  void publish_mmt();

  session::Scenario scenario_;  // the Tour points into its cuts
  haptics::LoopParams params_;
  DriverOptions options_;
  GridSpec spec_;
  Representation representation_;
  double blade_length_m_;
  double blade_height_m_;
  BucketSpec bucket_{};
  double repose_deg_ = 34.0;
  std::vector<float> initial_;
  Tour tour_;
  std::int64_t script_ticks_ = 0;
  std::unique_ptr<haptics::SnapshotExchange> exchange_;
  std::unique_ptr<ViewerDevice> device_;
  std::unique_ptr<session::HapticRig> rig_;  // after the device, which it uses
  // MMT: the remote world, the link and the two stations (instead of rig_).
  std::unique_ptr<session::Scenario> remote_scenario_;
  std::unique_ptr<net::EmulatedLink> link_;
  session::UdpLink udp_;  // DriverOptions::remote: the link to the other process
  std::unique_ptr<session::OperatorStation> operator_;
  std::unique_ptr<session::RemoteStation> remote_;
  MmtLive mmt_live_;
  double error_ms_n2_ = 0.0;  // running mean of the squared force error, N^2

  std::thread lockstep_thread_;
  std::atomic<bool> lockstep_running_{false};
  std::atomic<std::int64_t> target_ticks_{0};
  std::atomic<std::int64_t> ticks_done_{0};
  bool started_ = false;
};

/// How high above the soil the mouse tool is put down, metres: 2 % of the
/// terrain's tallest height or half a cell, whichever is more.
double mouse_clearance_m(const GridSpec& spec, double max_height_m);

/// The options a Reset opens the next session with: the same as the
/// previous ones, with the device's tool source and speed, and playing only
/// if it was playing (a paused viewer stays paused through a Reset).
DriverOptions reset_options(const DriverOptions& previous, const ViewerDevice& device);

/// The haptic settings the viewer uses: the scenario's `haptics:` section (or
/// the defaults), with a fixed tool rotation dropped (the viewer's device
/// gives the orientation, so the keys can turn the tool).
haptics::HapticSettings viewer_settings(haptics::HapticSettings settings);

}  // namespace terracut::viewer
