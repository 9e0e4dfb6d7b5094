// Haptic runs: the rig (world + loop) and the session of `terracut haptics`.
// See haptic.hpp.
#include "terracut/session/haptic.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <thread>

#include <nlohmann/json.hpp>

#include "bodies_json.hpp"
#include "terracut/core/error.hpp"
#include "terracut/core/format.hpp"
#include "terracut/haptics/haptics_csv.hpp"
#include "terracut/haptics/script_device.hpp"
#include "terracut/haptics/sim_hand.hpp"
#include "terracut/haptics/udp_device.hpp"
#include "terracut/io/files.hpp"

namespace terracut::session {
using namespace terracut::haptics;
namespace fs = std::filesystem;

namespace {

using Json = nlohmann::ordered_json;

// A number as summary.json gives it: nine significant digits (an output, so
// its own fixed precision, not format_number's shortest text), a whole
// number where those digits are one (8, not 8.0); null for NaN or infinity
// (JSON has neither).
Json json_number(double value) {
  if (!std::isfinite(value)) return nullptr;
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.9g", value);
  if (std::strpbrk(buffer, ".e") == nullptr) return std::strtoll(buffer, nullptr, 10);
  return std::strtod(buffer, nullptr);
}

// {"p50", "p99", "max", "mean"} in microseconds.
Json json_percentiles(const TimeStats& s) {
  return {{"p50", json_number(s.p50_s * 1e6)},
          {"p99", json_number(s.p99_s * 1e6)},
          {"max", json_number(s.max_s * 1e6)},
          {"mean", json_number(s.mean_s * 1e6)}};
}
Json json_percentiles(const TimePercentiles& s) {
  return {{"p50", json_number(s.p50_us)},
          {"p99", json_number(s.p99_us)},
          {"max", json_number(s.max_us)},
          {"mean", json_number(s.mean_us)}};
}

}  // namespace

std::vector<int> followed_cuts(const Scenario& scenario, const HapticSettings& settings) {
  const io::Scenario& sc = scenario.base;
  if (settings.cut.empty()) return sc.sequence;
  const int index = sc.find_cut(settings.cut);
  return index < 0 ? std::vector<int>{} : std::vector<int>{index};
}

DevicePath followed_path(const Scenario& scenario, const HapticSettings& settings,
                         const std::string& source, std::optional<double> rate_hz) {
  const io::Scenario& sc = scenario.base;
  std::vector<Motion> strokes;
  for (int index : followed_cuts(scenario, settings)) strokes.push_back(sc.cuts[std::size_t(index)]);
  if (strokes.empty() && !settings.cut.empty())
    throw InputError(source + ": haptics.cut: no cut named '" + settings.cut + "' in the scenario");
  if (strokes.empty())
    throw InputError(source + ": haptics.cut: the " + std::string(to_string(settings.device)) +
                     " device follows a cut, and the scenario has none");
  // A hand cannot jump from one stroke's end to the next one's start.
  if (settings.device == DeviceKind::kSim) strokes.resize(1);
  return DevicePath(std::move(strokes), rate_hz.value_or(sc.rate_hz),
                    Workspace(settings.workspace));
}

std::unique_ptr<Device> make_device(const Scenario& scenario, const HapticSettings& settings,
                                    int udp_port, const std::string& source,
                                    std::optional<double> rate_hz) {
  switch (settings.device) {
    case DeviceKind::kScript:
      return std::make_unique<ScriptDevice>(followed_path(scenario, settings, source, rate_hz));
    case DeviceKind::kSim:
      return std::make_unique<SimHandDevice>(SimHand(settings.hand,
                                                     settings.forces.device.inherent_damping_n_s_per_m,
                                                     followed_path(scenario, settings, source, rate_hz),
                                                     rate_hz.value_or(scenario.base.rate_hz)));
    case DeviceKind::kUdp:
      // A real device through the bridge (docs/bridge-protocol.md).
      return std::make_unique<UdpDevice>(settings.udp.address, udp_port);
  }
  throw InputError(source + ": haptics.device: unknown device");
}

// ---------------------------------------------------------------------------
// Building
// ---------------------------------------------------------------------------

HapticRig::HapticRig(const Scenario& scenario, const LoopParams& params, Quat default_orientation,
                     Device& device, const RigOptions& options) {
  WorldOptions wo;
  wo.rate_hz = params.rate_hz();
  wo.bodies_csv = options.bodies_csv;
  wo.arm_force_limit_n = options.arm_force_limit_n;
  world_ = std::make_unique<World>(scenario, wo);
  LoopOptions lo = options.loop;
  lo.bodies = world_->bodies();
  loop_ = std::make_unique<HapticLoop>(params, world_->simulation(), default_orientation, device,
                                       lo);
}

HapticRig::~HapticRig() {
  loop_.reset();  // the loop steps the world's simulation: it goes first
}

std::vector<std::string> HapticRig::rendering_changes() const {
  return loop_->force_model().limit_changes();
}

HapticSession::HapticSession(const Scenario& input, const SessionOptions& options)
    : source_(input.base.source_path), name_(input.base.name), options_(options) {
  const io::Scenario& sc = input.base;
  HapticSettings settings = input.haptics;
  if (options.device) settings.device = *options.device;
  if (options.udp_address) settings.udp.address = *options.udp_address;
  if (options.udp_port) settings.udp.port = *options.udp_port;
  if (options.duration_s) {
    if (!(std::isfinite(*options.duration_s) && *options.duration_s > 0.0 &&
          *options.duration_s <= 86400.0))
      throw InputError(must_be("--duration", "in (0, 86400] seconds", *options.duration_s));
    settings.duration_s = *options.duration_s;
  }
  kind_ = settings.device;
  clock_ =
      options.clock.value_or(kind_ == DeviceKind::kScript ? ClockMode::kFake : ClockMode::kReal);
  if (kind_ == DeviceKind::kUdp && clock_ == ClockMode::kFake)
    throw InputError(
        "--clock fake cannot be used with the udp device (a real device runs in real time)");

  // The settings, validated once, and what derives from them. A port of 0
  // (any free port) is allowed from the command line only: the device binds
  // the port asked for, and the loop never reads it.
  const int port = settings.udp.port;
  if (port == 0) settings.udp.port = 1;
  // The loop's rate: the scenario's, or the command line's.
  if (options.rate_hz)
    if (std::string m = check(kLoopRateRange, *options.rate_hz, "--rate"); !m.empty())
      throw InputError(m);
  const double rate_hz = options.rate_hz.value_or(sc.rate_hz);
  std::optional<LoopParams> params;
  try {
    params.emplace(settings, sc.blade, rate_hz);
  } catch (const InputError& e) {
    throw InputError(source_.string() + ": " + e.what());
  }
  const HapticSettings& valid = params->settings();

  // The device, and the path the script and sim devices follow: its length
  // and its first orientation (the default one).
  device_ = make_device(input, valid, port, source_.string(), rate_hz);
  std::optional<DevicePath> path;
  if (kind_ != DeviceKind::kUdp)
    path.emplace(followed_path(input, valid, source_.string(), rate_hz));
  cut_name_ = path ? path->strokes().front().name : "";
  const Quat default_orientation = path ? path->strokes().front().keyframes.front().pose.orientation : Quat{};
  const double path_s = path ? path->duration_s() : 0.0;
  duration_s_ =
      valid.duration_s.value_or(kind_ == DeviceKind::kUdp ? 30.0 : path_s + valid.settle_s);
  if (!(duration_s_ > 0.0))
    throw InputError(source_.string() +
                     ": haptics.duration_s: the session would last 0 s (the cut has one keyframe "
                     "and settle_s is 0); give duration_s or --duration");

  // The world and the loop.
  RigOptions ro;
  ro.loop.ticks = std::max<std::int64_t>(1, std::llround(duration_s_ * rate_hz));
  ro.loop.record_capacity = std::min<std::size_t>(options.max_records, std::size_t(ro.loop.ticks));
  ro.loop.realtime = options.realtime;
  ro.loop.snapshot = options.snapshot;
  if (options.end_with_device) ro.loop.end_after_silence_s = kDeviceEndSilence_s;
  ro.bodies_csv = options.bodies_csv;
  try {
    rig_ = std::make_unique<HapticRig>(input, *params, default_orientation, *device_, ro);
  } catch (const InputError& e) {
    throw InputError(source_.string() + ": " + e.what());
  }

  // What the device check changed, said once at start.
  build_warnings_ = rig_->rendering_changes();
  if (options.log)
    for (const std::string& w : build_warnings_)
      *options.log << "terracut haptics: warning: " << w << "\n";
}

HapticSession::~HapticSession() = default;

int HapticSession::udp_port() const {
  const auto* udp = dynamic_cast<const UdpDevice*>(device_.get());
  return udp ? udp->port() : -1;
}

// ---------------------------------------------------------------------------
// Running
// ---------------------------------------------------------------------------

void HapticSession::run() {
  const auto begin = std::chrono::steady_clock::now();
  if (clock_ == ClockMode::kFake) {
    rig_->loop().run_deterministic();
  } else {
    rig_->loop().start();
    if (options_.log)
      *options_.log << "terracut haptics: " << rig_->loop().realtime_status().message << "\n";
    while (rig_->loop().running()) {
      if (options_.interrupt && options_.interrupt->load(std::memory_order_relaxed)) {
        interrupted_ = true;
        rig_->loop().request_stop();
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    rig_->loop().join();
  }
  wall_s_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
}

// ---------------------------------------------------------------------------
// Outputs
// ---------------------------------------------------------------------------

std::vector<std::string> HapticSession::warnings() const {
  std::vector<std::string> w = build_warnings_;
  const std::vector<std::string> run = run_warnings();
  w.insert(w.end(), run.begin(), run.end());
  return w;
}

std::vector<std::string> HapticSession::run_warnings() const {
  std::vector<std::string> w;
  const HapticLoop& l = rig_->loop();
  const LoopCounters& c = l.counters();
  const SafetyCounters& s = l.safety().counters();
  if (clock_ == ClockMode::kReal && !l.realtime_status().fifo)
    w.push_back(l.realtime_status().message);
  if (c.bad_samples > 0)
    w.push_back(std::to_string(c.bad_samples) +
                " device samples were not finite (ignored, answered with zero force)");
  if (s.nonfinite > 0)
    w.push_back(std::to_string(s.nonfinite) + " non-finite forces were replaced by zero");
  if (c.missed_deadlines > 0) {
    // Say which it was: a tick whose work took longer than a period, or a
    // tick that had itself started late (the OS woke the loop late) and
    // ran past the next deadline with less work than a period.
    const LoopStats& ps = l.pacer_stats();
    std::string why;
    if (ps.missed_by_compute > 0)
      why += std::to_string(ps.missed_by_compute) + " after a tick that computed longer than a period (" +
             format_number(std::round(ps.compute.max_s * 1e7) / 10.0) + " us at most; timing_us.compute)";
    if (ps.missed_by_late_start > 0)
      why += std::string(why.empty() ? "" : ", ") + std::to_string(ps.missed_by_late_start) +
             " after a tick that had started late and computed less than a period (the OS woke the "
             "loop up to " + format_number(std::round(ps.wake_latency.max_s * 1e7) / 10.0) +
             " us after its deadline; timing_us.wake_latency)";
    w.push_back(std::to_string(c.missed_deadlines) + " ticks started late: " +
                (why.empty() ? std::string("the tick before ran past their deadline") : why));
  }
  // The waits before the device's first sample and after its last are
  // expected (the safety limiter holds zero force then); a silence in between
  // is not.
  if (const std::int64_t trips = l.watchdog_trips_while_active(); trips > 0)
    w.push_back("the watchdog ramped the force to zero " + std::to_string(trips) +
                " times while the device was sending (no sample for more than "
                "safety.watchdog_timeout_s)");
  if (c.records_dropped > 0)
    w.push_back(std::to_string(c.records_dropped) +
                " oldest records were not kept (the session was longer than max_records)");
  if (kind_ == DeviceKind::kUdp && c.samples == 0)
    w.push_back("no device sample was received on udp " + l.settings().udp.address + ":" +
                std::to_string(udp_port()) + " (is the bridge running?)");
  if (const auto* udp = dynamic_cast<const UdpDevice*>(device_.get()))
    if (udp->bridge_stats().rejected.total() > 0)
      w.push_back(std::to_string(udp->bridge_stats().rejected.total()) +
                  " bridge packets were rejected (see rejected_packets)");
  if (interrupted_) w.push_back("interrupted before the end of the session");
  return w;
}

std::string HapticSession::summary_json() const {
  const HapticLoop& l = rig_->loop();
  const HapticSettings& st = l.settings();
  const LoopCounters& c = l.counters();
  const SafetyCounters& s = l.safety().counters();
  const RenderingCheck& rc = l.force_model().rendering();
  const ForceModelParams& fp = l.force_model().params();
  const std::vector<LoopRecord> records = l.records();

  double peak_contact = 0.0, max_world = 0.0, removed = 0.0;
  std::int64_t in_contact = 0;
  for (const LoopRecord& r : records) {
    peak_contact = std::max(peak_contact, r.contact_length_m);
    max_world = std::max(max_world, length(r.force_world_n));
    if (r.contact_length_m > 0.0) ++in_contact;
  }
  removed = l.simulation().removed_volume_m3();

  Json j;
  j["scenario"] = name_;
  j["source"] = source_.string();
  j["device"] = std::string(to_string(kind_));
  j["cut"] = cut_name_;
  j["clock"] = clock_ == ClockMode::kFake ? "fake" : "real";
  j["rate_hz"] = json_number(l.params().rate_hz());
  j["duration_s"] = json_number(duration_s_);
  j["ticks"] = c.ticks;
  j["ended_with_device"] = l.ended_with_device();
  j["wall_s"] = json_number(wall_s_);
  j["realtime"] = {{"fifo", l.realtime_status().fifo},
                   {"priority", l.realtime_status().priority},
                   {"memory_locked", l.realtime_status().memory_locked},
                   {"message", l.realtime_status().message}};
  // Timing: the pacer's histograms cover every tick; the period's
  // percentiles come from the kept records.
  const LoopStats& ps = l.pacer_stats();
  j["timing_us"] = {{"period_jitter", json_percentiles(ps.period_jitter)},
                    {"compute", json_percentiles(ps.compute)},
                    {"wake_latency", json_percentiles(ps.wake_latency)},
                    {"period", json_percentiles(l.period())},
                    {"missed_deadlines", ps.missed_deadlines},
                    {"missed_by_compute", ps.missed_by_compute},
                    {"missed_by_late_start", ps.missed_by_late_start},
                    {"skipped_slots", ps.skipped_slots}};
  j["loop"] = {{"samples", c.samples},           {"silent_ticks", c.silent_ticks},
               {"bad_samples", c.bad_samples},   {"reconnects", c.reconnects},
               {"records_kept", records.size()}, {"records_dropped", c.records_dropped}};
  j["safety"] = {{"samples", s.samples},
                 {"clamped", s.clamped},
                 {"rate_limited", s.rate_limited},
                 {"ramping", s.ramping},
                 {"watchdog", s.watchdog},
                 {"watchdog_trips", s.watchdog_trips},
                 {"watchdog_trips_while_active", l.watchdog_trips_while_active()},
                 {"nonfinite", s.nonfinite},
                 {"restarts", s.restarts}};

  // Rejected bridge packets by reason (all zero for script and sim).
  RejectCounts rejected{};
  const auto* udp = dynamic_cast<const UdpDevice*>(device_.get());
  if (udp) rejected = udp->bridge_stats().rejected;
  Json& by_reason = j["rejected_packets"] = Json::object();
  for (std::size_t i = 1; i < kRejectReasonCount; ++i)
    by_reason[std::string(to_string(static_cast<Reject>(i)))] = rejected.by_reason[i];
  by_reason["total"] = rejected.total();

  Json& stats = j["device_stats"] = Json::object();
  for (const DeviceStat& d : device_->stats()) stats[d.name] = json_number(d.value);
  if (udp) stats["port"] = udp->port();

  j["forces"] = {
      {"cutting", std::string(to_string(fp.cutting))},
      {"surface", fp.surface_enabled},
      {"surface_reference", std::string(to_string(st.surface_reference))},
      {"force_scale", json_number(fp.force_scale)},
      {"workspace_scale", json_number(fp.workspace_scale)},
      {"max_device_force_n", json_number(l.max_device_force_n())},
      {"max_world_force_n", json_number(max_world)},
      {"rendering",
       {{"surface_stiffness_n_per_m", json_number(rc.surface_stiffness_n_per_m)},
        {"surface_damping_n_s_per_m", json_number(rc.surface_damping_n_s_per_m)},
        {"passive_stiffness_n_per_m", json_number(rc.passive_stiffness_n_per_m)},
        {"cutting_damping_n_s_per_m", json_number(rc.cutting_damping_n_s_per_m)},
        {"surface_stiffness_limited", rc.surface_stiffness_limited},
        {"surface_damping_limited", rc.surface_damping_limited},
        {"cutting_damping_limited", rc.cutting_damping_limited},
        {"requested_surface_stiffness_n_per_m",
         json_number(rc.requested_surface_stiffness_n_per_m)},
        {"requested_surface_damping_n_s_per_m",
         json_number(rc.requested_surface_damping_n_s_per_m)},
        {"requested_cutting_damping_n_s_per_m",
         json_number(rc.requested_cutting_damping_n_s_per_m)},
        {"cutting_gain", json_number(rc.cutting_gain)},
        {"changes", l.force_model().limit_changes()}}},
      {"safety_limits",
       {{"max_force_n", json_number(st.safety.max_force_n)},
        {"max_force_rate_n_per_s", json_number(st.safety.max_force_rate_n_per_s)},
        {"rise_time_s", json_number(st.safety.rise_time_s)},
        {"watchdog_timeout_s", json_number(st.safety.watchdog_timeout_s)},
        {"watchdog_ramp_s", json_number(st.safety.watchdog_ramp_s)}}}};
  j["cutting"] = {{"removed_volume_m3", json_number(removed)},
                  {"peak_contact_m", json_number(peak_contact)},
                  {"ticks_in_contact", in_contact}};
  // The rigid bodies and the peak force they put on the tool.
  if (rig_->world().bodies())
    j["bodies"] = detail::bodies_json(rig_->world(), detail::BodiesEntry::kLoop);
  j["warnings"] = warnings();
  return j.dump(2) + "\n";
}

void HapticSession::write_outputs(const fs::path& out_dir) {
  io::make_output_folder(out_dir);
  rig_->world().finish();
  write_haptics_csv(out_dir / "haptics.csv", rig_->loop().records());
  io::write_text_file(out_dir / "summary.json", summary_json());
}

std::string HapticSession::summary_line() const {
  const HapticLoop& l = rig_->loop();
  const LoopStats& ps = l.pacer_stats();
  const TimeStats& j = ps.period_jitter;
  const TimeStats& c = ps.compute;
  char line[512];
  std::snprintf(line, sizeof line,
                "%s: %s device, %lld ticks at %g Hz (%s clock), period jitter p50 %.1f us p99 "
                "%.1f us max %.1f us, compute p50 %.1f us p99 %.1f us, %lld missed deadlines, "
                "max device force %.3g N, removed %.4g m^3",
                name_.c_str(), std::string(to_string(kind_)).c_str(),
                static_cast<long long>(l.counters().ticks), l.params().rate_hz(),
                clock_ == ClockMode::kFake ? "fake" : "real", j.p50_s * 1e6, j.p99_s * 1e6,
                j.max_s * 1e6, c.p50_s * 1e6, c.p99_s * 1e6,
                static_cast<long long>(ps.missed_deadlines), l.max_device_force_n(),
                l.simulation().removed_volume_m3());
  return line;
}

}  // namespace terracut::session
