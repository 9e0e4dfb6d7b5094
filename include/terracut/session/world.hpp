// The simulated world of a run, built once from a scenario and shared by
// every program: the Simulation (terrain, representation, blade, rate) and
// the step listeners attached to it (today: the rigid bodies, a Bullet world
// over the same height array, when the scenario has `bodies:`). A batch run
// steps it directly; the haptic loop and the viewer's loop step it through
// HapticLoop. Whatever drives it, the same listeners see every step.
#pragma once

#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>

#include "terracut/core/bodies.hpp"
#include "terracut/core/simulation.hpp"
#include "terracut/session/scenario.hpp"

namespace terracut::bullet {
class BodiesListener;
struct BodiesReport;
}  // namespace terracut::bullet

namespace terracut::session {

/// True when this build has the rigid-body engine (Bullet).
bool bodies_available();

/// The message of the InputError a build without Bullet gives for a
/// scenario with bodies (the one place it is written).
std::string bodies_unavailable_message();

/// How to build a world.
struct WorldOptions {
  /// The simulation's step rate, Hz; nullopt: the scenario's rate_hz (the
  /// one rate). A haptic loop gives its own, LoopParams::rate_hz(): the
  /// scenario's, or its program's override (`terracut haptics --rate`).
  std::optional<double> rate_hz;
  /// Where the bodies' per-step states go (bodies.csv); empty: not written.
  /// Only used when the scenario has bodies; the folder must exist.
  std::filesystem::path bodies_csv;
  /// The arm's force limit at the tool, N (the remote's
  /// mmt.remote.arm_force_limit_n); 0 = none. With bodies, the Bullet tool
  /// plate becomes a force-limited servo (bullet::ToolPlateSpec::force_limit_n).
  double arm_force_limit_n = 0.0;
};

/// Where a force-limited arm's plate is (World::limited_arm).
struct ArmState {
  BladePose pose{};      ///< the blade pose the plate is at after the last step
  bool stalled = false;  ///< its servo's force reached the limit in the last step
};

class World {
 public:
  /// Builds the simulation and its listeners. Throws InputError naming the
  /// field (a bad body, a simulation parameter) or bodies_unavailable_message()
  /// when the scenario has bodies and this build has no Bullet.
  World(const Scenario& scenario, const WorldOptions& options = {});
  ~World();
  World(const World&) = delete;
  World& operator=(const World&) = delete;

  Simulation& simulation() { return *sim_; }
  const Simulation& simulation() const { return *sim_; }

  /// The rigid bodies' listener as a BodySource (for viewer frames), or null
  /// when the scenario has none.
  const BodySource* bodies() const;
  /// The Bullet listener, or null when the scenario has no bodies.
  bullet::BodiesListener* bodies_listener() { return bodies_.get(); }
  const bullet::BodiesListener* bodies_listener() const { return bodies_.get(); }

  /// The heights a depth camera looking straight down at the world would
  /// see over rect (inside the grid, not empty): out gets rect.area()
  /// values, row-major, metres above ground: the soil's height, or the top
  /// of a rigid body over the sample where that is higher (a buried body is
  /// under the soil until the blade reaches it). Allocation-free.
  void sense_heights(const Rect& rect, std::span<float> out) const;

  /// The samples under the bodies that moved since the last call (one more
  /// all round; empty without bodies or when none moved): where the
  /// camera's view may have changed although the soil did not.
  Rect take_moved_body_rect();

  /// With bodies and an arm force limit (WorldOptions::arm_force_limit_n):
  /// where the force-limited plate is after the last step (it stops short
  /// of the blade pose against a body it cannot move); nullopt otherwise.
  std::optional<ArmState> limited_arm() const;

  /// After the run: flushes and closes the listeners' files (bodies.csv).
  /// Throws InputError naming a file that could not be written.
  void finish();

 private:
  std::unique_ptr<Simulation> sim_;
  std::unique_ptr<bullet::BodiesListener> bodies_;
};

}  // namespace terracut::session
