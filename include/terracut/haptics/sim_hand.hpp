// The simulated operator hand (`sim` device): a point mass (hand plus the
// device's moving parts) with the device's own damping, pulled by an arm
// (spring-damper) toward a target moving along the cut's path. The force the
// loop renders acts on it, so the loop is closed without hardware: the hand
// lags and slows where the soil resists, and an unstable rendering would show
// as growing motion and energy.
//
// Dynamics, device frame, per axis-free vector form:
//   m a = k (x_t - x) + c (v_t - v) - b v + F
// with x_t, v_t the target's position and velocity, k, c the arm's stiffness
// and damping, b the device's inherent damping, F the rendered force (held
// between writes, as a device driver holds it). Integrated by semi-implicit
// (symplectic) Euler with `substeps` sub-steps per loop period.
#pragma once

#include <cstdint>

#include "terracut/haptics/settings.hpp"
#include "terracut/haptics/device.hpp"
#include "terracut/haptics/script_device.hpp"

namespace terracut::haptics {

/// The hand's physics; deterministic for a given sequence of calls.
class SimHand {
 public:
  /// params: validated (validate(HapticSettings)); inherent_damping_n_s_per_m:
  /// the device's damping b (forces.device.inherent_damping_n_s_per_m), >= 0;
  /// rate_hz: the loop rate, sets the sub-step size.
  SimHand(const SimHandParams& params, double inherent_damping_n_s_per_m, DevicePath path,
          double rate_hz);

  /// Puts the hand at rest at the path's start plus params.start_offset_m; time t_s.
  void reset(double t_s);

  /// Integrates from the current time to t_s (seconds, path time) with the
  /// force applied_n (device frame, newtons) held constant. A step back in
  /// time or a non-finite time is ignored; a gap of more than 0.25 s (a
  /// stalled caller) is integrated as 0.25 s.
  void advance_to(double t_s, Vec3 applied_n) noexcept;

  double t_s() const { return t_s_; }
  Vec3 position_m() const { return x_; }
  Vec3 velocity_m_per_s() const { return v_; }
  const DevicePath& path() const { return path_; }
  const SimHandParams& params() const { return params_; }

  /// Target position and velocity now (device frame).
  Vec3 target_m() const { return path_.position_m(t_s_); }
  Vec3 target_velocity_m_per_s() const { return path_.velocity_m_per_s(t_s_); }

  /// Energy of the hand relative to its target, J:
  /// 0.5 m |v - v_t|^2 + 0.5 k |x - x_t|^2. For a fixed target it is the
  /// hand's whole mechanical energy.
  double tracking_energy_j() const;
  /// Work done on the hand by the rendered force since reset, J (sum of
  /// F . dx over the sub-steps). Negative: the rendering took energy out.
  double rendered_work_j() const { return rendered_work_j_; }
  /// Largest |x - x_t| since reset, device metres.
  double max_tracking_error_m() const { return max_error_m_; }
  /// Largest hand speed since reset, device m/s.
  double max_speed_m_per_s() const { return max_speed_; }

 private:
  SimHandParams params_;
  double damping_b_ = 0.0;
  DevicePath path_;
  double substep_s_ = 0.0;
  double t_s_ = 0.0;
  Vec3 x_{};
  Vec3 v_{};
  double rendered_work_j_ = 0.0;
  double max_error_m_ = 0.0;
  double max_speed_ = 0.0;
};

/// The `sim` device: reads are the hand's state after integrating up to the
/// read time with the last force written. The orientation is the path's
/// (the hand turns the handle as the cut's keyframes say).
class SimHandDevice final : public Device {
 public:
  explicit SimHandDevice(SimHand hand);

  std::string_view kind() const override { return "sim"; }
  void start(double t_s) override;
  bool read(double t_s, DeviceSample& out) noexcept override;
  void write(const DeviceCommand& command) noexcept override;
  std::vector<DeviceStat> stats() const override;

  const SimHand& hand() const { return hand_; }

 private:
  SimHand hand_;
  double start_t_s_ = 0.0;
  Vec3 force_n_{};
  double max_tracking_energy_j_ = 0.0;
};

}  // namespace terracut::haptics
