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
    : cut_(checked(cut)), workspace_(workspace) {}

Vec3 DevicePath::position_m(double t_s) const {
  return workspace_.to_device(cut_.sample(t_s).position_m);
}

Vec3 DevicePath::velocity_m_per_s(double t_s) const {
  const std::vector<Keyframe>& k = cut_.keyframes;
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
  return workspace_.orientation_to_device(cut_.sample(t_s).orientation);
}

double DevicePath::max_speed_m_per_s() const {
  const std::vector<Keyframe>& k = cut_.keyframes;
  double best = 0.0;
  for (std::size_t i = 0; i + 1 < k.size(); ++i)
    best = std::max(
        best, length(k[i + 1].pose.position_m - k[i].pose.position_m) / (k[i + 1].t_s - k[i].t_s));
  return best / workspace_.mapping().scale;
}

ScriptDevice::ScriptDevice(DevicePath path) : path_(std::move(path)) {}

bool ScriptDevice::read(double t_s, DeviceSample& out) noexcept {
  const double t = t_s - start_t_s_;
  out.position_m = path_.position_m(t);
  out.orientation = path_.orientation(t);
  out.has_orientation = true;
  out.buttons = 0;
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
