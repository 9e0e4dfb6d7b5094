#include "loop_driver.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "terracut/core/error.hpp"
#include "terracut/core/surface.hpp"
#include "terracut/session/mmt_process.hpp"

namespace terracut::viewer {

haptics::HapticSettings viewer_settings(haptics::HapticSettings settings) {
  settings.tool_rotation_deg.reset();
  return settings;
}

double mouse_clearance_m(const GridSpec& spec, double max_height_m) {
  return std::max(0.02 * max_height_m, 0.5 * std::min(spec.cell_x_m(), spec.cell_z_m()));
}

DriverOptions reset_options(const DriverOptions& previous, const ViewerDevice& device) {
  DriverOptions o = previous;
  o.source = device.source();
  o.speed = device.speed();
  o.playing = device.playing();
  return o;
}

LoopDriver::LoopDriver(const session::Scenario& scenario, const haptics::HapticSettings& settings,
                       const DriverOptions& options, LoopTiming* timing)
    : scenario_(scenario),
      params_(settings, scenario.base.blade, scenario.base.rate_hz),
      options_(options),
      spec_(io::grid_spec(scenario.base)),
      representation_(scenario.base.representation),
      blade_length_m_(scenario.base.blade.length_m),
      blade_height_m_(scenario.base.blade.height_m),
      bucket_(scenario.base.blade.bucket),
      repose_deg_(scenario.base.soil.material.repose_deg),
      initial_(io::build_initial_heights(scenario.base)) {
  // Transits between cuts rise above everything the blade could touch.
  float max_h = 0.0f;
  for (float h : initial_) max_h = std::max(max_h, h);
  const double extent = std::max(spec_.size_x_m, spec_.size_z_m);
  const double clearance = spec_.origin_m.y + double(max_h) + 0.5 * blade_length_m_ + 0.05 * extent;
  const double transit_speed = std::max(0.5 * extent, 0.2);
  if (options.plough) {
    tour_ = plough_tour(spec_, double(max_h), blade_length_m_, std::max(0.3 * extent, 0.1), 1000);
  } else {
    tour_ = Tour(scenario_.base, clearance, transit_speed);
  }
  script_ticks_ = tour_.empty() ? 0 : std::llround(tour_.duration_s() * params_.rate_hz()) + 1;

  // The tool starts at the script's first pose, or above the middle.
  BladePose start;
  if (!tour_.empty()) {
    start = tour_.sample(0.0);
  } else {
    // No script (a bare heightmap): just above the soil in the middle, so
    // the first scroll down digs.
    const double x = spec_.origin_m.x + 0.5 * spec_.size_x_m;
    const double z = spec_.origin_m.z + 0.5 * spec_.size_z_m;
    start.position_m = {x,
                        spec_.origin_m.y +
                            surface_height_m(spec_, initial_.data(), representation_, x, z) +
                            mouse_clearance_m(spec_, double(max_h)),
                        z};
  }

  {
    HeightGrid grid(spec_, initial_);
    exchange_ = std::make_unique<haptics::SnapshotExchange>(grid);
  }
  device_ = std::make_unique<ViewerDevice>(haptics::Workspace(params_.settings().workspace), tour_, start,
                                           rate_hz(), clearance, transit_speed,
                                           options.paced ? timing : nullptr);
  device_->set_playing(options.playing);
  device_->set_speed(options.speed);
  device_->set_source(options.source);
  device_->set_pause_at_end(options.pause_at_end);

  // The world (with the rigid bodies' listener, when the scenario has
  // bodies) and the loop over it.
  session::RigOptions ro;
  ro.loop.ticks = std::numeric_limits<std::int64_t>::max() / 2;  // until stop()
  ro.loop.record_capacity = options.record_capacity;
  ro.loop.realtime = options.realtime;
  ro.loop.lock_memory = false;  // the viewer's GL driver allocates; locking all memory is not ours
  ro.loop.snapshot = exchange_.get();
  if (options.mmt) {
    if (!scenario_.mmt) throw InputError("--mmt: " + session::no_mmt_section(scenario_));
    // The operator station runs the loop with the viewer's settings; the
    // remote world is the scenario's mmt.remote.
    session::Scenario op = scenario_;
    op.haptics = params_.settings();
    const session::MmtSettings& mmt = *scenario_.mmt;
    session::OperatorOptions oo;
    oo.snapshot = exchange_.get();
    oo.keep_records = false;
    oo.wall_clock = !options.remote.empty();
    if (!options.remote.empty()) {
      // The remote is another process; a new session id each start, as
      // `terracut mmt --role operator` has it.
      const std::uint32_t id = session::new_station_id();
      udp_ = session::connect_operator_link(mmt, options.remote, "--remote",
                                            options.connect_timeout_s, options.key, id);
      operator_ = std::make_unique<session::OperatorStation>(op, mmt, *device_, *udp_.endpoint, id, oo);
    } else {
      remote_scenario_ = std::make_unique<session::Scenario>(session::load_remote_scenario(op));
      session::StationPair pair =
          session::make_station_pair(op, *remote_scenario_, mmt, *device_, oo, session::RemoteOptions{false});
      link_ = std::move(pair.link);
      operator_ = std::move(pair.operator_station);
      remote_ = std::move(pair.remote_station);
    }
    mmt_live_.emulated_rtt_s.store(mmt.to_remote.delay_s + mmt.to_operator.delay_s);
  } else {
    rig_ = std::make_unique<session::HapticRig>(scenario_, params_, start.orientation, *device_, ro);
  }

  // The first frame shows the tool where it starts (the loop is not running
  // yet, so this thread may write).
  haptics::ViewFrame& f = exchange_->back();
  f.pose = start;
  f.edge = blade_segment(scenario_.base.blade, start);
  f.device_position_m = start.position_m;
  f.proxy_position_m = start.position_m;
  haptics::fill_bodies(f, (operator_ ? operator_->rig() : *rig_).world().bodies());  // where they start
  HeightGrid grid(spec_, initial_);
  exchange_->publish(grid);
}

LoopDriver::~LoopDriver() { stop(); }

const haptics::HapticLoop& LoopDriver::loop() const {
  return operator_ ? operator_->rig().loop() : rig_->loop();
}

std::string LoopDriver::realtime_line() const {
  if (operator_)
    return "real-time: not asked (teleoperation: the stations tick on the viewer's own thread, "
           "normal scheduling)";
  return loop().realtime_status().message;
}

void LoopDriver::start() {
  if (started_) return;
  started_ = true;
  if (options_.paced && operator_) {
    lockstep_running_.store(true);
    lockstep_thread_ = std::thread([this] { paced_mmt_main(); });
  } else if (options_.paced) {
    rig_->loop().start();
  } else {
    lockstep_running_.store(true);
    lockstep_thread_ = std::thread([this] { lockstep_main(); });
  }
}

void LoopDriver::stop() {
  if (!started_) return;
  if (options_.paced && !operator_) {
    rig_->loop().request_stop();
    rig_->loop().join();
  } else {
    lockstep_running_.store(false);
    if (lockstep_thread_.joinable()) lockstep_thread_.join();
  }
  started_ = false;
}

void LoopDriver::end_session() {
  if (udp_.carrier && !started_) udp_.carrier->end_session(0.5);
}

void LoopDriver::lockstep_main() {
  // A remote in another process runs on the wall clock: each tick waits for
  // its time (i / rate from the start), or the operator would run ahead, and
  // its time is the wall clock's (the round trip it measures is real).
  using Clock = std::chrono::steady_clock;
  const Clock::time_point start = Clock::now();
  std::int64_t i = 0;
  while (lockstep_running_.load(std::memory_order_relaxed)) {
    if (i >= target_ticks_.load()) {
      std::this_thread::sleep_for(std::chrono::microseconds(200));
      continue;
    }
    if (udp_.endpoint)
      std::this_thread::sleep_until(start + std::chrono::duration_cast<Clock::duration>(
                                                std::chrono::duration<double>(double(i) / rate_hz())));
    tick(i);
    ++i;
    ticks_done_.store(i);  // after step2 published the tick's frame
  }
}

// Tick i at t = i / rate exactly, as HapticLoop::run_deterministic does: the
// loop, or the operator station and then the remote.
void LoopDriver::tick(std::int64_t i) {
  using Clock = std::chrono::steady_clock;
  const double period = 1.0 / rate_hz();
  const double t_s = double(i) * period;
  if (operator_) {
    if (link_) link_->release(t_s);
    operator_->tick(t_s);
    if (remote_) remote_->tick(t_s);
    publish_mmt();
    return;
  }
  const Clock::time_point begin = Clock::now();
  rig_->loop().step1(t_s);
  const double compute = std::chrono::duration<double>(Clock::now() - begin).count();
  rig_->loop().step2(i == 0 ? 0.0 : period, compute, false);
}

// MMT in real time: both stations ticked at the loop rate, tick i at t =
// i / rate due at that time after the start; far behind (10 periods), the
// missed ticks are skipped and t jumps to the wall clock's, never drifting
// behind it (the stations' time held still while the drawing thread slowed
// the ticks, and the measured round trip read 68 ms for 100 ms emulated).
void LoopDriver::paced_mmt_main() {
  using Clock = std::chrono::steady_clock;
  Clock::time_point start = Clock::now();
  std::int64_t i = 0;
  while (lockstep_running_.load(std::memory_order_relaxed)) {
    // Paused with the remote in this process: both stations hold (their
    // time leaves the pause out), as the plain loop does. A remote in
    // another process runs on, so the operator keeps answering it.
    if (!udp_.endpoint && i > 0 && device_->paused()) {
      const Clock::time_point held = Clock::now();
      std::this_thread::sleep_for(std::chrono::duration<double>(haptics::HapticLoop::kPausePoll_s));
      start += Clock::now() - held;
      continue;
    }
    tick(i);
    ++i;
    ticks_done_.store(i);
    const double now_s = std::chrono::duration<double>(Clock::now() - start).count();
    if (now_s > double(i + 10) / rate_hz()) i = std::int64_t(now_s * rate_hz());
    std::this_thread::sleep_until(start + std::chrono::duration_cast<Clock::duration>(
                                              std::chrono::duration<double>(double(i) / rate_hz())));
  }
}

void LoopDriver::publish_mmt() {
  const session::OperatorRecord& r = operator_->last_record();
  const session::StationCounters& oc = operator_->counters();
  MmtLive& m = mmt_live_;
  const double err = length(r.force_world_n - r.remote_force_world_n);
  error_ms_n2_ += (err * err - error_ms_n2_) / rate_hz();  // about the last second
  m.force_error_rms_n.store(std::sqrt(error_ms_n2_), std::memory_order_relaxed);
  m.remote_force_n.store(length(r.remote_force_world_n), std::memory_order_relaxed);
  m.rtt_s.store(operator_->rtt_s(), std::memory_order_relaxed);
  m.command_loss.store(operator_->command_loss_recent(), std::memory_order_relaxed);
  if (udp_.carrier) {
    const net::EnetCounters& c = udp_.carrier->counters();
    m.udp_dropped.store(c.dropped_unknown_source + c.dropped_oversize + c.kernel_dropped,
                        std::memory_order_relaxed);
    m.peers_refused.store(c.refused_total(), std::memory_order_relaxed);
  }
  auto loss = [](const net::LinkEmulator& e) {
    const net::EmulatorCounters& c = e.counters();
    return c.datagrams > 0 ? double(c.lost) / double(c.datagrams) : 0.0;
  };
  // With the remote in another process, its sender's losses are its own.
  m.loss_to_remote.store(loss(udp_.endpoint ? udp_.endpoint->emulator() : link_->a().emulator()),
                         std::memory_order_relaxed);
  m.loss_to_operator.store(link_ ? loss(link_->b().emulator()) : 0.0, std::memory_order_relaxed);
  m.patches.store(oc.patches, std::memory_order_relaxed);
  m.estimates.store(oc.estimates, std::memory_order_relaxed);
  m.rejected.store(oc.rejected.total() + (remote_ ? remote_->counters().rejected.total() : 0),
                  std::memory_order_relaxed);
  const net::Estimate& e = operator_->last_estimate();
  for (int f = 0; f < kSoilFieldCount; ++f) {
    const std::size_t i = std::size_t(f);
    m.material_applied[i].store(field_value(r.material, SoilField(f)), std::memory_order_relaxed);
    m.estimate[i].store(field_value(e.material, SoilField(f)), std::memory_order_relaxed);
    m.estimate_sd[i].store(e.sd[i], std::memory_order_relaxed);
  }
  m.identifiable.store(e.identifiable, std::memory_order_relaxed);
  m.link_silent.store(r.link_silent, std::memory_order_relaxed);
}

}  // namespace terracut::viewer
