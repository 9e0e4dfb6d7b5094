// The rigid bodies of a scenario as a step listener: a Bullet TerrainWorld
// (terrain_world.hpp) stepped at the end of every Simulation step, whatever
// drives the simulation (terracut run, the haptic loop, the viewer's loop).
// It is the one Bullet adapter of terracut.
//
// Per step (on the stepping thread, allocation-free once Bullet is warm):
// TerrainWorld::step(out) (the step's changed rectangle -> bodies woken and
// stale contacts dropped; the tool plate to the blade pose; one Bullet step
// of 1 / rate), then a row per body to bodies.csv when one is written, and
// the bodies' force on the tool plate is returned to the step (the haptic
// loop adds it to the force the operator feels). With soil that flows it
// turns the world's piles on (TerrainWorldParams::pile, with the soil's
// repose angle as the pile's friction angle) and sets the soil's obstacles
// (SoilFlow::set_obstacles) to the bodies' bounding boxes and a ring of one
// sample round them (TerrainWorld::soil_obstacle), for the next step. It also tells the viewer where the
// bodies are (BodySource).
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <vector>

#include "terracut/bullet/bodies_csv.hpp"
#include "terracut/bullet/terrain_world.hpp"
#include "terracut/core/bodies.hpp"
#include "terracut/core/simulation.hpp"
#include "terracut/core/soil.hpp"
#include "terracut/core/step_listener.hpp"

namespace terracut::bullet {

/// What the listener writes.
struct BodiesListenerOptions {
  /// bodies.csv (bodies_csv.hpp format): the bodies' state before the first
  /// step (t = 0) and after every step; empty: no file. The folder must exist.
  std::filesystem::path csv_path;
  /// The Bullet world's parameters (heightfield bounds, plate, gravity, ...).
  TerrainWorldParams world{};
};

/// What the bodies did over a run: the figures of summary.json's "bodies" entry.
struct BodiesReport {
  int count = 0;                        ///< bodies simulated
  double peak_tool_force_n = 0.0;       ///< largest |force of the bodies on the tool|, world N
  std::int64_t steps_touching_tool = 0;  ///< steps with at least one tool contact point
  std::int64_t steps = 0;               ///< Bullet steps taken
  double physics_mean_s = 0.0;          ///< mean wall-clock time of a Bullet step, seconds
  double physics_max_s = 0.0;           ///< largest wall-clock time of a Bullet step, seconds
  double min_height_m = 0.0;            ///< the heightfield's bounds, metres above ground
  double max_height_m = 0.0;
  std::int64_t samples_clamped = 0;     ///< samples clamped to the bounds over the run
  double soil_clamped_m3 = 0.0;         ///< the soil those clamps deleted, m^3
  std::vector<std::string> names;       ///< per body, in scenario order
  std::vector<Vec3> final_position_m;   ///< per body, world metres, at the end
};

class BodiesListener final : public StepListener, public BodySource {
 public:
  /// Builds the Bullet world over the simulation's terrain and adds itself to
  /// the simulation's listeners; removes itself when destroyed. The
  /// simulation must outlive the listener. Throws InputError naming the body
  /// (bodies[i] (NAME): ...) or the file (bodies.csv that cannot be created).
  BodiesListener(Simulation& sim, std::vector<BodySpec> bodies,
                 const BodiesListenerOptions& options = {});
  ~BodiesListener() override;
  BodiesListener(const BodiesListener&) = delete;
  BodiesListener& operator=(const BodiesListener&) = delete;

  // StepListener
  Vec3 on_step(const StepOutput& out) noexcept override;
  void on_lift() noexcept override;
  /// An edit between steps: the Bullet world refreshes the rectangle
  /// (TerrainWorld::terrain_changed: bounds, wakes the bodies over it).
  void on_edit(const Rect& changed) noexcept override;

  // BodySource
  int body_total() const noexcept override { return world_->body_count(); }
  int write_bodies(std::span<BodyView> out) const noexcept override;

  /// Flushes and closes bodies.csv (idempotent). Throws InputError naming the
  /// file when a write failed.
  void finish();

  /// The figures of the run so far.
  BodiesReport report() const;
  /// The name of the csv file written ("bodies.csv"), or empty when none.
  std::string csv_name() const;
  /// Rows written to the csv file so far (0 without one).
  std::int64_t csv_rows() const { return csv_ ? csv_->rows_written() : 0; }

  const TerrainWorld& world() const { return *world_; }
  TerrainWorld& world() { return *world_; }

 private:
  Simulation& sim_;
  std::vector<BodySpec> bodies_;
  BodiesListenerOptions options_;
  std::vector<Vec3> half_extents_;
  std::unique_ptr<TerrainWorld> world_;
  std::unique_ptr<BodiesCsvWriter> csv_;
  std::vector<SoilObstacle> obstacles_;  // the bodies' boxes, for soil that flows
  double peak_tool_force_n_ = 0.0;
  std::int64_t steps_touching_ = 0;
  std::int64_t steps_ = 0;
  double physics_sum_s_ = 0.0;
  double physics_max_s_ = 0.0;
};

}  // namespace terracut::bullet
