// Shared set-ups of the haptics tests: the trench scenario, a loop over a
// simulation of it, and a device wrapper that injects bad or missing samples.
#pragma once

#include <cmath>
#include <filesystem>
#include <functional>
#include <memory>
#include <vector>

#include "terracut/core/step_listener.hpp"
#include "terracut/haptics/device.hpp"
#include "terracut/haptics/loop.hpp"
#include "terracut/haptics/settings_yaml.hpp"
#include "terracut/io/scenario.hpp"

namespace terracut::haptics::test {

inline std::filesystem::path trench_path() {
  return std::filesystem::path(TERRACUT_SOURCE_DIR) / "scenarios/trench_dry_sand.yaml";
}

/// A scenario and its `haptics:` settings.
struct HapticScenario {
  io::Scenario scenario;
  HapticSettings haptics;
};

/// Reads a scenario file with its `haptics:` section.
inline HapticScenario load_with_haptics(const std::filesystem::path& path) {
  SettingsReader reader;
  io::SectionReader* const sections[] = {&reader};
  HapticScenario out{io::load_scenario(path, sections), {}};
  out.haptics = reader.settings;
  return out;
}

inline const HapticScenario& trench() {
  static const HapticScenario s = load_with_haptics(trench_path());
  return s;
}

/// A haptic loop and the simulation it steps (which a loop does not own:
/// in the programs, the session layer's world does). The loop goes first.
struct LoopRig {
  std::unique_ptr<Simulation> sim;
  std::unique_ptr<HapticLoop> loop;
  HapticLoop* operator->() const { return loop.get(); }
  HapticLoop& operator*() const { return *loop; }
};

/// Options of a synchronous test loop: `ticks` ticks, every record kept,
/// no real-time request, an optional snapshot exchange.
inline LoopOptions test_loop_options(std::int64_t ticks, SnapshotExchange* snapshot = nullptr) {
  LoopOptions o;
  o.ticks = ticks;
  o.record_capacity = std::size_t(ticks);
  o.realtime = false;
  o.snapshot = snapshot;
  return o;
}

/// A loop over a fresh simulation of sc at the loop's rate, with the given
/// step listeners added to the simulation first. Throws as LoopParams and
/// HapticLoop do.
inline LoopRig make_loop_rig(const HapticSettings& settings, const io::Scenario& sc,
                             Quat default_orientation, Device& device, const LoopOptions& options,
                             const std::vector<StepListener*>& listeners = {}) {
  const LoopParams params(settings, sc.blade, sc.rate_hz);
  LoopRig rig;
  rig.sim = std::make_unique<Simulation>(io::sim_params(sc, params.rate_hz()),
                                         io::build_initial_heights(sc));
  for (StepListener* l : listeners) rig.sim->add_listener(*l);
  rig.loop = std::make_unique<HapticLoop>(params, *rig.sim, default_orientation, device, options);
  return rig;
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
