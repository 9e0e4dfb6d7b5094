// Shared set-ups of the haptics tests: the trench scenario, and a device
// wrapper that injects bad or missing samples.
#pragma once

#include <cmath>
#include <filesystem>
#include <functional>
#include <memory>
#include <vector>

#include "terracut/haptics/device.hpp"
#include "terracut/haptics/session.hpp"

namespace terracut::haptics::test {

inline std::filesystem::path trench_path() {
  return std::filesystem::path(TERRACUT_SOURCE_DIR) / "scenarios/trench_dry_sand.yaml";
}

inline const HapticScenario& trench() {
  static const HapticScenario s = load_haptic_scenario(trench_path());
  return s;
}

/// Wraps a device: ticks for which `bad(tick)` is true read a NaN position,
/// ticks for which `silent(tick)` is true read nothing. Every command is kept.
class FaultyDevice final : public Device {
 public:
  FaultyDevice(Device& inner, std::function<bool(std::int64_t)> bad,
               std::function<bool(std::int64_t)> silent)
      : inner_(inner), bad_(std::move(bad)), silent_(std::move(silent)) {
    commands.reserve(100000);
  }
  std::string_view kind() const override { return inner_.kind(); }
  void start(double t_s) override { inner_.start(t_s); }
  bool read(double t_s, DeviceSample& out) noexcept override {
    const std::int64_t tick = reads_++;
    DeviceSample s = out;
    const bool got = inner_.read(t_s, s);
    if (silent_ && silent_(tick)) return false;
    if (bad_ && bad_(tick)) s.position_m.y = std::nan("");
    out = s;
    return got;
  }
  void write(const DeviceCommand& command) noexcept override {
    inner_.write(command);
    if (commands.size() < commands.capacity()) commands.push_back(command);
  }
  std::vector<DeviceCommand> commands;

 private:
  Device& inner_;
  std::function<bool(std::int64_t)> bad_;
  std::function<bool(std::int64_t)> silent_;
  std::int64_t reads_ = 0;
};

}  // namespace terracut::haptics::test
