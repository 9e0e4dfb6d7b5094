#include "terracut/haptics/sim_hand.hpp"

#include <algorithm>
#include <cmath>

namespace terracut::haptics {
namespace {

// A longer gap than this (a stalled caller) is integrated as this much time.
constexpr double kMaxGapS = 0.25;

}  // namespace

SimHand::SimHand(const SimHandParams& params, double inherent_damping_n_s_per_m, DevicePath path,
                 double rate_hz)
    : params_(params),
      damping_b_(inherent_damping_n_s_per_m),
      path_(std::move(path)),
      substep_s_(1.0 / (rate_hz * params.substeps)) {
  reset(0.0);
}

void SimHand::reset(double t_s) {
  t_s_ = t_s;
  x_ = path_.position_m(t_s) + params_.start_offset_m;
  v_ = {};
  rendered_work_j_ = 0.0;
  max_error_m_ = length(x_ - path_.position_m(t_s));
  max_speed_ = 0.0;
}

void SimHand::advance_to(double t_s, Vec3 applied_n) noexcept {
  if (!(t_s > t_s_) || !std::isfinite(t_s)) return;
  const bool force_ok = is_finite(applied_n);
  const Vec3 force = force_ok ? applied_n : Vec3{};
  // Integrate only the last kMaxGapS of a long gap; the target jumps ahead.
  const double gap = std::min(t_s - t_s_, kMaxGapS);
  const double start = t_s - gap;
  const int n = std::max(1, static_cast<int>(std::ceil(gap / substep_s_ - 1e-9)));
  const double dt = gap / n;
  const double m = params_.mass_kg;
  const double k = params_.stiffness_n_per_m;
  const double c = params_.damping_n_s_per_m;
  for (int i = 1; i <= n; ++i) {
    const double t = start + dt * i;
    const Vec3 target = path_.position_m(t);
    const Vec3 target_v = path_.velocity_m_per_s(t);
    const Vec3 total = (target - x_) * k + (target_v - v_) * c - v_ * damping_b_ + force;
    // Semi-implicit Euler: new velocity first, then the position with it.
    v_ = v_ + total * (dt / m);
    const Vec3 dx = v_ * dt;
    x_ = x_ + dx;
    rendered_work_j_ += dot(force, dx);
    max_error_m_ = std::max(max_error_m_, length(x_ - target));
    max_speed_ = std::max(max_speed_, length(v_));
  }
  t_s_ = t_s;
}

double SimHand::tracking_energy_j() const {
  const Vec3 e = x_ - target_m();
  const Vec3 ev = v_ - target_velocity_m_per_s();
  return 0.5 * params_.mass_kg * dot(ev, ev) + 0.5 * params_.stiffness_n_per_m * dot(e, e);
}

SimHandDevice::SimHandDevice(SimHand hand) : hand_(std::move(hand)) {}

void SimHandDevice::start(double t_s) {
  start_t_s_ = t_s;
  hand_.reset(0.0);
  force_n_ = {};
  max_tracking_energy_j_ = hand_.tracking_energy_j();
}

bool SimHandDevice::read(double t_s, DeviceSample& out) noexcept {
  hand_.advance_to(t_s - start_t_s_, force_n_);
  max_tracking_energy_j_ = std::max(max_tracking_energy_j_, hand_.tracking_energy_j());
  out.position_m = hand_.position_m();
  out.orientation = hand_.path().orientation(hand_.t_s());
  out.has_orientation = true;
  out.buttons = 0;
  return true;
}

void SimHandDevice::write(const DeviceCommand& command) noexcept { force_n_ = command.force_n; }

std::vector<DeviceStat> SimHandDevice::stats() const {
  return {{"hand_rendered_work_j", hand_.rendered_work_j()},
          {"hand_max_tracking_error_m", hand_.max_tracking_error_m()},
          {"hand_max_tracking_energy_j", max_tracking_energy_j_},
          {"hand_max_speed_m_per_s", hand_.max_speed_m_per_s()},
          {"hand_final_tracking_error_m", length(hand_.position_m() - hand_.target_m())}};
}

}  // namespace terracut::haptics
