// The haptic loop (loop.hpp): one tick = step1 (device -> pose -> contact)
// then step2 (cut -> force -> safety -> device -> record).
#include "terracut/haptics/loop.hpp"

#include <algorithm>
#include <cmath>
#include <future>
#include <numbers>
#include <stdexcept>

#include "terracut/core/error.hpp"
#include "terracut/core/format.hpp"
#include "terracut/core/surface.hpp"
#include "terracut/haptics/pacer.hpp"

namespace terracut::haptics {
namespace {

// The settings checked alone, then against the loop's rate.
HapticSettings validated(HapticSettings settings, const BladeSpec& blade, double rate_hz) {
  if (std::string m = check(kLoopRateRange, rate_hz); !m.empty())
    throw InputError(m + " (a haptic loop's rate)");
  if (std::string m = validate(settings); !m.empty()) throw InputError("haptics." + m);
  if (!(settings.velocity_cutoff_hz < rate_hz / 2.0))
    throw InputError(must_be("haptics.velocity_cutoff_hz",
                             "below rate_hz / 2 = " + format_number(rate_hz / 2.0),
                             settings.velocity_cutoff_hz));
  return with_derived_fields(std::move(settings), blade.length_m, rate_hz);
}

ForceModel built_model(const ForceModelParams& params) {
  try {
    return ForceModel(params);  // validates and makes the device check
  } catch (const InputError& e) {
    throw InputError(std::string("haptics.forces.") + e.what());
  }
}

}  // namespace

LoopParams::LoopParams(const HapticSettings& settings, const BladeSpec& blade, double rate_hz)
    : settings_(validated(settings, blade, rate_hz)), model_(built_model(settings_.forces)) {}

HapticLoop::HapticLoop(const LoopParams& params, Simulation& sim, Quat default_orientation,
                       Device& device, const LoopOptions& options)
    : params_(params),
      device_(device),
      options_(options),
      workspace_(params_.settings().workspace),
      safety_(params_.settings().safety),
      sim_(sim),
      default_orientation_(normalized(default_orientation)) {
  const HapticSettings& settings = params_.settings();
  if (options_.ticks < 1) throw InputError("haptics: the loop needs at least one tick");
  if (!(std::isfinite(options_.end_after_silence_s) && options_.end_after_silence_s >= 0.0))
    throw InputError(must_be("haptics: end_after_silence_s", "finite and >= 0",
                             options_.end_after_silence_s));
  if (sim_.params().rate_hz != params_.rate_hz())
    throw InputError("haptics: the simulation steps at " + format_number(sim_.params().rate_hz) +
                     " Hz, the loop runs at " + format_number(params_.rate_hz()) +
                     " Hz: build the simulation at the loop's rate");
  if (settings.tool_rotation_deg) {
    fixed_orientation_ = quat_from_euler_deg(*settings.tool_rotation_deg);
    has_fixed_orientation_ = true;
  }
  if (settings.velocity_cutoff_hz > 0.0)
    filter_rc_s_ = 1.0 / (2.0 * std::numbers::pi * settings.velocity_cutoff_hz);
  if (options_.snapshot) {
    const ViewFrame& f = options_.snapshot->front();
    if (f.cols != sim_.grid().cols() || f.rows != sim_.grid().rows())
      throw InputError("haptics: the snapshot exchange was built for another grid size");
  }
  // Everything a tick touches is allocated here, never during the run.
  records_.resize(options_.record_capacity);
}

HapticLoop::~HapticLoop() {
  request_stop();
  if (thread_.joinable()) thread_.join();
}

// ---------------------------------------------------------------------------
// One tick
// ---------------------------------------------------------------------------

void HapticLoop::step1(double t_s) noexcept {
  t_s_ = t_s;
  tick_flags_ = 0;
  if (!started_) {
    started_ = true;
    device_.start(t_s);
    safety_.restart(t_s);
  }
  const bool bad = !read_device(t_s);
  // A device that sent and then fell silent long enough has ended its session.
  if (options_.end_after_silence_s > 0.0 && has_sample_ &&
      t_s - last_sample_t_s_ > options_.end_after_silence_s && !ended_with_device_) {
    ended_with_device_ = true;
    request_stop();
  }

  // Without a usable sample (none yet, or a bad one) the simulation is not
  // stepped: nothing is measured or cut.
  stepped_ = has_sample_ && !bad;
  if (!stepped_) {
    velocity_m_per_s_ = {};
    acceleration_m_per_s2_ = {};
    yaw_rate_rad_per_s_ = 0.0;
    has_previous_tool_ = false;  // start the estimate afresh
    return;
  }
  // The handle may be anywhere after a reconnection, and a lifted tool
  // starts a new stroke: no sweep from the previous pose.
  if (tick_flags_ & (kFlagReconnected | kFlagLifted)) sim_.lift();
  const BladePose pose = tool_pose();
  estimate_velocity(pose, t_s);
  sim_.begin_step(pose);
}

// Reads the device: counts a non-finite sample (returns false) and keeps the
// last good one; a reconnection restarts the soft start.
bool HapticLoop::read_device(double t_s) noexcept {
  DeviceSample fresh = sample_;
  fresh.reconnected = false;
  fresh.lifted = false;
  if (!device_.read(t_s, fresh)) {
    ++counters_.silent_ticks;
    tick_flags_ |= kFlagSilent;
    return true;
  }
  ++counters_.samples;
  const bool finite =
      is_finite(fresh.position_m) && (!fresh.has_orientation || is_finite(fresh.orientation));
  if (!finite) {
    ++counters_.bad_samples;
    tick_flags_ |= kFlagBadSample;
    return false;
  }
  sample_ = fresh;
  device_position_m_ = fresh.position_m;
  if (!has_sample_) trips_before_first_sample_ = safety_.counters().watchdog_trips;
  trips_at_newest_sample_ = safety_.counters().watchdog_trips;
  has_sample_ = true;
  last_sample_t_s_ = t_s;
  if (fresh.lifted) {
    tick_flags_ |= kFlagLifted;
    has_previous_tool_ = false;  // a new stroke: the velocity estimate starts afresh
  }
  if (fresh.reconnected) {
    ++counters_.reconnects;
    tick_flags_ |= kFlagReconnected;
    safety_.restart(t_s);
    has_previous_tool_ = false;  // the handle may be anywhere now
  }
  return true;
}

// The tool pose: position from the device, orientation fixed, from the
// device, or the default.
BladePose HapticLoop::tool_pose() const noexcept {
  BladePose pose;
  pose.position_m = sample_.has_world_pose ? sample_.world_pose.position_m
                                           : workspace_.to_world(sample_.position_m);
  if (has_fixed_orientation_)
    pose.orientation = fixed_orientation_;
  else if (sample_.has_world_pose)
    pose.orientation = sample_.world_pose.orientation;
  else if (sample_.has_orientation)
    pose.orientation = workspace_.orientation_to_world(sample_.orientation);
  else
    pose.orientation = default_orientation_;
  return pose;
}

// Velocity: filtered backward difference, updated only on new good samples
// (a device slower than the loop does not read as stop-and-go).
void HapticLoop::estimate_velocity(const BladePose& pose, double t_s) noexcept {
  if (tick_flags_ & kFlagSilent) return;
  // The interval between the samples: on the device's clock when it gives
  // one (a late network packet is not a jump in speed), else the loop's.
  const double device_t = sample_.device_time_s;
  const bool device_clock = std::isfinite(device_t) && std::isfinite(previous_device_t_s_) &&
                            device_t > previous_device_t_s_;
  if (has_previous_tool_ && (device_clock || t_s > previous_tool_t_s_)) {
    const double dt = device_clock ? device_t - previous_device_t_s_ : t_s - previous_tool_t_s_;
    const Vec3 raw = (pose.position_m - previous_tool_m_) * (1.0 / dt);
    const double alpha = filter_rc_s_ > 0.0 ? 1.0 - std::exp(-dt / filter_rc_s_) : 1.0;
    const Vec3 before = velocity_m_per_s_;
    velocity_m_per_s_ = velocity_m_per_s_ + (raw - velocity_m_per_s_) * alpha;
    // The acceleration: the filtered velocity's change, low-passed again. A
    // first-order low-pass keeps the integral of what it filters, so the
    // impulse of the load's inertia is its mass x its change of velocity.
    const double beta = 1.0 - std::exp(-dt * 2.0 * std::numbers::pi * kAccelerationCutoffHz);
    acceleration_m_per_s2_ =
        acceleration_m_per_s2_ + ((velocity_m_per_s_ - before) * (1.0 / dt) - acceleration_m_per_s2_) * beta;
  } else {
    velocity_m_per_s_ = {};
    acceleration_m_per_s2_ = {};
  }
  // The yaw rate: the turn of the edge's horizontal direction about +Y
  // (Ry(a) X = (cos a, 0, -sin a)), filtered as the velocity is.
  const Vec3 edge_dir = rotate(pose.orientation, Vec3{1.0, 0.0, 0.0});
  const bool level = std::hypot(edge_dir.x, edge_dir.z) > 1e-6;
  const double yaw = level ? std::atan2(-edge_dir.z, edge_dir.x) : previous_yaw_rad_;
  if (has_previous_tool_ && (device_clock || t_s > previous_tool_t_s_)) {
    const double dt = device_clock ? device_t - previous_device_t_s_ : t_s - previous_tool_t_s_;
    const double turn = std::remainder(yaw - previous_yaw_rad_, 2.0 * std::numbers::pi);
    const double alpha = filter_rc_s_ > 0.0 ? 1.0 - std::exp(-dt / filter_rc_s_) : 1.0;
    yaw_rate_rad_per_s_ += (turn / dt - yaw_rate_rad_per_s_) * alpha;
  } else {
    yaw_rate_rad_per_s_ = 0.0;
  }
  previous_yaw_rad_ = yaw;
  previous_device_t_s_ = device_t;
  previous_tool_m_ = pose.position_m;
  previous_tool_t_s_ = t_s;
  has_previous_tool_ = true;
}

const LoopRecord& HapticLoop::step2(double period_s, double compute_s,
                                    bool missed_deadline) noexcept {
  // Cut, soil and the physical force (and the simulation's listeners: e.g.
  // the rigid bodies), then its rendering at the device's motion.
  const StepOutput& out = stepped_ ? sim_.finish_step() : not_stepped_;
  const ForceOutput force = stepped_ ? rendered_force(out) : ForceOutput{};

  // Safety: a bad sample or no sample yet asks for zero force (shrinking to
  // zero is immediate); the watchdog looks at the last good sample's time.
  SafetyOutput safe = safety_.update(t_s_, force.device_n, last_sample_t_s_);
  if (tick_flags_ & kFlagBadSample) {
    // Zero for a bad sample also while the watchdog fades an older force
    // out (update() would give the fading force; found by terracut-soak).
    safe.force_n = {};
    safety_.zero_output();
  }
  std::uint32_t flags = tick_flags_ | safe.flags.bits();
  if (missed_deadline) {
    flags |= kFlagMissedDeadline;
    ++counters_.missed_deadlines;
  }

  // To the device frame, and out.
  DeviceCommand command;
  command.force_n = workspace_.direction_to_device(safe.force_n);
  command.flags = flags;
  command.t_s = t_s_;
  device_.write(command);

  LoopRecord& r = write_record(out, force, command, period_s, compute_s);
  if (options_.snapshot) publish_frame(out, force, command, period_s, compute_s);
  return r;
}

// The step's physical force rendered at the device's (filtered) motion: the
// cutting model, the low-speed damper, the device's gain, the surface proxy,
// the carried load's filtered inertia (ForceModel::compute).
ForceOutput HapticLoop::rendered_force(const StepOutput& out) const noexcept {
  const HapticSettings& settings = params_.settings();
  ForceInput in;
  in.physical = out.force;
  in.velocity_m_per_s = velocity_m_per_s_;
  in.acceleration_m_per_s2 = acceleration_m_per_s2_;
  in.yaw_rate_rad_per_s = yaw_rate_rad_per_s_;
  in.contact_length_m = out.contact.length_m;
  in.device_point_m = out.pose.position_m;
  in.surface_y_m = settings.surface_reference == SurfaceReference::kGround
                       ? sim_.grid().spec().origin_m.y
                       : surface_y_m(sim_.grid(), sim_.params().representation,
                                     out.pose.position_m.x, out.pose.position_m.z);
  return params_.force_model().compute(in);
}

// The tick's record (last_, and the ring of kept records).
LoopRecord& HapticLoop::write_record(const StepOutput& out, const ForceOutput& force,
                                     const DeviceCommand& command, double period_s,
                                     double compute_s) noexcept {
  const Vec3 body_force = stepped_ ? out.listener_force_world_n : Vec3{};
  LoopRecord& r = last_;
  r.tick = counters_.ticks;
  r.t_s = t_s_;
  r.device_position_m = device_position_m_;
  r.tool = stepped_ ? out.pose : sim_.last().pose;
  r.contact_length_m = out.contact.length_m;
  r.cut_depth_m = stepped_ ? out.force.cut_depth_m : 0.0;
  r.physical_force_world_n = stepped_ ? out.force.total_n : Vec3{};
  r.removed_volume_m3 = out.cut.removed_volume_m3;
  r.velocity_m_per_s = velocity_m_per_s_;
  r.force_world_n = force.world_n;
  r.body_force_world_n = body_force;
  r.penetration_force_n = force.penetration_n.y;
  r.cutting_force_world_n = force.cutting_n;
  r.cutting_uncapped_n = force.cutting_uncapped_n;
  r.cutting_cap_n = force.cutting_cap_n;
  r.twist_torque_n_m = force.twist_torque_n_m;
  r.yaw_rate_rad_per_s = yaw_rate_rad_per_s_;
  r.force_device_n = command.force_n;
  r.flags = command.flags;
  r.period_s = period_s;
  r.compute_s = compute_s;
  max_device_force_n_ = std::max(max_device_force_n_, length(command.force_n));
  max_body_force_n_ = std::max(max_body_force_n_, length(body_force));
  ++counters_.ticks;
  record(r);
  return r;
}

// The viewer's picture of this tick.
void HapticLoop::publish_frame(const StepOutput& out, const ForceOutput& force,
                               const DeviceCommand& command, double period_s,
                               double compute_s) noexcept {
  SnapshotExchange& x = *options_.snapshot;
  x.note_changed(out.changed);
  ViewFrame& f = x.back();
  f.t_s = t_s_;
  f.step = out.step;
  f.pose = out.pose;
  f.edge = out.edge;
  f.contact = out.contact;
  f.device_position_m = out.pose.position_m;
  f.proxy_position_m = force.surface.in_contact ? force.surface.proxy_m : out.pose.position_m;
  f.force_world_n = force.world_n;
  f.force_device_n = command.force_n;
  f.bucket_load_m3 = out.soil.bucket_load_m3;
  f.body_force_world_n = last_.body_force_world_n;
  f.penetration_force_n = force.penetration_n.y;
  f.twist_torque_n_m = force.twist_torque_n_m;
  f.yaw_rate_rad_per_s = yaw_rate_rad_per_s_;
  f.step_time_s = compute_s;
  f.period_s = period_s;
  fill_bodies(f, options_.bodies);
  x.publish(sim_.grid());
}

void HapticLoop::record(const LoopRecord& r) noexcept {
  if (records_.empty()) return;
  if (records_wrapped_) ++counters_.records_dropped;
  records_[next_record_] = r;
  if (++next_record_ == records_.size()) {
    next_record_ = 0;
    records_wrapped_ = true;
  }
}

// ---------------------------------------------------------------------------
// Running
// ---------------------------------------------------------------------------

namespace {

// The fake clock of run_deterministic: time moves only when the pacer sleeps,
// and then exactly to the deadline, so every tick starts on its deadline.
class FakeClock final : public PacerClock {
 public:
  double now_s() override { return now_s_; }
  void sleep_until(double t_s) override { now_s_ = std::max(now_s_, t_s); }
  void relax() override {}

