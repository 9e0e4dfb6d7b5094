#include "terracut/core/simulation.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "terracut/core/error.hpp"
#include "terracut/core/format.hpp"
#include "terracut/core/ranges.hpp"
#include "terracut/core/soil_ahead.hpp"

namespace terracut {

namespace {

double now_s() {
  using clock = std::chrono::steady_clock;
  return std::chrono::duration<double>(clock::now().time_since_epoch()).count();
}

/// Largest number of sweep sub-steps in one step (bounds the step's cost).
constexpr int kMaxSubsteps = 64;

/// How far, in cells, each sweep reaches back over the previous one's end.
constexpr double kSweepOverlapCells = 1e-6;

// The sweep's start, moved back in time: each end goes back along its own
// motion by the same fraction of it, so that the end that moved furthest
// goes back by `back` metres and every point of the edge by that fraction
// of its own motion. Consecutive sweeps then overlap along the line they
// share, so a sample lying (to rounding) on it is inside at least one of
// them. The rasterisers decide a sample within about 1e-15 of a cell of a
// sweep's edge either way, and without the overlap a blade moving by small
// steps could miss such a row in both sweeps. Cutting twice is cutting
// once. (Each end moved back by `back` along its own motion, the overlap
// of a turning edge whose ends go opposite ways across its line was the
// ends' shifts interpolated: none at the edge's middle, and a gap between
// the middle and the point that stands still, where the motion and the
// shift point the same way. A 2 m blade turning about its centre while it
// pushed, its line on a row of cell centres in one step (2 cm cells, a
// lattice direction), never cut those centres, and the soil on them slid
// into the trench behind it: 2 cm.)
Segment reach_back(const Segment& from, const Segment& to, double back) {
  const Vec3 da = to.a - from.a, db = to.b - from.b;
  const double most = std::max(length(da), length(db));
  if (!(most > 0.0)) return from;
  const double k = back / most;
  return {from.a - da * k, from.b - db * k};
}

// A sweep whose edge did not move across its line in plan (a blade set
// down, standing, or going straight up or down) is a line in plan, and the
// rasterisers decide a sample centre on that line either way, by rounding:
// a blade set down with its line through a row of centres left some of
// them standing under its edge, and the terrain's place decided which. So
// such a step also cuts the band `back` either side of the edge where it
// now is (true, with the band's two sides in lo and hi): a centre on the
// line, within rounding, is cut wherever the terrain lies. False for an
// edge that moved across its line by more than `back` at either end (the
// reach back covers it) or that stands end-on in plan.
bool still_band(const Segment& from, const Segment& to, double back, Segment& lo, Segment& hi) {
  const double ex = to.b.x - to.a.x, ez = to.b.z - to.a.z;
  const double plan = std::hypot(ex, ez);
  if (!(plan > 0.0)) return false;
  const Vec3 n{-ez / plan, 0.0, ex / plan};
  const auto across = [&](const Vec3& was, const Vec3& is) {
    return std::abs((is.x - was.x) * n.x + (is.z - was.z) * n.z);
  };
  if (!(across(from.a, to.a) <= back && across(from.b, to.b) <= back)) return false;
  lo = {to.a - n * back, to.b - n * back};
  hi = {to.a + n * back, to.b + n * back};
  return true;
}

}  // namespace

std::string validate(const SimParams& params) {
  if (std::string e = validate(params.grid); !e.empty()) return e;
  const auto check_field = [](std::string_view path, double value) {
    return check(find_range(kSimParamsRanges, path), value);
  };
  if (std::string e = check_field("rate_hz", params.rate_hz); !e.empty()) return e;
  if (std::string e = check_field("blade.length_m", params.blade.length_m); !e.empty()) return e;
  if (std::string e = check_field("max_arc_error_cells", params.max_arc_error_cells); !e.empty())
    return e;
  const BucketSpec& bucket = params.blade.bucket;
  if (std::string e = check_field("blade.bucket.depth_m", bucket.depth_m); !e.empty()) return e;
  if (bucket.enabled()) {
    if (std::string e = check_field("blade.bucket.height_m", bucket.height_m); !e.empty()) return e;
    if (params.soil.model != SoilModel::kFlow)
      return "blade.bucket: a bucket carries soil, so it needs soil model flow (soil: {model: flow})";
  }
  if (std::string e = check_field("blade.edge_thickness_m", params.blade.edge_thickness_m);
      !e.empty())
    return e;
  // The blade's top: finite and > 0, or infinity (a wall as tall as any
  // pile); a bucket's is its own.
  if (params.blade.height_m != std::numeric_limits<double>::infinity()) {
    if (std::string e = check_field("blade.height_m", params.blade.height_m); !e.empty()) return e;
    if (bucket.enabled())
      return "blade.height_m: a bucket's height is blade.bucket.height_m; leave blade.height_m out with a bucket";
  }
  if (params.representation != Representation::kColumns &&
      params.representation != Representation::kSurface)
    return "representation must be columns or surface";
  if (std::string e = validate(params.soil); !e.empty()) return e;
  // The blade's rake with the material: a planar failure wedge must exist.
  EarthmovingParams cut;
  cut.soil = params.soil.material;
  cut.rake_angle_deg = params.blade.rake_angle_deg;
  if (std::string e = validate(cut); !e.empty()) {
    if (e.starts_with("rake_angle_deg")) return "blade." + e;
    return e;
  }
  return {};
}

ToolForceParams tool_force_params(const SimParams& params) {
  ToolForceParams t;
  t.earthmoving.soil = params.soil.material;
  t.earthmoving.rake_angle_deg = params.blade.rake_angle_deg;
  t.edge_thickness_m = params.blade.edge_thickness_m;
  t.blade_length_m = params.blade.length_m;
  t.representation = params.representation;
  t.piles = params.soil.model == SoilModel::kFlow;
  return t;
}

static const SimParams& checked(const SimParams& params) {
  if (std::string e = validate(params); !e.empty()) throw InputError(e);
  return params;
}

Simulation::Simulation(const SimParams& params, std::vector<float> initial_heights_m)
    : params_(checked(params)),
      grid_(params.grid, std::move(initial_heights_m)),
      tool_params_(tool_force_params(params_)),
      lookahead_m_(depth_lookahead_m(params_.grid)) {
  if (params_.soil.model == SoilModel::kFlow) soil_ = std::make_unique<SoilFlow>(params_.soil, grid_, params_.blade);
}

const StepOutput& Simulation::begin_step(const BladePose& pose) {
  begin_clock_s_ = now_s();
  in_step_ = true;
  out_.step = step_count_;
  out_.t_s = time_s();
  // A non-finite or zero pose is unusable: the blade stays where it was and
  // nothing is measured or cut; the caller (haptic loop) counts the sample.
  BladePose p = pose;
  p.orientation = normalized(pose.orientation);
  bool valid = is_finite(pose.position_m) && is_finite(pose.orientation);
  out_.pose = valid ? p : previous_pose_;
  out_.edge = blade_segment(params_.blade, out_.pose);
  out_.contact = valid ? measure_contact(grid_, params_.representation, out_.edge) : ContactResult{};
  out_.cut = {};
  out_.soil = {};
  out_.changed = {};
  out_.substeps = 0;
  out_.listener_force_world_n = {};
  out_.force = {};
  out_.timers = {};
  if (!valid) has_previous_ = false;
  // The tool's motion over the step: its poses' change times the rate
  // (none at the first step of a stroke).
  out_.motion = {};
  velocity_valid_ = has_previous_;
  if (has_previous_) {
    const double rate = params_.rate_hz;
    out_.motion.velocity_m_per_s = (out_.pose.position_m - previous_pose_.position_m) * rate;
    if (has_previous_velocity_)
      out_.motion.acceleration_m_per_s2 = (out_.motion.velocity_m_per_s - previous_velocity_m_per_s_) * rate;
    const Vec3 v = out_.motion.velocity_m_per_s;
    const double speed_xz = std::hypot(v.x, v.z);
    if (speed_xz >= kRestSpeed_m_per_s) heading_ = Vec3{v.x / speed_xz, 0.0, v.z / speed_xz};
    // The edge's heading about +Y (Ry(a) X = (cos a, 0, -sin a)); a vertical
    // edge has none.
    const Vec3 now = rotate(out_.pose.orientation, Vec3{1.0, 0.0, 0.0});
    const Vec3 before = rotate(previous_pose_.orientation, Vec3{1.0, 0.0, 0.0});
    if (std::hypot(now.x, now.z) > 1e-6 && std::hypot(before.x, before.z) > 1e-6) {
      const double turn = std::remainder(std::atan2(-now.z, now.x) - std::atan2(-before.z, before.x),
                                         2.0 * std::numbers::pi);
      out_.motion.yaw_rate_rad_per_s = turn * rate;
    }
  }
  out_.motion.heading = heading_;
  out_.timers.contact_s = now_s() - begin_clock_s_;
  return out_;
}

const StepOutput& Simulation::finish_step() {
  if (!in_step_) return out_;
  double cut_start = now_s();
  // The blade cuts where it rests even when it has just been put down.
  BladePose from = has_previous_ ? previous_pose_ : out_.pose;
  // Split a step with a large rotation so the blade ends follow their arc to
  // within max_arc_error_cells of a cell (sagitta of each sub-step's chord).
  double half_length = params_.blade.length_m / 2.0;
  double tolerance = params_.max_arc_error_cells *
                     std::min(params_.grid.cell_x_m(), params_.grid.cell_z_m());
  double angle = angle_between(from.orientation, out_.pose.orientation);
  int substeps = 1;
  if (angle > 0.0 && tolerance < half_length) {
    double max_angle = 2.0 * std::acos(1.0 - tolerance / half_length);
    // Bounded before the conversion to int: on absurdly small cells max_angle
    // is 0 and the ratio inf (found by the scenario fuzz target).
    const double n = std::ceil(angle / max_angle);
    substeps = n < kMaxSubsteps ? std::max(1, int(n)) : kMaxSubsteps;
  }
  const double overlap_m =
      kSweepOverlapCells * std::min(params_.grid.cell_x_m(), params_.grid.cell_z_m());
  Segment previous = blade_segment(params_.blade, from);
  const Segment step_from = previous;
  // (before_cut remembers the heights the cut may change: soil time.)
  double soil_before_s = 0.0;
  if (soil_) {
    const double t = now_s();
    soil_->before_cut(grid_, step_from, out_.edge);
    soil_before_s = now_s() - t;
  }
  for (int k = 1; k <= substeps; ++k) {
    double t = double(k) / substeps;
    BladePose pose = k == substeps ? out_.pose
                                   : BladePose{lerp(from.position_m, out_.pose.position_m, t),
                                               slerp(from.orientation, out_.pose.orientation, t)};
    Segment next = blade_segment(params_.blade, pose);
    CutResult part = cut_sweep(grid_, params_.representation, reach_back(previous, next, overlap_m),
                               next);
    out_.cut.removed_volume_m3 += part.removed_volume_m3;
    out_.cut.cells_visited += part.cells_visited;
    out_.cut.changed.include(part.changed);
    Segment band_lo, band_hi;
    if (still_band(previous, next, overlap_m, band_lo, band_hi)) {
      const CutResult band = cut_sweep(grid_, params_.representation, band_lo, band_hi);
      out_.cut.removed_volume_m3 += band.removed_volume_m3;
      out_.cut.cells_visited += band.cells_visited;
      out_.cut.changed.include(band.changed);
    }
    previous = next;
  }
  out_.substeps = substeps;
  removed_volume_m3_ += out_.cut.removed_volume_m3;
  previous_pose_ = out_.pose;
  has_previous_ = true;
  ++step_count_;
  const double cut_end = now_s();
  out_.timers.cut_s = cut_end - cut_start - soil_before_s;
  out_.changed = out_.cut.changed;

  // Soil that flows: what was cut goes ahead of the blade, slopes relax.
  double soil_end = cut_end;
  if (soil_) {
    out_.soil = soil_->after_cut(grid_, step_from, out_.edge, out_.pose.orientation);
    out_.changed.include(out_.soil.changed);
    soil_end = now_s();
    out_.timers.soil_s = soil_end - cut_end + soil_before_s;
  }

  // The soil's physical force on the tool, from the terrain the step leaves.
  const double bucket_load_m3 = soil_ ? out_.soil.bucket_load_m3 : 0.0;
  out_.force = soil_force_on_tool(tool_params_, grid_, out_.edge, out_.pose.position_m, out_.motion,
                                  bucket_load_m3, lookahead_m_);
  const double force_end = now_s();
  out_.timers.force_s = force_end - soil_end;
  previous_velocity_m_per_s_ = out_.motion.velocity_m_per_s;
  has_previous_velocity_ = velocity_valid_;

  // The listeners see the finished step (its cut and changed rectangle) and
  // may push on the tool.
  Vec3 listener_force{};
  in_listener_ = true;
  for (StepListener* listener : listeners_) listener_force = listener_force + listener->on_step(out_);
  in_listener_ = false;
  out_.listener_force_world_n = listener_force;
  out_.force.bodies_n = listener_force;
  out_.force.total_n = out_.force.total_n + listener_force;
  in_step_ = false;
  const double end = now_s();
  out_.timers.listeners_s = end - force_end;
  out_.timers.total_s = end - begin_clock_s_;
  return out_;
}

float Simulation::lower_sample(std::int64_t i, float height_m) {
  if (!in_listener_)
    throw std::logic_error("Simulation::lower_sample: only from a listener's on_step or on_edit");
  return grid_.lower(i, height_m);
}

void Simulation::move_height(std::int64_t from, std::int64_t to, float amount_m) {
  if (!in_listener_)
    throw std::logic_error("Simulation::move_height: only from a listener's on_step or on_edit");
  float* h = grid_.edit_layers().height_m;
  h[from] -= amount_m;
  h[to] += amount_m;
}

void Simulation::include_changed(const Rect& rect) {
  if (!in_step_) throw std::logic_error("Simulation::include_changed: only during a step");
  out_.changed.include(rect);
  if (soil_) soil_->wake(rect);
}

void Simulation::lift() {
  has_previous_ = false;
  if (soil_) soil_->new_stroke();
  has_previous_velocity_ = false;
  heading_ = {};
  for (StepListener* listener : listeners_) listener->on_lift();
}

void Simulation::add_listener(StepListener& listener) {
  if (in_step_) throw std::logic_error("Simulation::add_listener: not during a step");
  if (std::find(listeners_.begin(), listeners_.end(), &listener) != listeners_.end())
    throw std::logic_error("Simulation::add_listener: this listener was already added");
  listeners_.push_back(&listener);
}

void Simulation::remove_listener(StepListener& listener) {
  if (in_step_) throw std::logic_error("Simulation::remove_listener: not during a step");
  listeners_.erase(std::remove(listeners_.begin(), listeners_.end(), &listener), listeners_.end());
}

void Simulation::set_force_material(const SoilMaterial& material) {
  if (in_step_) throw std::logic_error("Simulation::set_force_material: not during a step");
  EarthmovingParams p = tool_params_.earthmoving;
  p.soil = material;
  if (std::string e = validate(p); !e.empty()) throw InputError(e);
  tool_params_.earthmoving.soil = material;
}

void Simulation::reset() {
  grid_.reset();
  if (soil_) {
    // A fresh soil state, with the obstacles and the ceiling it was given
    // (the bodies are not part of the terrain's reset: their listener sets
    // them again only when they change).
    const std::vector<SoilObstacle> obstacles(soil_->obstacles().begin(), soil_->obstacles().end());
    const float ceiling = soil_->ceiling_m();
    soil_ = std::make_unique<SoilFlow>(params_.soil, grid_, params_.blade);
    soil_->set_obstacles(obstacles);
    soil_->set_ceiling(ceiling);
  }
  tool_params_ = tool_force_params(params_);
  has_previous_ = false;
  has_previous_velocity_ = false;
  heading_ = {};
  in_step_ = false;
  step_count_ = 0;
  removed_volume_m3_ = 0.0;
  out_ = {};
  // Whoever caches heights (the Bullet world) hears of the whole grid.
  tell_edited({0, 0, grid_.cols(), grid_.rows()});
}

void Simulation::tell_edited(const Rect& changed) {
  in_listener_ = true;
  for (StepListener* listener : listeners_) listener->on_edit(changed);
  in_listener_ = false;
}

Rect Simulation::edit_heights(const Rect& rect, std::span<const float> values_m) {
  if (in_step_) throw std::logic_error("Simulation::edit_heights: not during a step");
  const Rect grid_rect{0, 0, grid_.cols(), grid_.rows()};
  if (rect.empty() || rect.c0 < 0 || rect.r0 < 0 || rect.c1 > grid_rect.c1 ||
      rect.r1 > grid_rect.r1)
    throw InputError("edit_heights: rectangle [" + std::to_string(rect.c0) + ", " +
                     std::to_string(rect.c1) + ") x [" + std::to_string(rect.r0) + ", " +
                     std::to_string(rect.r1) + ") must be non-empty and inside the " +
                     std::to_string(grid_rect.c1) + " x " + std::to_string(grid_rect.r1) +
                     " grid (cols x rows)");
  const int width = rect.c1 - rect.c0;
  if (std::int64_t(values_m.size()) != rect.area())
    throw InputError("edit_heights: expected " + std::to_string(rect.r1 - rect.r0) + " x " +
                     std::to_string(width) + " values (rows x cols), got " +
                     std::to_string(values_m.size()));
  for (std::size_t i = 0; i < values_m.size(); ++i) {
    const float h = values_m[i];
    if (!(std::isfinite(h) && h >= 0.0f))
      throw InputError(must_be("edit_heights: height at (col " +
                                   std::to_string(rect.c0 + int(i) % width) + ", row " +
                                   std::to_string(rect.r0 + int(i) / width) + ")",
                               "finite and >= 0 metres", h));
  }
  const Rect changed = grid_.set_heights(rect, values_m.data());
  if (soil_) soil_->wake(changed);
  tell_edited(changed);
  return changed;
}

}  // namespace terracut
