// Soil that flows (soil.hpp): its parameters, construction and the order
// of a step's phases (after_cut), each phase in a file of its own: the
// displacement ahead of the blade (soil_displace.cpp), the relaxation to the
// angle of repose (soil_relax.cpp), the bucket (soil_bucket.cpp) and rigid
// bodies (soil_bodies.cpp).
#include "terracut/core/soil.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "terracut/core/error.hpp"
#include "terracut/core/format.hpp"
#include "soil_internal.hpp"

namespace terracut {

using namespace soil_internal;

std::string validate(const SoilFlowParams& p) {
  if (p.model != SoilModel::kVanish && p.model != SoilModel::kFlow)
    return "soil.model must be vanish or flow";
  if (p.edge != SoilEdge::kWall && p.edge != SoilEdge::kOpen) return "soil.edge must be wall or open";
  if (p.settle != SoilSettle::kPatches && p.settle != SoilSettle::kPasses && p.settle != SoilSettle::kFans)
    return "soil.settle must be patches, passes or fans";
  // The material's ranges (material.hpp): below a degree of repose the
  // material is a liquid, out of the model's reach (a repose of 1e-300
  // degrees made the tolerance 0, and float noise kept the cells moving).
  if (std::string m = validate(p.material); !m.empty()) return "soil." + m;
  if (std::string m = check(find_range(kSoilFlowRanges, "max_pair_checks_per_step"),
                             double(p.max_pair_checks_per_step), "soil.max_pair_checks_per_step");
      !m.empty())
    return m;
  return {};
}

double steepest_standing_slope_deg(double cell_x_m, double cell_z_m, double repose_deg) {
  const double t = std::tan(repose_deg * std::numbers::pi / 180.0);
  // The tolerance as the relaxation takes it: a fraction of the repose
  // drop over the shorter cell side, the same for every pair.
  const double tol = kToleranceOfLimit * t * std::min(cell_x_m, cell_z_m);
  // The neighbours' directions (from +X toward +Z) and each one's bound on
  // the plane's slope along its own direction: (t d + tol) / d.
  struct Dir {
    double angle, bound;
  };
  Dir dirs[8];
  for (int k = 0; k < 8; ++k) {
    const double x = kNeighbours[k].dc * cell_x_m, z = kNeighbours[k].dr * cell_z_m;
    const double d = std::hypot(x, z);
    dirs[k] = {std::atan2(z, x), (t * d + tol) / d};
  }
  std::sort(std::begin(dirs), std::end(dirs), [](const Dir& a, const Dir& b) { return a.angle < b.angle; });
  // A plane of slope s falling along theta stands while s cos(theta -
  // angle_k) <= bound_k for every neighbour ahead of it (cos > 0). Its
  // steepest standing slope over theta peaks where two adjacent
  // directions' bounds meet: with u = theta - angle_k and g the gap,
  // bound_k cos(u - g) = bound_k+1 cos(u).
  const auto standing = [&](double theta) {
    double s = std::numeric_limits<double>::infinity();
    for (const Dir& d : dirs) {
      const double c = std::cos(theta - d.angle);
      if (c > 1e-12) s = std::min(s, d.bound / c);
    }
    return s;
  };
  double steepest = 0.0;
  for (int k = 0; k < 8; ++k) {
    const Dir& a = dirs[k];
    const Dir& b = dirs[(k + 1) % 8];
    const double g = k == 7 ? b.angle + 2.0 * std::numbers::pi - a.angle : b.angle - a.angle;
    const double u = std::atan2(b.bound - a.bound * std::cos(g), a.bound * std::sin(g));
    steepest = std::max(steepest, standing(a.angle + u));
  }
  return std::atan(steepest) * 180.0 / std::numbers::pi;
}

SoilFlow::SoilFlow(const SoilFlowParams& params, const HeightGrid& grid, const BladeSpec& blade)
    : params_(params), blade_spec_(blade), cols_(grid.cols()), rows_(grid.rows()) {
  if (std::string m = validate(params); !m.empty()) throw InputError(m);
  if (!(blade.height_m > 0.0)) throw InputError(must_be("blade.height_m", "> 0 (infinity: unbounded)", blade.height_m));
  step_cap_ = params_.max_pair_checks_per_step;
  const GridSpec& spec = grid.spec();
  dx_ = spec.cell_x_m();
  dz_ = spec.cell_z_m();
  const double slope = std::tan(params.material.repose_deg * std::numbers::pi / 180.0);
  limit_[0] = slope * dx_;
  limit_[1] = slope * dz_;
  limit_[2] = slope * std::hypot(dx_, dz_);
  tolerance_m_ = float(kToleranceOfLimit * std::min(limit_[0], limit_[1]));
  {
    // The relaxation's quantum: the float step of heights up to twice the
    // highest initial height (at least 1 m). Every height the relaxation
    // writes and every amount it moves is a multiple of it, so its float
    // additions are exact below that bound.
    double highest = 0.5;
    for (std::int64_t i = 0; i < grid.spec().sample_count(); ++i) highest = std::max(highest, double(grid.heights()[i]));
    quantum_m_ = std::ldexp(1.0, std::ilogb(2.0 * highest) - 23);
    inv_quantum_m_ = 1.0 / quantum_m_;
  }
  origin_x_ = spec.origin_m.x;
  origin_z_ = spec.origin_m.z;
  coord_rounding_m_ = 64.0 * std::numeric_limits<double>::epsilon() *
                      std::max({std::abs(spec.origin_m.x), std::abs(spec.origin_m.x + spec.size_x_m),
                                std::abs(spec.origin_m.z), std::abs(spec.origin_m.z + spec.size_z_m)});
  row_div_ = detail::IndexDivider(std::uint32_t(cols_));

  for (int k = 0; k < 8; ++k) {
    offset_[k] = std::int64_t(kNeighbours[k].dr) * cols_ + kNeighbours[k].dc;
    limit8_[k] = float(limit_[kNeighbours[k].kind]);
  }

  const std::size_t n = std::size_t(grid.spec().sample_count());
  queued_.assign(n, CellFlags(0));
  for (int c = 0; c < cols_; ++c) {
    set_flag(std::uint32_t(c), kEdge);
    set_flag(std::uint32_t(std::int64_t(rows_ - 1) * cols_ + c), kEdge);
  }
  for (int r = 0; r < rows_; ++r) {
    set_flag(std::uint32_t(std::int64_t(r) * cols_), kEdge);
    set_flag(std::uint32_t(std::int64_t(r) * cols_ + cols_ - 1), kEdge);
  }
  obstacle_.assign(n, 0);
  obstacles_.reserve(16);
  // The per-step scratch sized up front for the blade (its swept rectangle
  // and the cells near it: a square of its length plus a margin of cells)
  // and for an active set of a large pile, so that the 1 kHz loop's ticks
  // do not grow them: a haptic loop on flowing soil allocates nothing.
  const double reach_cells = blade.length_m / std::min(dx_, dz_) + 8.0;
  const std::size_t footprint = std::size_t(std::min(double(n), reach_cells * reach_cells));
  before_.reserve(footprint);
  after_cut_.reserve(footprint);
  marked_.reserve(footprint);
  const std::size_t active = std::min(n, std::max<std::size_t>(std::size_t(1) << 16, 4 * footprint));
  active_.reserve(active);
  next_.reserve(active);
  candidates_.reserve(active);
  // A source's fall lines give up to 8 x kMaxFallCells fluxes, a handful as
  // a rule: a pass holds at most kFluxesPerActiveCell x active of them (a
  // larger one is split, examine's loop).
  fluxes_.reserve(kFluxesPerActiveCell * active);
  sources_.reserve(active);
  held_.reserve(footprint);
  dirty_.reserve(footprint);
  if (blade.bucket.enabled()) {
    // The hull lies within this of the lip's centre in any orientation:
    // its bounding rectangle is at most twice that across, plus a cell.
    const double reach = std::sqrt(0.25 * blade.length_m * blade.length_m + blade.bucket.depth_m * blade.bucket.depth_m +
                                   blade.bucket.height_m * blade.bucket.height_m);
    const double box = (2.0 * reach / dx_ + 3.0) * (2.0 * reach / dz_ + 3.0);
    const std::size_t hull = std::size_t(std::min(double(n), box));
    hull_cells_.reserve(hull);
    hull_under_.reserve(hull);
    hull_row_c0_.reserve(std::size_t(rows_));
    hull_row_c1_.reserve(std::size_t(rows_));
    held_.reserve(footprint + hull);
    dirty_.reserve(footprint + hull);
  }

  if (!blade.bucket.enabled()) {
    // spill_round_ends' window round each end, and its sets (at most the
    // window's cells).
    const std::size_t window = std::size_t(2 * kEndWindowCells + 1) * std::size_t(2 * kEndWindowCells + 1);
    ends_place_.assign(window, 0);
    ends_dist_.assign(window, 0.0f);
    ends_state_.assign(window, 0);
    ends_keys_.reserve(window);
    ends_queue_.reserve(window);
    touch_reserved(ends_keys_);
    touch_reserved(ends_queue_);
    // The settle's window: the blade's square, the spill's windows
    // round its ends, the pile ahead and the margin.
    const double side = reach_cells + 2.0 * (kEndWindowCells + kSettlePileCells + kSettleMarginCells);
    reserve_settle(std::size_t(std::min(double(n), side * side)));
  }
  for (auto* v : {&before_, &after_cut_}) touch_reserved(*v);
  for (auto* v : {&marked_, &held_, &dirty_, &hull_cells_}) touch_reserved(*v);
  touch_reserved(fluxes_);
  touch_reserved(sources_);
  touch_reserved(hull_under_);

  // Every cell of a slope already steeper than the repose angle starts active.
  const float* h = grid.heights();
  for (int r = 0; r < rows_; ++r)
    for (int c = 0; c < cols_; ++c) {
      const std::uint32_t a = std::uint32_t(std::int64_t(r) * cols_ + c);
      for (const Neighbour& nb : kNeighbours) {
        const int c2 = c + nb.dc, r2 = r + nb.dr;
        if (c2 < 0 || r2 < 0 || c2 >= cols_ || r2 >= rows_) continue;
        const std::uint32_t b = std::uint32_t(std::int64_t(r2) * cols_ + c2);
        if (double(h[a]) - double(h[b]) > limit_[nb.kind] + tolerance_m_) {
          activate(a);
          activate(b);
        }
      }
    }
}

bool SoilFlow::wake_held(const Segment* edge) {
  // Soil the blade held up is examined again once the blade is elsewhere
  // (or gone); while it stands still, nothing it holds can move.
  // "Elsewhere": an end moved by a quarter of a cell or more (what the
  // blade holds changes only where its line crosses a cell's centre or
  // edge; a step of 0.6 mm on 1 cm cells would wake them every step).
  if (held_.empty()) return false;
  if (edge != nullptr) {
    const double q2 = kHeldMoveCells * kHeldMoveCells * std::min(dx_ * dx_, dz_ * dz_);
    const auto near = [&](const Vec3& p, const Vec3& q) {
      const Vec3 d = p - q;
      return d.x * d.x + d.y * d.y + d.z * d.z < q2;
    };
    if (near(edge->a, held_edge_.a) && near(edge->b, held_edge_.b) &&
        (hull_cells_.empty() || (near(hull_heel_.a, held_heel_.a) && near(hull_heel_.b, held_heel_.b))))
      return false;
  }
  for (std::uint32_t cell : held_) {
    clear_flag(cell, kHeld);
    activate(cell);
  }
  held_.clear();
  return true;
}

void SoilFlow::wake(const Rect& rect) {
  if (rect.empty()) return;
  settle_exclude(Rect{rect.c0 - 1, rect.r0 - 1, rect.c1 + 1, rect.r1 + 1});  // heights another hand wrote
  const int c0 = std::max(rect.c0 - 1, 0), c1 = std::min(rect.c1 + 1, cols_);
  const int r0 = std::max(rect.r0 - 1, 0), r1 = std::min(rect.r1 + 1, rows_);
  for (int r = r0; r < r1; ++r)
    for (int c = c0; c < c1; ++c) {
      const auto cell = std::uint32_t(std::int64_t(r) * cols_ + c);
      dirty(cell);
      activate(cell);
    }
}

const Segment& SoilFlow::motion_origin(MotionTrack& track, const Segment& from, const Segment& to, bool by_ends) {
  const auto same = [](const Vec3& p, const Vec3& q) { return p.x == q.x && p.y == q.y && p.z == q.z; };
  if (!track.known || !same(from.a, track.last.a) || !same(from.b, track.last.b)) {
    track.anchor = track.from = from;
    track.known = true;
  }
  track.last = to;
  const double reach = 2.0 * kMotionCells * std::max(dx_, dz_);
  const auto moved = [reach](double x, double z) { return x * x + z * z > reach * reach; };
  const Segment& a = track.anchor;
  const PlanMotion mid = midpoint_motion(a, to);
  const bool far = by_ends ? moved(to.a.x - a.a.x, to.a.z - a.a.z) || moved(to.b.x - a.b.x, to.b.z - a.b.z)
                           : moved(mid.x, mid.z);
  if (far) {
    track.from = track.anchor;
    track.anchor = to;
  }
  return track.from;
}

SoilStepResult SoilFlow::after_cut(HeightGrid& grid, const Segment& from, const Segment& to,
                                   const Quat& orientation) {
  SoilStepResult out;
  // Which way the blade goes, for the side behind it (the spill, the
  // settle's wall, the passes') and the displacement's push in a step that
  // did not cross the edge's line: from where it stood before its last move
  // of a fiftieth of a cell, not from this step's start alone
  // (motion_origin).
  const Segment& moved_from = motion_origin(motion_mid_, from, to, false);
  const Segment& ends_from = motion_origin(motion_ends_, from, to, true);
  double room = 0.0, holds = 0.0;
  if (blade_spec_.bucket.enabled()) {
    holds = bucket_retained_m3(blade_spec_, orientation, params_.material.repose_deg);
    // It takes soil in only while its lip leads: moving toward its opening
    // (the blade frame's -Z, in plan).
    const Vec3 opening = rotate(orientation, {0.0, 0.0, -1.0});
    const PlanMotion m = midpoint_motion(from, to);
    if (m.x * opening.x + m.z * opening.z > 0.0) room = std::max(0.0, holds - load_m3_);
  }
  displace(grid, from, moved_from, to, room, out);
  // What the push left above the repose cone through an end of the blade
  // goes round it now (the bucket's ends are its side plates: not yet).
  if (!blade_spec_.bucket.enabled() && out.displaced_volume_m3 > 0.0) spill_round_ends(grid, moved_from, to, out);
  // What they left steeper than the stencil allows settles in one
  // construction (soil_settle.cpp), spread over as many steps as the work
  // cap asks while the passes wait. A step that displaces soil while one is
  // still under way lets it go on without the cells it wrote, and another
  // follows it, over both steps' cells, before the passes run. A settle
  // under way goes on only below, after this step's displacement and spill:
  // it once went first, in before_cut, and at a step that cut soil again
  // while it ran it took the whole cap, the spill round the ends found none
  // left, and what the spill should have put in the trench's first rows
  // came down by passes over the next 15 steps, ten times the converged
  // work (docs/soil.md, "The spill comes before a settle under way").
  if (!blade_spec_.bucket.enabled() && out.displaced_volume_m3 > 0.0 && params_.settle != SoilSettle::kPasses) {
    if (settle_phase_ == SettlePhase::kIdle) {
      settle_start(grid, moved_from, to, out.changed);
    } else {
      // (the cells the steps since wrote: the one under way settles the rest)
      if (!settle_again_) settle_next_rect_ = out.changed;
      else settle_next_rect_.include(out.changed);
      settle_next_from_ = moved_from;
      settle_next_to_ = to;
      settle_again_ = true;
    }
  }
  load_m3_ += out.bucket_in_m3;
  if (load_m3_ > holds && blade_spec_.bucket.enabled()) {
    pour(grid, to, load_m3_ - holds, out);
    load_m3_ = holds;
  }
  out.bucket_load_m3 = load_m3_;
  if (blade_spec_.bucket.enabled()) {
    // The hull at its new pose: what stands inside it is shouldered out.
    mark_hull(grid, to, orientation);
    shoulder(grid, out);
  }
  // Where this step's cut or the last one's passed cell centres, cells the
  // blade held may now lie behind it (the trench's, blade_blocks: a centre
  // the edge stood on when it cut it is behind it from the next step on):
  // all are examined again.
  const bool cut_now = out.displaced_volume_m3 > 0.0 || out.bucket_in_m3 > 0.0;
  const bool woke = wake_held(cut_now || cut_last_step_ ? nullptr : &to);
  cut_last_step_ = cut_now;
  // What the blade held at its ends slides round them once it has moved
  // on: the spill round the ends runs again (it ran above only in a step
  // that displaced soil). Left to the passes, that soil drained through the
  // cells at each end a millimetre a pass, for about 100 passes after each
  // row crossing (docs/soil.md, "The held soil spills round the ends").
  if (woke && !cut_now && !blade_spec_.bucket.enabled()) spill_round_ends(grid, moved_from, to, out);
  // A row crossing displaces the whole pushed face at once, work the cap
  // does not bound (a step's cut is displaced whole). After
  // kRestStepsBeforeCharge steps in a row whose relaxation finished within
  // the cap, what that walk cost is taken from this step's settle and
  // passes, up to half the cap, and what they leave goes on in the next
  // step, which has the room: the crossing's work is spread over two steps.
  // (Charged to nothing, the crossing of a 2 m blade on 1 cm cells did its
  // displacement, about 200 us, and then a settle of up to the whole cap:
  // 560 to 590 us at the 99th percentile. Charged after any step, pushes
  // on 5 mm cells, at the cap for steps after each crossing, lost that
  // work: 6 of 48 pushes of 2.4 m missed the converged pile's bounds, where
  // 3 to 5 do uncharged at caps of 49000 to 51000; docs/soil.md, "A
  // crossing's settle over two steps".)
  const std::int64_t cap = params_.max_pair_checks_per_step;
  const std::int64_t taken = rest_steps_ >= kRestStepsBeforeCharge ? std::min(displace_work_, cap / 2) : 0;
  step_cap_ = cap - taken;
  out.displace_visits = displace_work_;
  out.relax_budget = step_cap_;
  displace_work_ = 0;
  if (settle_phase_ != SettlePhase::kIdle) {
    settle_follow(grid.spec(), moved_from, to);
    out.settle_visits += settle_charged(grid, out.changed, step_cap_ - ends_work_);
  }
  // The blade's wall matters only to a pass: marked only when one runs.
  if (settle_phase_ != SettlePhase::kIdle) {
    out.reached_cap = true;  // the settle goes on in the next step
  } else if (pending()) {
    mark_blade(grid, ends_from, to);
    if (held_.empty()) held_edge_ = to, held_heel_ = hull_heel_;  // where the blade and hull hold what the passes find held
    run_passes(grid, out);
    clear_blade();
  }
  // Last, what stands against a blade of finite height above its top falls
  // over it (after the settle and the passes, which could raise one again;
  // what falls is relaxed from the next step on): at the end of a step a
  // cell against it stands higher only where the slope behind the blade is
  // full to the top, the blade buried, or the spill's allowance spent.
  spill_over_top(grid, to, orientation, out);
  out.pair_checks += ends_work_;  // (no pass ran)
  ends_work_ = 0;
  rest_steps_ = rest_run_after(rest_steps_, out.reached_cap);
  out.backlog_cells = active_cells();
  return out;
}

}  // namespace terracut