 private:
  double now_s_ = 0.0;
};

}  // namespace

void HapticLoop::patch_compute(double compute_s) noexcept {
  last_.compute_s = compute_s;
  if (!records_.empty())
    records_[next_record_ == 0 ? records_.size() - 1 : next_record_ - 1].compute_s = compute_s;
}

// One paced tick of either mode: the pacer's tick gives the loop time and the
// period; the compute time is measured on `measure` (the pacer's clock in
// real time; the steady clock with the fake clock, whose time stands still)
// and handed to the pacer for its statistics.
void HapticLoop::paced_tick(Pacer& pacer, PacerClock& measure, const Tick& tick, double origin_s,
                            bool fake) noexcept {
  const double begin = fake ? measure.now_s() : tick.start_s;
  const double t = (fake ? tick.deadline_s : tick.start_s) - origin_s;
  step1(t);
  // The fake clock's periods are nominal (its deadlines differ from it by rounding only).
  const double period = tick.index == 0 ? 0.0 : fake ? 1.0 / params_.rate_hz() : tick.period_s;
  step2(period, measure.now_s() - begin, tick.after_overrun);
  // step2's own cost belongs to the tick too.
  const double compute = measure.now_s() - begin;
  patch_compute(compute);
  pacer.record_compute(compute);
}

void HapticLoop::run_deterministic() {
  realtime_ = {};
  realtime_.message = "real-time: not used (fake clock)";
  PacerSettings ps;
  ps.rate_hz = params_.rate_hz();
  ps.spin_s = 0.0;
  Pacer pacer(ps, std::make_shared<FakeClock>());
  const std::shared_ptr<PacerClock> measure = steady_pacer_clock();
  Tick tick = pacer.start();
  const double origin = tick.deadline_s;
  for (std::int64_t i = 0; i < options_.ticks; ++i) {
    if (stop_requested_.load(std::memory_order_relaxed)) break;
    if (i > 0) tick = pacer.wait_next();
    paced_tick(pacer, *measure, tick, origin, true);
  }
  pacer_stats_ = pacer.stats();
  device_.stop();
}

void HapticLoop::start() {
  if (running_.load() || thread_.joinable())
    throw std::logic_error("HapticLoop::start: the loop is already running or was not joined");
  stop_requested_.store(false);
  running_.store(true, std::memory_order_release);
  // Wait until the thread has set up its scheduling, so that
  // realtime_status() may be read as soon as start() returns.
  std::promise<void> ready;
  std::future<void> set_up = ready.get_future();
  thread_ = std::thread([this, &ready] { thread_main(ready); });
  set_up.wait();
}

void HapticLoop::join() {
  if (thread_.joinable()) thread_.join();
}

void HapticLoop::thread_main(std::promise<void>& ready) {
  // Real-time scheduling and locked memory for this thread, where permitted.
  if (options_.realtime) {
    realtime_ = enable_realtime(options_.realtime_priority, options_.lock_memory);
  } else {
    realtime_ = {};
    realtime_.message = "real-time: not asked (normal scheduling, memory not locked)";
  }
  ready.set_value();  // `ready` lives in start(), which returns after this
  {
    PacerSettings ps;
    ps.rate_hz = params_.rate_hz();
    const std::shared_ptr<PacerClock> clock =
        options_.clock ? options_.clock : steady_pacer_clock();
    Pacer pacer(ps, clock);
    Tick tick = pacer.start();
    double origin = tick.start_s;
    for (std::int64_t i = 0; i < options_.ticks; ++i) {
      if (stop_requested_.load(std::memory_order_relaxed)) break;
      if (i > 0 && device_.paused()) {
        // Held while the device is paused (the viewer's Pause): no ticks,
        // a short sleep at a time to see Play or a stop. The loop's time
        // leaves the pause out: the next tick is one period after the last.
        const double last_start = tick.start_s;
        pacer.hold();
        while (device_.paused() && !stop_requested_.load(std::memory_order_relaxed))
          clock->sleep_until(clock->now_s() + kPausePoll_s);
        if (stop_requested_.load(std::memory_order_relaxed)) break;
        tick = pacer.resume();
        origin += tick.start_s - last_start - tick.period_s;
      } else if (i > 0) {
        tick = pacer.wait_next();
      }
      paced_tick(pacer, *clock, tick, origin, false);
    }
    pacer_stats_ = pacer.stats();
  }
  device_.stop();
  release_realtime(realtime_);
  running_.store(false, std::memory_order_release);
}

std::vector<LoopRecord> HapticLoop::records() const {
  std::vector<LoopRecord> out;
  if (records_.empty()) return out;
  if (records_wrapped_) {
    out.insert(out.end(), records_.begin() + std::ptrdiff_t(next_record_), records_.end());
    out.insert(out.end(), records_.begin(), records_.begin() + std::ptrdiff_t(next_record_));
  } else {
    out.insert(out.end(), records_.begin(), records_.begin() + std::ptrdiff_t(next_record_));
  }
  return out;
}

TimePercentiles HapticLoop::percentiles(double LoopRecord::*field, bool deviation) const {
  const std::vector<LoopRecord> rs = records();
  std::vector<double> v;
  v.reserve(rs.size());
  const double nominal = 1.0 / params_.rate_hz();
  // The first tick has no period.
  for (const LoopRecord& r : rs) {
    if (field == &LoopRecord::period_s && r.tick == 0) continue;
    const double x = r.*field;
    v.push_back(deviation ? std::abs(x - nominal) : x);
  }
  return timing_stats(v);
}

TimePercentiles HapticLoop::jitter() const { return percentiles(&LoopRecord::period_s, true); }
TimePercentiles HapticLoop::period() const { return percentiles(&LoopRecord::period_s, false); }
TimePercentiles HapticLoop::compute() const { return percentiles(&LoopRecord::compute_s, false); }

}  // namespace terracut::haptics
