// The one hook into a step: something that runs in every step of a
// Simulation (in the spirit of Jolt's PhysicsStepListener). The rigid-body
// world, a recorder, a network sender, a soil estimator: each attaches to
// the simulation the same way, whichever program drives it (a batch run, the
// haptic loop, the viewer's loop, the Python module).
//
// A step is a pipeline (simulation.hpp): pose -> contact (before the cut) ->
// cut -> [soil flow, when it exists] -> listeners. The listeners run at the
// end of Simulation::finish_step, in the order they were added, on the
// stepping thread; each sees the step's output, including the rectangle of
// samples the step changed (StepOutput::changed), and may put a force on
// the tool, which the step sums into StepOutput::listener_force_world_n (the
// haptic loop adds it to the force models' force before device scaling and
// safety).
#pragma once

#include "terracut/core/grid.hpp"
#include "terracut/core/math.hpp"

namespace terracut {

struct StepOutput;

class StepListener {
 public:
  virtual ~StepListener() = default;

  /// One step has cut the terrain. out: the step's pose, contact, cut and
  /// changed rectangle (valid during the call). Returns the listener's force
  /// on the tool, world N (zero when it has none; a non-finite value is
  /// passed on for the haptic loop's safety limiter to catch). Runs inside
  /// the real-time step: once warm it must not allocate, block or throw.
  virtual Vec3 on_step(const StepOutput& out) noexcept = 0;

  /// The blade was lifted (Simulation::lift): the next pose is a jump, not a
  /// sweep.
  virtual void on_lift() noexcept {}

  /// Heights inside `changed` were edited outside a step
  /// (Simulation::edit_heights): whoever caches them refreshes that
  /// rectangle. Not called during a step.
  virtual void on_edit(const Rect& changed) noexcept { (void)changed; }
};

}  // namespace terracut
