#include "viewer_device.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

namespace terracut::viewer {
namespace {

std::int64_t wall_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

void atomic_max(std::atomic<std::int64_t>& a, std::int64_t v) {
  std::int64_t cur = a.load(std::memory_order_relaxed);
  while (v > cur && !a.compare_exchange_weak(cur, v, std::memory_order_relaxed)) {
  }
}

int bin_of(double seconds) {
  double us = seconds * 1e6;
  if (!(us >= 0.0)) return 0;
  return int(std::min(us, double(LoopTiming::kBins - 1)));
}

double percentile_us(const std::vector<std::atomic<std::uint32_t>>& hist, double q) {
  std::uint64_t total = 0;
  for (const auto& b : hist) total += b.load(std::memory_order_relaxed);
  if (total == 0) return 0.0;
  const std::uint64_t want = std::max<std::uint64_t>(1, std::uint64_t(std::ceil(q * double(total))));
  std::uint64_t seen = 0;
  for (std::size_t i = 0; i < hist.size(); ++i) {
    seen += hist[i].load(std::memory_order_relaxed);
    if (seen >= want) return double(i) + 0.5;  // the bin's centre
  }
  return double(hist.size());
}

}  // namespace

// ---------------------------------------------------------------------------
// Tour
// ---------------------------------------------------------------------------

BladePose sample_leg(const PoseLeg& leg, const io::Scenario* scenario, double t_s) {
  if (leg.cut >= 0 && scenario) return scenario->cuts[std::size_t(leg.cut)].sample(t_s);
  double u = leg.duration_s > 0.0 ? std::clamp(t_s / leg.duration_s, 0.0, 1.0) : 1.0;
  return {lerp(leg.from.position_m, leg.to.position_m, u),
          slerp(leg.from.orientation, leg.to.orientation, u)};
}

double Tour::transit(PoseLeg (&out)[3], double start_s, const BladePose& from,
                     const BladePose& to, double clearance_y_m, double speed_m_per_s) {
  // Up from `from`, across at the clearance height (turning to the new
  // orientation), down onto `to`.
  BladePose up = from, over = to;
  up.position_m.y = std::max(clearance_y_m, from.position_m.y);
  over.position_m.y = std::max(clearance_y_m, to.position_m.y);
  over.orientation = to.orientation;
  const BladePose points[4] = {from, up, over, to};
  double t = start_s;
  for (int i = 0; i < 3; ++i) {
    double d = length(points[i + 1].position_m - points[i].position_m);
    PoseLeg leg;
    leg.start_s = t;
    leg.duration_s = std::max(d / speed_m_per_s, i == 1 ? 0.1 : 0.0);
    leg.from = points[i];
    leg.to = points[i + 1];
    out[i] = leg;
    t += leg.duration_s;
  }
  return t;
}

Tour::Tour(const io::Scenario& scenario, double clearance_y_m, double transit_speed_m_per_s)
    : scenario_(&scenario) {
  double t = 0.0;
  for (std::size_t k = 0; k < scenario.sequence.size(); ++k) {
    const int cut = scenario.sequence[k];
    const Motion& motion = scenario.cuts[std::size_t(cut)];
    if (k > 0) {
      const Motion& prev = scenario.cuts[std::size_t(scenario.sequence[k - 1])];
      PoseLeg legs[3];
      t = transit(legs, t, prev.sample(prev.duration_s()), motion.sample(0.0), clearance_y_m,
                  transit_speed_m_per_s);
      legs_.insert(legs_.end(), legs, legs + 3);
    }
    PoseLeg leg;
    leg.start_s = t;
    leg.duration_s = motion.duration_s();
    leg.cut = cut;
    leg.sequence_index = int(k);
    legs_.push_back(leg);
    t += leg.duration_s;
  }
  duration_s_ = t;
}

Tour::Tour(std::vector<PoseLeg> legs) : legs_(std::move(legs)) {
  double t = 0.0;
  for (PoseLeg& leg : legs_) {
    leg.start_s = t;
    leg.cut = -1;
    t += leg.duration_s;
  }
  duration_s_ = t;
}

Tour plough_tour(const GridSpec& spec, double max_height_m, double blade_length_m,
                 double speed_m_per_s, int passes_at_ground) {
  const double x = spec.origin_m.x + 0.5 * spec.size_x_m;
  const double margin = 0.05 * spec.size_z_m + 0.1 * blade_length_m;
  const double z_a = spec.origin_m.z - margin, z_b = spec.origin_m.z + spec.size_z_m + margin;
  const double step = max_height_m / 12.0;
  std::vector<PoseLeg> legs;
  BladePose at;
  at.position_m = {x, spec.origin_m.y + 0.75 * max_height_m, z_a};
  bool forward = true;
  int ground_passes = 0;
  while (ground_passes < passes_at_ground) {
    // One pass across, then down one step outside the terrain.
    BladePose end = at;
    end.position_m.z = forward ? z_b : z_a;
    legs.push_back({0.0, (z_b - z_a) / speed_m_per_s, at, end, -1, -1});
    BladePose lower = end;
    lower.position_m.y = std::max(spec.origin_m.y, end.position_m.y - step);
    if (lower.position_m.y <= spec.origin_m.y) ++ground_passes;
    legs.push_back({0.0, step / speed_m_per_s, end, lower, -1, -1});
    at = lower;
    forward = !forward;
  }
  return Tour(std::move(legs));
}

const PoseLeg* Tour::leg_at(double t_s) const {
  if (legs_.empty()) return nullptr;
  // Few legs: a linear scan.
  for (const PoseLeg& leg : legs_)
    if (t_s < leg.start_s + leg.duration_s) return &leg;
  return &legs_.back();
}

BladePose Tour::sample(double t_s) const {
  const PoseLeg* leg = leg_at(t_s);
  if (!leg) return {};
  return sample_leg(*leg, scenario_, std::max(0.0, t_s - leg->start_s));
}

// ---------------------------------------------------------------------------
// LoopTiming
// ---------------------------------------------------------------------------

void LoopTiming::record_period(double period_s) {
  period_hist_[std::size_t(bin_of(period_s))].fetch_add(1, std::memory_order_relaxed);
  ticks_.fetch_add(1, std::memory_order_relaxed);
  const std::int64_t ns = std::int64_t(period_s * 1e9);
  atomic_max(period_max_ns_, ns);
  atomic_max(worst_jitter_ns_, std::llabs(ns - nominal_ns_));
}

void LoopTiming::record_compute(double compute_s) {
  compute_hist_[std::size_t(bin_of(compute_s))].fetch_add(1, std::memory_order_relaxed);
  atomic_max(compute_max_ns_, std::int64_t(compute_s * 1e9));
}

LoopTimingSnapshot LoopTiming::snapshot() const {
  LoopTimingSnapshot s;
  s.ticks = ticks_.load(std::memory_order_relaxed);
  s.period_p50_us = percentile_us(period_hist_, 0.50);
  s.period_p99_us = percentile_us(period_hist_, 0.99);
  s.period_max_us = double(period_max_ns_.load(std::memory_order_relaxed)) * 1e-3;
  s.compute_p50_us = percentile_us(compute_hist_, 0.50);
  s.compute_p99_us = percentile_us(compute_hist_, 0.99);
  s.compute_max_us = double(compute_max_ns_.load(std::memory_order_relaxed)) * 1e-3;
  return s;
}

void LoopTiming::clear() {
  for (auto& b : period_hist_) b.store(0, std::memory_order_relaxed);
  for (auto& b : compute_hist_) b.store(0, std::memory_order_relaxed);
  ticks_.store(0, std::memory_order_relaxed);
  period_max_ns_.store(0, std::memory_order_relaxed);
  compute_max_ns_.store(0, std::memory_order_relaxed);
  worst_jitter_ns_.store(0, std::memory_order_relaxed);
}

double LoopTiming::take_worst_jitter_s() {
  return double(worst_jitter_ns_.exchange(0, std::memory_order_relaxed)) * 1e-9;
}

// ---------------------------------------------------------------------------
// ViewerDevice
// ---------------------------------------------------------------------------

ViewerDevice::ViewerDevice(const haptics::Workspace& workspace, const Tour& tour,
                           const BladePose& start, double rate_hz, double clearance_y_m,
                           double transit_speed_m_per_s, LoopTiming* timing)
    : workspace_(workspace),
      tour_(tour),
      dt_s_(1.0 / rate_hz),
      clearance_y_m_(clearance_y_m),
      transit_speed_m_per_s_(transit_speed_m_per_s),
      timing_(timing),
      pose_(start),
      mouse_target_(start) {
  if (timing_) timing_->set_nominal(dt_s_);
  script_finished_.store(tour.empty());
}

void ViewerDevice::set_speed(double speed) {
  if (!std::isfinite(speed)) speed = 1.0;
  speed_.store(std::clamp(speed, 0.0, 16.0));
}

void ViewerDevice::set_frame_interval_s(double interval_s) {
  if (!std::isfinite(interval_s)) interval_s = 0.0;
  frame_interval_s_.store(std::clamp(interval_s, 0.0, 0.25), std::memory_order_relaxed);
}

void ViewerDevice::request_step_s(double step_s) {
  if (!(step_s > 0.0) || !std::isfinite(step_s)) return;
  step_budget_s_.fetch_add(step_s, std::memory_order_relaxed);
}

void ViewerDevice::set_lag_s(double lag_s) {
  if (!std::isfinite(lag_s)) lag_s = kVirtualDeviceLag_s;
  lag_s_.store(std::clamp(lag_s, kVirtualDeviceLag_s, 1.0), std::memory_order_relaxed);
}

void ViewerDevice::start(double t_s) {
  previous_t_s_ = t_s;
  started_ = true;
  active_ = source();
}

bool ViewerDevice::paused() noexcept {
  const bool paused = !playing_.load(std::memory_order_relaxed) &&
                      step_requests_.load(std::memory_order_relaxed) == 0 &&
                      !(step_budget_s_.load(std::memory_order_relaxed) > 0.0);
  held_ = held_ || paused;
  return paused;
}

bool ViewerDevice::read(double t_s, haptics::DeviceSample& out) noexcept {
  if (timing_) {
    const std::int64_t now = wall_ns();
    // After a pause the gap since the last read is the pause, not a period.
    if (previous_wall_ns_ != 0 && !held_) timing_->record_period(double(now - previous_wall_ns_) * 1e-9);
    previous_wall_ns_ = now;
    read_wall_ns_ = now;
  }
  held_ = false;
  const double dt = std::max(0.0, t_s - previous_t_s_);
  previous_t_s_ = t_s;

  // How far the device's own clock moves this tick.
  double advance = playing_.load(std::memory_order_relaxed) ? speed_.load(std::memory_order_relaxed) * dt : 0.0;
  advance += double(step_requests_.exchange(0, std::memory_order_relaxed)) * dt_s_;
  if (advance == 0.0) {
    // A timed step while paused: at the device's speed, until its budget is played.
    const double budget = step_budget_s_.load(std::memory_order_relaxed);
    if (budget > 0.0) {
      const double rate = speed_.load(std::memory_order_relaxed);
      const double a = std::min(budget, (rate > 0.0 ? rate : 1.0) * dt);
      step_budget_s_.fetch_sub(a, std::memory_order_relaxed);
      advance = a;
    }
  }
  clock_s_ += advance;
  clock_published_.store(clock_s_, std::memory_order_relaxed);

  const ToolSource wanted = ToolSource(source_.load(std::memory_order_relaxed));
  if (wanted != active_) {
    if (wanted == ToolSource::kMouse) {
      mouse_target_ = pose_;
      ramp_from_ = pose_;
      ramp_len_s_ = 0.0;
    } else if (!tour_.empty()) {
      // Back to the script: travel over the terrain to where it left off.
      Tour::transit(transit_, 0.0, pose_, tour_.sample(script_time_s_), clearance_y_m_,
                    transit_speed_m_per_s_);
      transit_time_s_ = 0.0;
      in_transit_ = true;
    }
    active_ = wanted;
  }

  if (active_ == ToolSource::kMouse) {
    // The goal ramps from where it was to each new target over one frame.
    auto goal = [&] {
      const double u = ramp_len_s_ > 0.0 ? std::min(1.0, ramp_t_s_ / ramp_len_s_) : 1.0;
      return BladePose{lerp(ramp_from_.position_m, mouse_target_.position_m, u),
                       normalized(slerp(ramp_from_.orientation, mouse_target_.orientation, u))};
    };
    BladePose posted;
    if (target_.read(posted)) {
      ramp_from_ = goal();
      mouse_target_ = posted;
      ramp_t_s_ = 0.0;
      ramp_len_s_ = frame_interval_s_.load(std::memory_order_relaxed);
    }
    if (advance > 0.0) {
      ramp_t_s_ += advance;
      const BladePose g = goal();
      const double a = 1.0 - std::exp(-advance / lag_s_.load(std::memory_order_relaxed));
      pose_.position_m = lerp(pose_.position_m, g.position_m, a);
      pose_.orientation = normalized(slerp(pose_.orientation, g.orientation, a));
    }
  } else if (!tour_.empty()) {
    if (in_transit_) {
      transit_time_s_ += advance;
      const PoseLeg& last = transit_[2];
      const double end = last.start_s + last.duration_s;
      if (transit_time_s_ >= end) {
        in_transit_ = false;
        pose_ = tour_.sample(script_time_s_);
      } else {
        int i = transit_time_s_ < transit_[1].start_s ? 0 : (transit_time_s_ < last.start_s ? 1 : 2);
        pose_ = sample_leg(transit_[i], nullptr, transit_time_s_ - transit_[i].start_s);
      }
    } else {
      script_time_s_ = std::min(script_time_s_ + advance, tour_.duration_s());
      pose_ = tour_.sample(script_time_s_);
      if (script_time_s_ >= tour_.duration_s() && !script_finished_.load(std::memory_order_relaxed)) {
        script_finished_.store(true);
        if (pause_at_end_) playing_.store(false);
      }
    }
    script_time_published_.store(script_time_s_, std::memory_order_relaxed);
  }

  workspace_.fill_sample(pose_, out);
  return true;
}

void ViewerDevice::write(const haptics::DeviceCommand& command) noexcept {
  (void)command;
  if (timing_) timing_->record_compute(double(wall_ns() - read_wall_ns_) * 1e-9);
}

}  // namespace terracut::viewer
