// The fixed-step cutting simulation: parameters (read-only during a run) apart
// from state (heights, blade pose, time, counters, timers).
//
// One step, at the fixed rate:
//   1. begin_step(pose): the blade moves to `pose`; contact is measured against
//      the terrain as it was before this step's cut, so a cut never hides the
//      contact that caused it.
//   2. finish_step(): the region the edge swept since the previous pose is
//      cut; with SoilModel::kFlow the cut soil is put down ahead of the
//      blade and slopes relax to the angle of repose (soil.hpp); the soil's
//      physical force on the tool is computed from the terrain it leaves
//      and the tool's motion over the step (tool_force.hpp); then every
//      StepListener added (step_listener.hpp: the rigid-body
//      world, recorders, ...) sees the step's output and the rectangle it
//      changed, and may put a force on the tool, which joins the force.
// step(pose) does both. A step allocates nothing (nor may its listeners).
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "terracut/core/cut.hpp"
#include "terracut/core/ranges.hpp"
#include "terracut/core/soil.hpp"
#include "terracut/core/step_listener.hpp"
#include "terracut/core/tool_force.hpp"

namespace terracut {

/// Simulation parameters; validated at construction, read-only during a run.
struct SimParams {
  GridSpec grid{};
  Representation representation = Representation::kSurface;
  /// The fixed step rate, Hz, in (0, 1e6]: the one rate of a run (the
  /// scenario's rate_hz). A haptic loop steps the simulation at it too,
  /// unless its program overrides it (session::WorldOptions::rate_hz).
  double rate_hz = 1000.0;
  BladeSpec blade{};
  /// A step whose rotation would move a blade end off its straight path by
  /// more than this fraction of a cell is split into sub-steps (slerp), so a
  /// fast rotation still sweeps its true arc. In (0, 1].
  double max_arc_error_cells = 0.25;
  /// The soil (the scenario's `soil:` section): its material, which every
  /// force and the flow read, and what happens to what the blade cuts
  /// (soil.hpp); kVanish by default.
  SoilFlowParams soil{};
};

/// The ranges of SimParams' own numbers (core/ranges.hpp): validate()
/// checks the fields through this table and the scenario reader reads the
/// file's same fields through its entries. The grid and the soil have their
/// own checks (validate(GridSpec), kSoilFlowRanges); the blade's rake is the
/// earthmoving model's entry, which validate() checks with the material.
inline constexpr Range kSimParamsRanges[] = {
    kRateRange,
    {"max_arc_error_cells", 0.0, 1.0, RangeEnds::kOpenLow},
    {"blade.length_m", 0.0, kRangeMax, RangeEnds::kOpenLow},
    at_path(find_range(kEarthmovingRanges, "rake_angle_deg"), "blade.rake_angle_deg"),
    {"blade.edge_thickness_m", 0.0, kRangeMax, RangeEnds::kOpenLow},
    {"blade.height_m", 0.0, kRangeMax, RangeEnds::kOpenLow},  // (or infinity: unbounded, the default)
    {"blade.bucket.depth_m", 0.0, kRangeMax, RangeEnds::kClosed},  // 0: no bucket
    {"blade.bucket.height_m", 0.0, kRangeMax, RangeEnds::kOpenLow},
};

/// Returns an empty string when params are valid, else a message naming the field.
std::string validate(const SimParams& params);

/// Wall-clock time of each phase of the last step, seconds.
struct StepTimers {
  double contact_s = 0.0;
  double cut_s = 0.0;
  double soil_s = 0.0;       ///< displacement and relaxation (kFlow)
  double force_s = 0.0;      ///< the physical force on the tool (tool_force.hpp)
  double listeners_s = 0.0;  ///< all step listeners together (e.g. the Bullet world)
  double total_s = 0.0;
};

/// The outcome of the last step.
struct StepOutput {
  std::int64_t step = 0;     ///< index of the step, from 0
  double t_s = 0.0;          ///< simulation time of the step, seconds (step / rate)
  BladePose pose{};          ///< blade pose during the step
  Segment edge{};            ///< cutting edge during the step, world metres
  ContactResult contact{};   ///< measured before the cut
  CutResult cut{};           ///< what the sweep since the previous pose removed
  SoilStepResult soil{};     ///< what the soil phase moved (kFlow; empty with kVanish)
  /// Every sample whose height the step changed: the cut's and the soil
  /// phase's rectangles together. Whoever caches heights (the Bullet world,
  /// a renderer, a network sender) reads this rectangle.
  Rect changed{};
  int substeps = 0;          ///< sweep sub-steps used (0 when the blade was lifted)
  /// Sum of the step listeners' forces on the tool (StepListener::on_step),
  /// world N; zero without listeners.
  Vec3 listener_force_world_n{};
  /// The tool's motion over the step, from the previous pose to this one
  /// (zero at the first step of a stroke, after lift()).
  ToolMotion motion{};
  /// The physical force on the tool, world N, with its parts
  /// (tool_force.hpp): the soil's, from the terrain after the cut and the
  /// soil phase and the motion above, and the listeners' (force.bodies_n,
  /// filled after they ran; total_n includes it). Nothing a haptic device
  /// renders changes it.
  ToolForce force{};
  StepTimers timers{};
};

class Simulation {
 public:
  /// Throws InputError naming the bad field when params or heights are invalid.
  Simulation(const SimParams& params, std::vector<float> initial_heights_m);

  const SimParams& params() const { return params_; }
  /// The terrain, read-only: the simulation owns the heights and changes
  /// them itself (steps, edit_heights, reset) or for a listener (below).
  const HeightGrid& grid() const { return grid_; }

