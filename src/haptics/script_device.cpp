#include "terracut/haptics/script_device.hpp"

#include <algorithm>
#include <cmath>

#include "terracut/core/error.hpp"

namespace terracut::haptics {
namespace {

const Motion& checked(const Motion& cut) {
  if (std::string m = validate(cut); !m.empty()) throw InputError("cut '" + cut.name + "': " + m);
  return cut;
}

}  // namespace

DevicePath::DevicePath(const Motion& cut, const Workspace& workspace)
    : strokes_{checked(cut)}, starts_s_{0.0}, workspace_(workspace) {}

DevicePath::DevicePath(std::vector<Motion> strokes, double rate_hz, const Workspace& workspace)
    : strokes_(std::move(strokes)), rate_hz_(rate_hz), workspace_(workspace) {
  if (strokes_.empty()) throw InputError("a device path needs at least one cut");
  if (!(std::isfinite(rate_hz) && rate_hz > 0.0))
    throw InputError("a device path's rate must be finite and > 0");
  // Each stroke takes round(duration x rate) + 1 steps, as a batch run.
  std::int64_t steps = 0;
  for (const Motion& m : strokes_) {
    checked(m);
    starts_s_.push_back(double(steps) / rate_hz);
    starts_step_.push_back(steps);
    steps += std::llround(m.duration_s() * rate_hz) + 1;
  }
}

BladePose DevicePath::world_pose(double t_s) const {
  const std::size_t k = stroke_at(t_s);
  double local = t_s - starts_s_[k];
  if (rate_hz_ > 0.0) {
    const double step = t_s * rate_hz_;
    const double whole = std::round(step);
    if (std::abs(step - whole) < 1e-6) local = double(std::int64_t(whole) - starts_step_[k]) / rate_hz_;
  }
  return strokes_[k].sample(local);
}

std::size_t DevicePath::stroke_at(double t_s) const {
  // Half a step's margin: a tick at a stroke's start, to rounding, is its.
  const double margin = rate_hz_ > 0.0 ? 0.5 / rate_hz_ : 0.0;
  std::size_t k = 0;
  while (k + 1 < starts_s_.size() && t_s + margin >= starts_s_[k + 1]) ++k;
  return k;
}

Vec3 DevicePath::position_m(double t_s) const {
  return workspace_.to_device(world_pose(t_s).position_m);
}

Vec3 DevicePath::velocity_m_per_s(double t_s) const {
  const std::size_t s = stroke_at(t_s);
  const std::vector<Keyframe>& k = strokes_[s].keyframes;
  t_s -= starts_s_[s];
  if (k.size() < 2 || !(t_s >= k.front().t_s) || t_s >= k.back().t_s) return {};
  // The segment [k[i], k[i+1]) containing t_s.
  auto it = std::upper_bound(k.begin(), k.end(), t_s,
                             [](double t, const Keyframe& kf) { return t < kf.t_s; });
  const std::size_t i = static_cast<std::size_t>(it - k.begin()) - 1;
  const Vec3 world =
      (k[i + 1].pose.position_m - k[i].pose.position_m) * (1.0 / (k[i + 1].t_s - k[i].t_s));
  return workspace_.direction_to_device(world) * (1.0 / workspace_.mapping().scale);
}

Quat DevicePath::orientation(double t_s) const {
  return workspace_.orientation_to_device(world_pose(t_s).orientation);
}

double DevicePath::max_speed_m_per_s() const {
  double best = 0.0;
  for (const Motion& m : strokes_) {
    const std::vector<Keyframe>& k = m.keyframes;
    for (std::size_t i = 0; i + 1 < k.size(); ++i)
      best = std::max(best, length(k[i + 1].pose.position_m - k[i].pose.position_m) /
                                (k[i + 1].t_s - k[i].t_s));
  }
  return best / workspace_.mapping().scale;
}

ScriptDevice::ScriptDevice(DevicePath path) : path_(std::move(path)) {}

bool ScriptDevice::read(double t_s, DeviceSample& out) noexcept {
  const double t = t_s - start_t_s_;
  out.world_pose = path_.world_pose(t);
  out.has_world_pose = true;
  out.position_m = path_.position_m(t);
  out.orientation = path_.orientation(t);
  out.has_orientation = true;
  out.buttons = 0;
  // A new stroke: the tool was lifted between the cuts.
  const std::size_t stroke = path_.stroke_at(t);
  out.lifted = stroke != stroke_;
  stroke_ = stroke;
  return true;
}

void ScriptDevice::write(const DeviceCommand& command) noexcept {
  ++writes_;
  const double f = length(command.force_n);
  if (f > max_force_n_) max_force_n_ = f;
}

std::vector<DeviceStat> ScriptDevice::stats() const {
  return {{"forces_written", double(writes_)}, {"max_force_n", max_force_n_}};
}

}  // namespace terracut::haptics
