// The rigid bodies as a step listener. See bodies_listener.hpp.
#include "terracut/bullet/bodies_listener.hpp"

#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <cmath>

namespace terracut::bullet {

BodiesListener::BodiesListener(Simulation& sim, std::vector<BodySpec> bodies,
                               const BodiesListenerOptions& options)
    : sim_(sim), bodies_(std::move(bodies)), options_(options) {
  // Soil that flows banks against the bodies and presses on them: the
  // simulation's soil material gives the pile's unit weight, and its angle
  // of repose is the loose pile's friction angle.
  // The soil material holds buried bodies (their break-out force, with a
  // force-limited tool plate).
  {
    const SoilMaterial& material = sim_.params().soil.material;
    options_.world.break_out.unit_weight_n_per_m3 = material.unit_weight_n_per_m3;
    options_.world.break_out.cohesion_pa = material.cohesion_pa;
    options_.world.break_out.friction_angle_deg = material.internal_friction_deg;
  }
  if (sim_.soil()) {
    const SoilMaterial& material = sim_.params().soil.material;
    options_.world.pile.enabled = true;
    options_.world.pile.unit_weight_n_per_m3 = material.unit_weight_n_per_m3;
    options_.world.pile.friction_angle_deg = material.repose_deg;
  }
  world_ = std::make_unique<TerrainWorld>(sim, bodies_, options_.world);
  // Shapes and sizes never change: kept for the viewer's frames.
  for (const BodySpec& b : bodies_) half_extents_.push_back(half_extents_m(b));
  if (!options_.csv_path.empty()) {
    csv_ = std::make_unique<BodiesCsvWriter>(options_.csv_path);
    csv_->write_step(*world_);  // the initial state, t = 0
  }
  obstacles_.reserve(bodies_.size());
  // Soil piled above the heightfield's upper bound would be clamped to it
  // (lost): the soil never piles higher.
  if (SoilFlow* soil = sim_.soil()) soil->set_ceiling(float(world_->bounds().max_height_m));
  sim_.add_listener(*this);
}

BodiesListener::~BodiesListener() { sim_.remove_listener(*this); }

Vec3 BodiesListener::on_step(const StepOutput& out) noexcept {
  world_->step(out);
  if (csv_) csv_->write_step(*world_);
  const WorldStepInfo& info = world_->last();
  // A released buried body lowered the soil it stood in: part of this step's change.
  if (info.bodies_released > 0) sim_.include_changed(info.released_rect);
  // So did soil a body pushed out of its ring.
  if (!info.shed_rect.empty()) sim_.include_changed(info.shed_rect);
  peak_tool_force_n_ = std::max(peak_tool_force_n_, length(info.tool_force_n));
  if (info.tool_contact_points > 0) ++steps_touching_;
  ++steps_;
  physics_sum_s_ += info.physics_s;
  physics_max_s_ = std::max(physics_max_s_, info.physics_s);
  if (SoilFlow* soil = sim_.soil()) {
    // Each body's bounding box (Bullet's, margin included) and a ring of
    // one sample round it as an obstacle (TerrainWorld::soil_obstacle).
    obstacles_.clear();
    for (int i = 0; i < world_->body_count(); ++i) obstacles_.push_back(world_->soil_obstacle(i));
    soil->set_obstacles(obstacles_);
  }
  return info.tool_force_n;
}

void BodiesListener::on_lift() noexcept { world_->lift_tool(); }

void BodiesListener::on_edit(const Rect& changed) noexcept { world_->terrain_changed(changed); }

int BodiesListener::write_bodies(std::span<BodyView> out) const noexcept {
  const int n = std::min(world_->body_count(), int(out.size()));
  for (int i = 0; i < n; ++i) {
    const BodyState s = world_->body_state(i);
    BodyView& v = out[std::size_t(i)];
    v.shape = bodies_[std::size_t(i)].shape;
    v.half_extents_m = half_extents_[std::size_t(i)];
    v.position_m = s.position_m;
    v.orientation = s.orientation;
    v.active = s.active;
  }
  return n;
}

void BodiesListener::finish() {
  if (csv_) csv_->close();
}

std::string BodiesListener::csv_name() const {
  return options_.csv_path.empty() ? std::string() : options_.csv_path.filename().string();
}

BodiesReport BodiesListener::report() const {
  BodiesReport r;
  r.count = int(bodies_.size());
  r.peak_tool_force_n = peak_tool_force_n_;
  r.steps_touching_tool = steps_touching_;
  r.steps = steps_;
  r.physics_mean_s = steps_ > 0 ? physics_sum_s_ / double(steps_) : 0.0;
  r.physics_max_s = physics_max_s_;
  r.min_height_m = world_->bounds().min_height_m;
  r.max_height_m = world_->bounds().max_height_m;
  r.samples_clamped = world_->bounds().clamped_total;
  r.soil_clamped_m3 = world_->bounds().clamped_volume_m3;
  for (int i = 0; i < world_->body_count(); ++i) {
    r.names.push_back(bodies_[std::size_t(i)].name);
    r.final_position_m.push_back(world_->body_state(i).position_m);
  }
  return r;
}

}  // namespace terracut::bullet