  /// Lifts the blade out of the soil: the next step starts a new stroke and
  /// sweeps nothing from the previous pose (used between separate cuts).
  /// Tells every listener (StepListener::on_lift).
  void lift();

  /// Adds a listener, run at the end of every finish_step after those added
  /// before it. Not owned: it must outlive the simulation or be removed
  /// first. Adding one twice is refused (std::logic_error). Not during a step.
  void add_listener(StepListener& listener);
  /// Removes a listener (nothing when it was not added). Not during a step.
  void remove_listener(StepListener& listener);
  /// The listeners, in the order they run.
  const std::vector<StepListener*>& listeners() const { return listeners_; }

  /// The soil phase's state (kFlow), or null with kVanish.
  const SoilFlow* soil() const { return soil_.get(); }
  /// The soil phase, to set its obstacles (a step listener between steps).
  SoilFlow* soil() { return soil_.get(); }

  /// Phase 1: move the blade and measure contact before any cut.
  const StepOutput& begin_step(const BladePose& pose);
  /// Phase 2: cut what the edge swept since the previous pose, run the
  /// listeners; advance time.
  const StepOutput& finish_step();
  /// Both phases.
  const StepOutput& step(const BladePose& pose) {
    begin_step(pose);
    return finish_step();
  }

  // --- A step listener that changes the terrain -------------------------
  // (Jolt's HeightFieldShape::SetHeights: the owner makes the edit, so that
  // whoever caches the heights hears of it.) The Bullet world lowers the
  // soil a released buried body stood in, pushes soil out of the ring round
  // a body and keeps heights inside its bounds. It does so only through
  // these, from inside its own callbacks (on_step, on_edit; std::logic_error
  // anywhere else: an internal error), reads the heights with grid(), and
  // reports what it changed during a step with include_changed.

  /// Lowers sample i (index = r * cols + c) to height_m when that is lower,
  /// never below 0 (the rigid floor); returns the height removed, metres (0
  /// when nothing changed).
  float lower_sample(std::int64_t i, float height_m);
  /// Moves amount_m metres of height from sample `from` to sample `to` (soil
  /// pushed aside): the volume is kept. amount_m in (0, height at from].
  void move_height(std::int64_t from, std::int64_t to, float amount_m);
  /// For a step listener that changed heights during its on_step: adds the
  /// rectangle to this step's StepOutput::changed, which the listeners after
  /// it and whoever reads last() see, and the soil phase re-examines it (and
  /// its neighbours) from the next step on. std::logic_error outside a step.
  void include_changed(const Rect& rect);

  const StepOutput& last() const { return out_; }
  std::int64_t step_count() const { return step_count_; }
  double time_s() const { return double(step_count_) / params_.rate_hz; }
  /// Total volume cut since construction or reset, cubic metres.
  double removed_volume_m3() const { return removed_volume_m3_; }

  /// Restores the initial terrain, time and counters (and the force's
  /// material to the parameters' soil), and tells every listener that the
  /// whole grid changed (StepListener::on_edit).
  void reset();

  /// The material the physical force is computed with (StepOutput::force:
  /// cutting, surcharge, penetration, twist, a bucket's load); starts as
  /// params().soil.material. The soil flow keeps the parameters' material
  /// (its angle of repose).
  const SoilMaterial& force_material() const { return tool_params_.earthmoving.soil; }
  /// Replaces it between steps: what a teleoperation station's local model
  /// does when it adopts an estimate of the remote's soil, or a remote world
  /// whose soil changes along the path (session/mmt.hpp). The one exception
  /// to the parameters being read-only during a run, and through the owner:
  /// the next step's force uses it. Throws InputError naming the field when
  /// the material is invalid (validate(SoilMaterial)) or the blade's rake
  /// with its friction angles leaves no failure wedge (rake + delta + phi
  /// must be < 179 degrees); std::logic_error during a step.
  void set_force_material(const SoilMaterial& material);

  /// Replaces the heights of a rectangle of samples between steps (an
  /// excavation made by hand, a terrain loaded from elsewhere): values_m
  /// holds (r1 - r0) x (c1 - c0) heights, row-major, metres, finite and >= 0;
  /// the rectangle must lie inside the grid and not be empty. removed is
  /// updated (initial - height); with SoilModel::kFlow the edited samples
  /// and their neighbours are relaxed from the next step on; every listener
  /// hears of it (StepListener::on_edit). Returns the rectangle written.
  /// Throws InputError naming the bad argument or sample (nothing is
  /// written then); std::logic_error during a step.
  Rect edit_heights(const Rect& rect, std::span<const float> values_m);

 private:
  /// StepListener::on_edit for every listener (they may change heights there).
  void tell_edited(const Rect& changed);

  SimParams params_;
  HeightGrid grid_;
  BladePose previous_pose_{};
  bool has_previous_ = false;
  bool in_step_ = false;
  bool in_listener_ = false;  // a listener's on_step or on_edit is running
  std::int64_t step_count_ = 0;
  double removed_volume_m3_ = 0.0;
  StepOutput out_{};
  double begin_clock_s_ = 0.0;
  std::vector<StepListener*> listeners_;
  std::unique_ptr<SoilFlow> soil_;  // kFlow only
  ToolForceParams tool_params_{};   // derived from params_ once
  double lookahead_m_ = 0.0;        // where the soil ahead is read (depth_lookahead_m)
  Vec3 previous_velocity_m_per_s_{};
  bool has_previous_velocity_ = false;
  bool velocity_valid_ = false;  // this step's motion came from a previous pose
  Vec3 heading_{};               // the stroke's latest horizontal direction of motion
};

}  // namespace terracut
