// Soil that flows: the soil phase of a step (simulation.hpp), between the cut
// and the step listeners.
//
// Two models, chosen by SoilFlowParams::model:
//  - kVanish (the paper's): what the blade cuts is gone. The phase does
//    nothing; per sample height + removed = initial with removed >= 0.
//  - kFlow: nothing vanishes. What the blade cut in the step is put down
//    just ahead of the blade (displacement), then every slope steeper than
//    the angle of repose slides until it is not (relaxation). The total
//    volume of soil on the grid is conserved; removed = initial - height is
//    then signed: > 0 where soil was taken, < 0 where it was deposited.
//
// Displacement. Each sample the cut lowered gives its lost height to the
// cell straight ahead of the blade: along the edge's horizontal normal, on
// the side the edge moved to, one and a half cells beyond the edge's current
// line. The blade is a wall for the flowing soil: where the soil stands above
// the edge, no soil moves between two cells whose centres lie on the two
// sides of the edge (in plan, within its length), nor into a cell the edge
// passes through (its centre within half a cell of the edge's line), so
// soil never flows through or under the blade into the cut behind it; the pile in front grows
// as the blade pushes, and spills around the blade's ends and to the sides
// as it relaxes (windrows). The blade's face is taken as tall as the pile.
//
// Relaxation. Between a cell and each of its 8 neighbours (axis distance dx
// or dz, diagonal distance sqrt(dx^2 + dz^2)), the excess is the height
// difference above tan(repose) x distance. Per pass, a cell whose excess
// toward some neighbours is above a tolerance (2 % of the repose drop over
// the shorter cell side) sheds half of its largest excess, shared among
// those neighbours in proportion to their excess (the thermal-erosion rule
// of Musgrave, Kolb & Mace, SIGGRAPH 1989). A pass's fluxes are computed
// from the heights frozen at its start (Jacobi) and then applied, so the
// result does not depend on the order of the cells: the same inputs give
// the same bits, and relaxation alone gives a mirrored terrain the
// mirrored result to float rounding (with a blade cutting, rounding that
// is not mirror-symmetric tips pairs at their threshold one way: about a
// millimetre in docs/soil.md's check). With the diagonals the repose angle
// holds along the axes and the diagonals and on square cells is up to 2.6
// degrees steeper in between (steepest_standing_slope_deg; a 4-neighbour
// stencil makes diagonals about 9 degrees too steep), so a pile poured at
// a point settles into a round cone.
//
// Cost follows activity: only cells whose height changed (and, once, at
// construction, every cell steeper than the repose angle) are examined, and
// a pass examines each active cell's 8 pairs. A cell that changed is
// examined in the next pass, and so is a neighbour of one that fell when
// the pair between them is now too steep (only that pair of the neighbour
// changed); soil the blade held up (a pair it blocked) is examined again
// once the blade has moved a quarter of a cell, so nothing it held stays
// steeper than the repose angle after it has gone.
// The work of a step is bounded by max_pair_checks_per_step, always: a pass
// too large for what is left of it is carried on in the next step where it
// stopped. A pass is examined whole from the heights it started from before
// any of its fluxes is applied, so spreading it over steps gives the same
// bits as running it at once (a flux from or to a cell the cut, the
// displacement or an edit changed meanwhile is dropped, and the cell
// examined again). What is left is the backlog, carried over: a large
// collapse is spread over ticks of bounded work.
// A step with nothing active costs microseconds: the blade is marked only when a pass runs.
//
// Each step that displaces soil, what stands above the repose cone through
// an end of the blade's edge slides round that end at once (the soil's
// spill into the trench's corner and the pile's hip, built rather than
// relaxed over hundreds of passes; docs/soil.md "The spill round the
// blade's ends"); its work counts against the same cap.
//
// A bucket (BladeSpec::bucket) takes what its lip cuts while it digs
// forward (toward its opening), up to what it can hold in its present
// orientation; the rest is displaced ahead as from a blade. What it holds is
// carried with it (SoilStepResult::bucket_load_m3: grid volume plus load is
// conserved). It holds the soil below a surface rising from the lip into
// the bucket at the repose angle (bucket_retained_m3): level, a bucket whose
// back is no steeper than the repose angle holds its struck capacity; tilted
// back up, it holds less, and nothing once its floor is steeper than the
// repose angle. What it can no longer hold pours from the lip onto the
// terrain below the lip, where it relaxes. Only the lip cuts, but the
// bucket's body (its floor and back plates, their underside per cell under
// them in plan) is a solid: soil above the underside of a cell under it is
// shouldered out of its footprint (each cell's excess carried away from the
// footprint's plan centre to the first cell outside it and not under a
// body), and no soil flows into a cell under it higher than its underside
// there, so nothing sits inside the bucket's body but its load; what the
// hull held back is examined again once the bucket has moved.
//
// Rigid obstacles (set_obstacles; the Bullet bodies' listener sets them
// from the bodies' bounding boxes every step): no soil flows, is pushed or
// is put down into a cell under an obstacle, whatever the gap under it, so
// soil banks against a body instead of passing through or under it (and
// never lifts it from below); cut soil with no free cell between the blade
// and a body goes round it. Soil under a body can still slide out from
// under it. set_ceiling bounds how high the displacement piles soil (the
// Bullet heightfield's upper bound, above which soil would be clamped), and
// every other writer too (the spill round the ends, the settle, the passes,
// the spill over a blade's top).
//
// The rigid floor stays: heights never go below 0. The grid's edge is a wall
// (no soil leaves) or, with SoilEdge::kOpen, bare ground beyond which soil
// slides or is pushed off the terrain, counted in left_over_edge_m3.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include "terracut/core/enum_names.hpp"
#include "terracut/core/blade.hpp"
#include "terracut/core/grid.hpp"
#include "terracut/core/material.hpp"

namespace terracut {

namespace detail {

/// Division of 32-bit cell indices by a fixed row length without a divide
/// instruction: the quotient is the high word of a 64 x 64-bit product with
/// ceil(2^64 / d), exact for every 32-bit numerator and every d >= 1
/// (Lemire, Kaser & Kurz, "Faster remainder by direct computation",
/// Software: Practice and Experience 49 (2019), theorem 1 with N = 32,
/// F = 64). The relaxation turns a cell index into its column and row on
/// every source; a hardware 32-bit division cost about a tenth of a pass.
class IndexDivider {
 public:
  IndexDivider() = default;
  explicit IndexDivider(std::uint32_t d) : d_(d), magic_(d > 1 ? ~std::uint64_t(0) / d + 1 : 0) {}
  std::uint32_t quotient(std::uint32_t n) const {
    if (d_ <= 1) return n;
    // The high word of magic_ x n from two 32 x 32-bit products (no sum
    // overflows: (2^32 - 1)^2 + 2^32 < 2^64).
    const std::uint64_t hi = (magic_ >> 32) * n, lo = ((magic_ & 0xffffffffu) * n) >> 32;
    return std::uint32_t((hi + lo) >> 32);
  }
  std::uint32_t divisor() const { return d_; }

 private:
  std::uint32_t d_ = 1;
  std::uint64_t magic_ = 0;
};

/// A list of cell indices that can take one on a condition without a
/// branch (push_if): the relaxation queues a neighbour only when it is not
/// queued yet, a test whose outcome changes from cell to cell, so a branch
/// on it was often mispredicted. The storage always has a slot beyond the
/// last element, which push_if writes whether it keeps it or not; it grows
/// (doubling) only when a kept element fills that slot, so a list reserved
/// for n cells never allocates while it holds at most n. Kept across
/// clear(); copies are deep.
class CellList {
 public:
  CellList() : buf_(64) {}
  std::size_t size() const { return size_; }
  /// Elements it holds before it allocates again.
  std::size_t capacity() const { return buf_.size() - 1; }
  bool empty() const { return size_ == 0; }
  void clear() { size_ = 0; }
  /// Keeps the first n elements (n <= size()).
  void truncate(std::size_t n) { size_ = std::min(size_, n); }
  void reserve(std::size_t n) {
    if (n + 1 > buf_.size()) buf_.resize(n + 1);
  }
  void push_back(std::uint32_t cell) { push_if(cell, true); }
  /// Appends cell when keep is true; either way without a branch on keep.
  void push_if(std::uint32_t cell, bool keep) {
    buf_[size_] = cell;
    size_ += keep ? 1u : 0u;
    if (size_ == buf_.size()) buf_.resize(2 * buf_.size());
  }
  std::uint32_t operator[](std::size_t i) const { return buf_[i]; }
  /// Overwrites element i (i < size()): a list compacted in place.
  void set(std::size_t i, std::uint32_t cell) { buf_[i] = cell; }
  const std::uint32_t* begin() const { return buf_.data(); }
  const std::uint32_t* end() const { return buf_.data() + size_; }
  void swap(CellList& other) noexcept {
    buf_.swap(other.buf_);
    std::swap(size_, other.size_);
  }

 private:
  std::vector<std::uint32_t> buf_;  // buf_.size() is the capacity
  std::size_t size_ = 0;
};

}  // namespace detail

/// What happens to the soil the blade cuts.
enum class SoilModel {
  kVanish,  ///< it is gone (the paper's model; the default)
  kFlow,    ///< it is pushed ahead of the blade and slides to its angle of repose
};
/// Its names (enum_names.hpp: to_string, parse_enum).
inline constexpr EnumName<SoilModel> kSoilModelNames[] = {
    {SoilModel::kVanish, "vanish"},
    {SoilModel::kFlow, "flow"},
};
constexpr std::span<const EnumName<SoilModel>> enum_names(SoilModel) { return kSoilModelNames; }

/// What the grid's edge does to soil that reaches it.
enum class SoilEdge {
  kWall,  ///< no soil leaves the terrain (the default)
  kOpen,  ///< soil sliding or pushed past the edge leaves it, and is counted
};
/// Its names (enum_names.hpp: to_string, parse_enum).
inline constexpr EnumName<SoilEdge> kSoilEdgeNames[] = {
    {SoilEdge::kWall, "wall"},
    {SoilEdge::kOpen, "open"},
};
constexpr std::span<const EnumName<SoilEdge>> enum_names(SoilEdge) { return kSoilEdgeNames; }

/// How the pile a blade displaces is brought to the repose angle.
enum class SoilSettle {
  /// In one construction over each patch of the cells it left too steep,
  /// then the passes (docs/soil.md, "The displaced pile settled at once"):
  /// cheap at the work cap, and the pile's shape smooth across float
  /// rounding; but it moves soil across a patch, not only down the fall
  /// line, so its converged pile is not the passes' own: 2 to 63 % less
  /// soil ahead of the blade in 18 pushes, half at 10 degrees on 5 mm
  /// cells, and 22 % less square to the grid over a 3 m push
  /// (docs/soil.md, "The fans by default"). The default until 2026-12-07.
  kPatches,
  /// By the relaxation's passes alone: the reference the other two are
  /// measured against (the same pile at any yaw within 2 % between 0 and 10
  /// degrees, the capped pile within 1.4 % of the converged one at 0 and 10
  /// degrees), but the cap is reached on most 5 mm steps of a push (648 of
  /// 1201 against 115), a capped pile stands up to 23 mm off its mirror
  /// image and a capped peak up to 5.3 mm off the converged one.
  kPasses,
  /// The default. As kPatches, but each patch's soil stays in its fans, the
  /// cells fed along the stencil's fall lines from one source (docs/soil.md,
  /// "The settle follows the fall lines", "The fans by default"): the
  /// converged pile is the passes' own (within 3 % in 13 of 18 pushes, 14 %
  /// less at worst, against 2 to 63 % less with kPatches; 0.4 % less over a
  /// 3 m push), about the same at any yaw, and the capped pile within 3 % of
  /// the converged one at 0 to 30 degrees. Which cell joins which fan turns
  /// on float rounding: a long capped push's pile stands up to about 2 cm
  /// off its mirror image (kPatches: 1.7 mm); and a step that settles costs
  /// more (the 2 m blade's p99 on 1 cm cells 1.2 to 1.3 times kPatches';
  /// docs/performance.md, "The fans by default").
  kFans,
};
/// Its names (enum_names.hpp: to_string, parse_enum).
inline constexpr EnumName<SoilSettle> kSoilSettleNames[] = {
    {SoilSettle::kPatches, "patches"},
    {SoilSettle::kPasses, "passes"},
    {SoilSettle::kFans, "fans"},
};
constexpr std::span<const EnumName<SoilSettle>> enum_names(SoilSettle) { return kSoilSettleNames; }

/// The soil: its material and what happens to what the blade cuts (the
/// scenario's `soil:` section); read-only during a run.
struct SoilFlowParams {
  SoilModel model = SoilModel::kVanish;
  /// The soil's material (material.hpp): the flow relaxes slopes to its
  /// angle of repose (the stopping angle of a flowing slope: dry sand about
  /// 34 degrees, wet sand about 45, saturated 15-30; Al-Hashemi &
  /// Al-Amoudi, Powder Technology 330 (2018) 397); the forces read the rest.
  SoilMaterial material{};
  /// Work cap of one step's relaxation, in neighbour visits, in
  /// [1000, 1e9]: 8 per cell examined, 1 per flux applied, 8 per fallen
  /// cell's test of its neighbours; the settle of a displaced pile charges 4
  /// a cell it handles. The displacement itself is not bounded (a step's cut
  /// is put down whole), but after a run of steps at rest what its walk cost
  /// is taken from the step's settle and passes, up to half the cap
  /// (SoilStepResult::displace_visits, relax_budget). A step never does
  /// more; the rest is carried on in the next step (see above). The spill
  /// over a blade's top (BladeSpec::height_m), last in a step, walks at
  /// most this many cells besides (SoilStepResult::over_top_visits). On the
  /// project's 2-core machine a pass's visit costs 3.6 to 6 ns and a
  /// settle's charged visit 7 to 11 ns (the TSC over whole pushes,
  /// 2026-12-07; 6 and 7 on 2026-12-06), so a step at the default cap costs
  /// up to about 0.5 ms there at a quiet load (docs/soil.md, "Speed: the
  /// second pass", "The settle charged for its time", "A crossing's settle
  /// over two steps"): it is a work bound, not a clock; a lower cap is a
  /// tighter time bound, but lets a pushed pile lag further behind the
  /// blade.
  std::int64_t max_pair_checks_per_step = 50000;
  /// The grid's edge: a wall, or open (bare ground beyond it at height 0).
  SoilEdge edge = SoilEdge::kWall;
  /// How a displaced pile settles (SoilSettle).
  SoilSettle settle = SoilSettle::kFans;
};

/// The ranges of SoilFlowParams' own numbers (core/ranges.hpp): validate()
/// checks them and the scenario reader reads `soil:` through them (the
/// material's are material_ranges()).
inline constexpr Range kSoilFlowRanges[] = {
    {"max_pair_checks_per_step", 1000, 1e9, RangeEnds::kClosed, true},
};

/// Returns an empty string when params are valid, else a message naming the field.
std::string validate(const SoilFlowParams& params);

/// What the soil phase did in one step.
struct SoilStepResult {
  double displaced_volume_m3 = 0.0;  ///< cut soil put down ahead of the blade (soil pushed again counts again), m^3
  /// The part of the step's cut that lay below the initial surface, m^3:
  /// ground the blade cut, not pile it cut again (soil that slid back into
  /// the cut and is cut again counts again).
  double cut_from_ground_m3 = 0.0;
  int passes = 0;                    ///< relaxation passes run
  std::int64_t pair_checks = 0;      ///< work done, in neighbour visits (see max_pair_checks_per_step)
  /// The part of pair_checks the settle of the displaced pile did (docs/soil.md
  /// "The displaced pile settled at once"), in neighbour visits.
  std::int64_t settle_visits = 0;
  /// What the displacement's walk cost, in visits (3 a cell its walks
  /// passed: docs/soil.md "A crossing's settle over two steps"). Not part of
  /// pair_checks and not bounded by the cap (a step's cut is displaced
  /// whole). After 8 steps in a row whose relaxation finished within the
  /// cap, it is taken from this step's settle and passes, up to half the
  /// cap (relax_budget), and what they leave goes on in the next step.
  std::int64_t displace_visits = 0;
  /// What this step's settle and passes could do, in visits: the cap, less
  /// what displace_visits took from it (the spill round the blade's ends,
  /// before them, is held to the cap itself).
  std::int64_t relax_budget = 0;
  std::int64_t moved_pairs = 0;      ///< pairs that exchanged soil
  std::int64_t backlog_cells = 0;    ///< cells still active after the step (carried over)
  /// The relaxation stopped at the work cap (max_pair_checks_per_step) with
  /// work left, the spill round the blade's ends, the settle of the
  /// displaced pile, the passes or the spill over a blade's top (its own
  /// allowance spent); the rest is done in later steps. How
  /// often a push reaches it, and how far the capped pile then lies from
  /// the converged one (within 1 % along an axis; not at a slant on 5 mm
  /// cells), is measured in docs/soil.md ("Not done yet").
  bool reached_cap = false;
  /// Fluxes examined in an earlier step and dropped in this one because a
  /// cell they join changed (or the tool moved into their way) meanwhile:
  /// work the cap paid for nothing. None with a tool in the soil, where the
  /// cap splits a pass rather than carry its fluxes over.
  std::int64_t stale_fluxes = 0;
  double left_over_edge_m3 = 0.0;    ///< soil that left over an open edge, m^3
  double bucket_in_m3 = 0.0;         ///< cut soil the bucket took in this step, m^3
  double poured_m3 = 0.0;            ///< soil poured from the bucket's lip this step, m^3
  double bucket_load_m3 = 0.0;       ///< soil in the bucket after the step, m^3
  double shouldered_m3 = 0.0;        ///< soil the bucket's hull pushed out of its footprint this step, m^3
  /// Soil that stood above a blade's top (BladeSpec::height_m) and fell
  /// over it to the other side this step, m^3 (0 for a blade of unbounded
  /// height, the default).
  double over_top_m3 = 0.0;
  /// Cells the spill over the blade's top walked down the other side this
  /// step (not part of pair_checks: an allowance of its own, at most
  /// max_pair_checks_per_step).
  std::int64_t over_top_visits = 0;
  Rect changed{};                    ///< samples whose height the phase changed
};

/// A rigid obstacle for flowing soil: the samples under it (closed to soil
/// coming in) and the height of its underside above the ground there,
/// metres (a change of it, as of the cells, wakes the soil along its sides).
struct SoilObstacle {
  Rect cells{};
  float bottom_m = 0.0f;
};

/// Soil a bucket holds in the given orientation, m^3: its section (see
/// BucketSpec) below the surface that rises from the lip into the bucket
/// at the repose angle (steeper, the soil would slide out over the lip),
/// times its length. Level, that is the struck capacity when height_m <=
/// depth_m x tan(repose); tilted so the floor is steeper than the repose
/// angle, zero; with neither the floor nor the back wall facing up (upside
/// down), zero. 0 without a bucket.
double bucket_retained_m3(const BladeSpec& blade, const Quat& orientation, double repose_deg);

/// The steepest plane, in degrees, that the relaxation leaves standing on
/// cells of cell_x_m x cell_z_m for a repose angle of repose_deg. A plane
/// moves only where its drop toward one of the 8 neighbours passes that
/// pair's limit (tan(repose) x distance, plus the tolerance); a fall line
/// between two neighbour directions meets both pairs at a slant, so a
/// plane there stands steeper than the repose angle. The steepest is where
/// two angularly adjacent neighbours' bounds meet, in the widest gap: on
/// square cells (gaps of 45 degrees) 36.6 degrees for 34; on cells twice
/// as long along Z as along X (the diagonal 63.4 degrees off the X axis,
/// 26.6 off Z) 38.8, on 4:1 40.9. A
/// cone settles at the repose angle along the 8 directions and up to this
/// in between.
double steepest_standing_slope_deg(double cell_x_m, double cell_z_m, double repose_deg);

/// The soil phase's state (kFlow): the active cells and the scratch of the
/// passes, sized at construction (2 bytes per sample, plus lists for the
/// blade's footprint and an active set of at least 65536 cells) so that a
/// step allocates nothing (tested in the haptic loop on flowing soil); only
/// a backlog larger than that grows them.
class SoilFlow {
 public:
  /// Builds the state over the grid (which must outlive it) and marks every
  /// cell steeper than the repose angle active. Throws InputError naming the
  /// field on bad params.
  SoilFlow(const SoilFlowParams& params, const HeightGrid& grid, const BladeSpec& blade = {});

  /// Before the cut of a step: remembers the heights under the region the
  /// edge may sweep from `from` to `to` (their bounding rectangle plus a
  /// cell), so that the cut's change of each sample is known afterwards.
  void before_cut(HeightGrid& grid, const Segment& from, const Segment& to);

  /// After the cut: displacement of what was cut ahead of the edge `to`
  /// (moving from `from`) or into the bucket, the bucket's pour at its
  /// `orientation` (the blade frame's), the edge's cells capped, then
  /// relaxation.
  SoilStepResult after_cut(HeightGrid& grid, const Segment& from, const Segment& to,
                           const Quat& orientation = {});

  /// A new stroke begins (Simulation::lift): which way the blade goes is
  /// measured afresh from its next step (motion_origin), not from where the
  /// last stroke ended, even where the new one starts at that very pose.
  void new_stroke() {
    motion_mid_.known = false;
    motion_ends_.known = false;
  }

  /// Relaxation only (no blade): e.g. between strokes, or a settling run.
  SoilStepResult relax(HeightGrid& grid);

  /// The obstacles for the next steps (replacing the previous ones), at most
  /// kMaxObstacles (more are ignored); rectangles are clipped to the grid.
  /// Allocation-free once the list has grown to its largest size.
  void set_obstacles(std::span<const SoilObstacle> obstacles) noexcept;
  static constexpr int kMaxObstacles = 255;
  /// The highest the displacement may pile soil, metres above the ground
  /// (default: unbounded). The Bullet world sets its heightfield's upper
  /// bound here, so that no pile rises past it and is clamped (deleted).
  /// The displacement, the spill round the ends and the relaxation's passes
  /// raise no cell past it (a pass's source keeps what would), but for
  /// float rounding (2 ulps above a 0.3 m ceiling in a push into a pocket:
  /// docs/soil.md, "Soil slides along a body's face").
  void set_ceiling(float height_m) noexcept { ceiling_m_ = height_m > 0.0f ? height_m : ceiling_m_; }
  float ceiling_m() const { return ceiling_m_; }
  /// The obstacles as last set (their cells clipped to the grid).
  std::span<const SoilObstacle> obstacles() const { return obstacles_; }
  /// Soil in the bucket, m^3 (0 without one).
  double bucket_load_m3() const { return load_m3_; }
  /// Marks the cells of `rect` and their neighbours (clipped to the grid)
  /// for relaxation, after an edit made outside a step; the next step's
  /// passes examine them.
  void wake(const Rect& rect);

  /// Cells still active (the backlog).
  std::int64_t active_cells() const {
    // (While a settle's seed phase compacts the lists, the slots of the
    // cells it dropped are still inside them until it ends.)
    const std::size_t dropped = settle_phase_ == SettlePhase::kSeed
                                    ? settle_q_ - settle_keep_active_ - settle_keep_next_
                                    : 0;
    return std::int64_t(active_.size() - examined_ + fluxes_.size() - applied_ + next_.size() - dropped);
  }
  const SoilFlowParams& params() const { return params_; }

 private:
  void activate(std::uint32_t cell) {
    const unsigned f = queued_[cell];
    queued_[cell] = CellFlags(f | kQueued);
    next_.push_if(cell, !(f & kQueued));
  }
  void lowered(std::uint32_t cell, const float* h, bool self = true);
  /// Marks cell a as held by the blade or the hull (examined again once
  /// they have moved), once.
  void hold(std::uint32_t a) {
    if (queued_[a] & kHeld) return;
    set_flag(a, kHeld);
    held_.push_back(a);
  }
  /// Queues the cells the blade or hull held once they have moved (edge:
  /// where the blade's edge stands now; nullptr: all). Returns whether any
  /// were woken.
  bool wake_held(const Segment* edge);
  void mark_blade(const HeightGrid& grid, const Segment& from, const Segment& edge);
  void clear_blade();
  /// The state of motion_origin: a new stroke (new_stroke, which
  /// Simulation::lift calls; or a step whose `from` is not the last step's
  /// `to`) starts it afresh, so a new stroke does not take its way from
  /// where the last one ended.
  struct MotionTrack {
    Segment anchor{};  ///< the edge where the blade last moved that far
    Segment from{};    ///< where it stood before that move
    Segment last{};    ///< the last step's `to`
    bool known = false;
  };
  /// Where the blade's motion is measured from, for a step from `from` to
  /// `to`: the edge where it stood before it last moved more than 2
  /// kMotionCells of a cell in plan (so that the motion is more than the
  /// side tests' kMotionCells), so a slow blade's motion is that of its last
  /// few steps together, not one step's, and a blade standing still keeps
  /// the way it last went. With by_ends the move is either end's (the
  /// passes' wall, which looks at each end's motion), else the midpoint's
  /// (the displacement, the spill and the settle, which look at the
  /// midpoint's: a turning blade's ends move further than its middle, and
  /// moves counted at the ends left the middle's under a hundredth of a
  /// cell).
  const Segment& motion_origin(MotionTrack& track, const Segment& from, const Segment& to, bool by_ends);
  /// Whether the blade stops soil at height top_m flowing from cell
  /// (hc, hr) to its neighbour (lc, lr).
  bool blade_blocks(int hc, int hr, int lc, int lr, float top_m) const;
  /// Column and row of cell i.
  int col_of(std::uint32_t i) const { return int(i - row_div_.quotient(i) * std::uint32_t(cols_)); }
  int row_of(std::uint32_t i) const { return int(row_div_.quotient(i)); }
  bool pending() const { return !active_.empty() || !next_.empty(); }
  /// Queues a cell the displacement changed (was_lowered: its neighbours
  /// may now stand too steep above it) for settle_candidates.
  void candidate(std::uint32_t cell, bool was_lowered) {
    const unsigned f = queued_[cell];
    queued_[cell] = CellFlags(f | kCandidate | (was_lowered ? kCandLowered : 0));
    candidates_.push_if(cell, !(f & kCandidate));
  }
  /// Queues the candidates that stand too steep toward a neighbour, and the
  /// neighbours that stand too steep above a lowered one.
  void settle_candidates(const float* h);
  /// Whether cell a stands steeper than a pair's limit and the tolerance
  /// toward some neighbour (examine's test, without the blade).
  bool steep_now(std::uint32_t a, const float* h) const;
  /// The cut soil pushed ahead of the edge `to`: the way it goes, at each
  /// point of the edge, is that point's motion across the edge's line (its
  /// ends' motions interpolated along it: a turning blade's parts can go
  /// opposite ways) in this step (from `from`) where that is more than
  /// rounding, else its motion since `moved_from` (motion_origin: a blade
  /// that stands still or goes straight down keeps the way it went).
  void displace(HeightGrid& grid, const Segment& from, const Segment& moved_from, const Segment& to,
                double bucket_room_m3,
                SoilStepResult& out);
  void pour(HeightGrid& grid, const Segment& lip, double volume_m3, SoilStepResult& out);
  void mark_hull(const HeightGrid& grid, const Segment& lip, const Quat& orientation);
  void clear_hull();
  void shoulder(HeightGrid& grid, SoilStepResult& out);
  /// Where cell (c, row) of the hull's bounding rectangle is in hull_under_.
  std::size_t hull_slot(int c, int row) const {
    return std::size_t(row - hull_rect_.r0) * std::size_t(hull_rect_.c1 - hull_rect_.c0) + std::size_t(c - hull_rect_.c0);
  }
  /// The hull's underside over a marked cell (kHull set), metres above the ground.
  float hull_under(std::uint32_t cell) const {
    return hull_under_[hull_slot(col_of(cell), row_of(cell))];
  }
  /// Adds delta_m, a float rounding the writes lost (or, negative, gained),
  /// back to a cell, never below the floor nor above the ceiling (a cell
  /// already at the ceiling keeps it: the ulp is left out of the books
  /// rather than clamped, and so deleted, by the Bullet heightfield).
  void give_back(float& height_m, double delta_m) const {
    height_m = float(std::clamp(double(height_m) + delta_m, 0.0, std::max(double(ceiling_m_), double(height_m))));
  }
  void run_passes(HeightGrid& grid, SoilStepResult& out);
  /// The soil above the repose cone through each end of the edge `to`
  /// slides round it, down to the cells under the cone, those the edge has
  /// just cut behind it included (soil_ends.cpp); `from` is where its
  /// motion is measured from (motion_origin), for which side is behind.
  void spill_round_ends(HeightGrid& grid, const Segment& from, const Segment& to, SoilStepResult& out);
  /// The soil standing against the edge `to` higher than the blade's top
  /// (BladeSpec::height_m, turned with `orientation`) falls over it onto the
  /// first cell clear of the blade on the other side (soil_top.cpp). A
  /// blade of unbounded height, or a bucket, does nothing here.
  void spill_over_top(HeightGrid& grid, const Segment& edge, const Quat& orientation, SoilStepResult& out);
  // spill_round_ends' window round an end's apex (the first cell past it),
  // per cell: where it lies, its distance to the apex, and donor / receiver
  // in the round; sized at construction.
  std::vector<std::uint8_t> ends_place_;
  std::vector<float> ends_dist_;
  std::vector<std::uint8_t> ends_state_;
  double ends_s_[2] = {0.0, 0.0};  // each end's cone height at the last call
  bool cut_last_step_ = false;     // the last after_cut displaced or took in soil
  // The displacement's walk this step, in visits (kDisplaceCellVisits a
  // cell its walks passed), and what the settle and passes may do: the cap,
  // less that walk after a run of steps at rest (after_cut).
  std::int64_t displace_work_ = 0;
  std::int64_t step_cap_ = 0;
  int rest_steps_ = 0;  // steps in a row whose relaxation finished within the cap (up to kRestStepsBeforeCharge)
  std::int64_t ends_work_ = 0;     // visits the spill and the settle spent this step (charged to the cap by run_passes)
  std::vector<std::pair<double, int>> ends_keys_;  // the round's donors' and receivers' cone keys
  std::vector<std::int32_t> ends_queue_;           // the round's sets, window cells in the order found
  /// What the displacement and the spill left steeper than a pair's limit
  /// settles, each connected patch to a stable surface of its own volume
  /// (soil_settle.cpp, docs/soil.md "The displaced pile settled at once"):
  /// settle_start sets it up over the window round `changed`, replacing
  /// one under way; settle_continue does up to `budget` visits of it and
  /// returns them (it is done when settle_phase_ is back to kIdle; the
  /// passes wait for it); settle_abort drops it.
  void settle_start(HeightGrid& grid, const Segment& from, const Segment& to, const Rect& changed, int round = 0);
  /// The columns [row_lo[lr], row_hi[lr]) of each row lr of the settle's
  /// window that the blade (`to`, its side behind it from `from`) walls off:
  /// with `band`, the cells inside it and behind it; without, only those
  /// whose centres it has passed (none when no side is known).
  void settle_wall_rows(const GridSpec& spec, const Segment& from, const Segment& to, bool band, int* row_lo,
                        int* row_hi) const;
  /// A settle under way, spread over steps, follows the blade: the cells
  /// the edge has passed since the settle started (behind its line now, and
  /// not walled then) leave it.
  void settle_follow(const GridSpec& spec, const Segment& from, const Segment& to);
  std::int64_t settle_continue(HeightGrid& grid, Rect& changed, std::int64_t budget);
  /// settle_continue, its visits charged to the step's cap (ends_work_).
  std::int64_t settle_charged(HeightGrid& grid, Rect& changed, std::int64_t budget) {
    const std::int64_t done = settle_continue(grid, changed, budget);
    ends_work_ += done;
    return done;
  }
  /// Back to kIdle after `work` visits; starts the chained settle, if any,
  /// with what is left of `budget`. Returns the visits done.
  std::int64_t settle_finish(HeightGrid& grid, Rect& changed, std::int64_t budget, std::int64_t work);
  /// settle_exclude for every cell of `rect`.
  void settle_exclude(const Rect& rect);
  void settle_abort();
  /// Another writer changed `cell` while a settle is under way: the cell
  /// takes no part in its patches (each still keeps its own volume, from
  /// its cells' heights; the passes see to the rest).
  void settle_exclude(std::int64_t cell) {
    if (settle_phase_ == SettlePhase::kIdle) return;
    const int lc = col_of(std::uint32_t(cell)) - settle_wc0_, lr = row_of(std::uint32_t(cell)) - settle_wr0_;
    if (lc < 0 || lr < 0 || lc >= settle_ww_ || lr >= settle_wh_) return;
    settle_leave(std::size_t(lr) * std::size_t(settle_ww_) + std::size_t(lc));
    settle_drop_ok_ = false;
  }
  // A window cell's state bits of the settle's patches: in a patch found
  // (kSettleInPatch), in the one under way (kSettleCurrent), changed by
  // another writer (kSettleExcluded).
  // In the second round (the seams): written by the first (kSettleWrote),
  // changed by another writer since the first began (kSettleFresh).
  static constexpr std::uint8_t kSettleInPatch = 8, kSettleExcluded = 16, kSettleCurrent = 32;
  static constexpr std::uint8_t kSettleWrote = 64, kSettleFresh = 128;
  /// Marks a window cell excluded, counting it if it leaves the patch under way.
  void settle_leave(std::size_t l) {
    std::uint8_t& bits = settle_done_[l];
    if (bits & kSettleExcluded) return;
    if (bits & kSettleCurrent) ++settle_patch_left_;
    bits |= kSettleExcluded;
    if (settle_lists_excluded_) settle_excluded_.push_back(std::uint32_t(l));
  }
  /// Sizes the settle's scratch for a window of this many cells.
  void reserve_settle(std::size_t window_cells);
  enum class SettlePhase : std::uint8_t { kIdle, kSeed, kLow, kHigh, kPatches };
  SettlePhase settle_phase_ = SettlePhase::kIdle;
  // A step displaced soil while a settle was under way: another follows it
  // (over the cells the steps since changed), before the passes.
  bool settle_again_ = false;
  // The round under way (0: the fans, 1: their seams); the cells the first
  // wrote (and their rectangle), and those another writer changed while it
  // ran; the blade where it last stood (the second round's wall).
  int settle_round_ = 0;
  Rect settle_written_{};
  std::vector<std::uint32_t> settle_wrote_, settle_fresh_;
  // The window cells other writers changed in the fans' first round, as
  // they were excluded (the second round walls them off), and whether they
  // are being listed.
  std::vector<std::uint32_t> settle_excluded_;
  bool settle_lists_excluded_ = false;
  Segment settle_from_{}, settle_to_{};
  Rect settle_next_rect_{};
  Segment settle_next_from_{}, settle_next_to_{};
  // The settle's window (first column and row, columns, rows); where it is
  // in its phase (the list index of the seeding and the patches; the
  // spread's current bucket, the buckets used and the lowest key).
  int settle_wc0_ = 0, settle_wr0_ = 0, settle_ww_ = 0, settle_wh_ = 0;
  std::size_t settle_q_ = 0, settle_b_ = 0, settle_used_ = 0;
  // The patch under way (settle_patch_, from touched[settle_q_]): searched
  // up to settle_patch_next_, balanced (its delta) or to be written; its
  // balances, and the cells that left it (in all, and when it was
  // balanced).
  enum class PatchStage : std::uint8_t { kNone, kSearch, kSolve, kWrite };
  PatchStage settle_patch_stage_ = PatchStage::kNone;
  std::size_t settle_patch_next_ = 0;
  int settle_patch_balances_ = 0;
  std::uint64_t settle_patch_left_ = 0, settle_balanced_at_ = 0;
  // The seed phase drops the listed cells it finds standing at rest (the
  // test a pass would make of them), compacting the lists in place: where
  // the kept ones of active_'s unexamined tail and of next_ have been
  // written so far. Only while no height in the window changed since the
  // settle began (settle_drop_ok_): the window's copy is then the grid.
  std::size_t settle_keep_active_ = 0, settle_keep_next_ = 0;
  bool settle_drop_ok_ = false;
  /// Keeps a listed cell the seed phase read: written at the next kept
  /// slot of its list (active_'s unexamined tail or next_).
  void settle_keep(std::uint32_t cell, bool in_active);
  /// Ends the seed phase's compaction: the entries not read yet move down
  /// to the kept ones, and both lists are cut there.
  void settle_compact_rest();
  float settle_kmin_ = 0.0f;
  // Its scratch, per window cell: its state bits, the low and high
  // surfaces; per row, the columns the blade walls off; the cells changed,
  // a patch, its widths, the seeds, and the buckets' lists (entries: cell,
  // next; heads per bucket).
  std::vector<std::uint8_t> settle_done_;
  std::vector<float> settle_low_, settle_high_, settle_widths_;
  std::vector<int> settle_row_lo_, settle_row_hi_;
  std::vector<int> settle_follow_lo_, settle_follow_hi_;  // settle_follow's scratch
  std::vector<std::int32_t> settle_cells_, settle_patch_;
  // The cell each spread reached a cell from (its seed), set where it changed the value.
  std::vector<std::int32_t> settle_root_low_, settle_root_high_;
  // The patch under way's fans: each one's balance, a fan's slot by its id
  // (-1: none), each patch cell's slot (-1: excluded).
  struct FanBalance {
    std::int32_t id = 0;      // the fan (its source's window cell)
    std::int32_t slot = 0;    // its own slot
    std::int32_t parent = 0;  // the fan it joined (its slot; its own if none)
    double excess = 0.0, room = 0.0;
    // As the root of a group of fans: their excess, cell count, first
    // width in the scratch, and the lowering that balances them.
    double group_excess = 0.0, delta = 0.0;
    std::size_t cells = 0, start = 0;
  };
  std::vector<FanBalance> settle_fans_;
  std::vector<std::int32_t> settle_fan_slot_, settle_cell_fan_;
  // A window cell's fan slot while its patch is balanced (-1 otherwise):
  // the stuck fans' union reads its neighbours' from it.
  std::vector<std::int32_t> settle_cell_slot_;
  std::vector<std::pair<float, std::int32_t>> settle_seeds_[2];
  std::vector<std::pair<std::int32_t, std::int32_t>> settle_entries_;
  std::vector<std::int32_t> settle_heads_;
  /// v rounded to a multiple of the relaxation's quantum, as a float: the
  /// heights it writes and the amounts it moves, so that a cell's sum over
  /// a pass is exact whatever the order of its sources (quantum_m_).
  /// The quantum is a power of two, so v x its inverse is v / quantum to
  /// the bit, and adding and taking away 1.5 x 2^52 rounds a double of
  /// magnitude under 2^51 to the nearest integer, ties to even, as
  /// nearbyint does in the default rounding mode: the same value without
  /// the library call and the division (about 5 % of a capped step's time;
  /// a negative v that rounds to zero gives +0 where nearbyint gave -0,
  /// equal in every comparison and sum).
  float quantized(double v) const {
    const double q = v * inv_quantum_m_;
    if (!(std::abs(q) < 0x1p51)) return float(quantum_m_ * std::nearbyint(q));
    constexpr double kRound = 0x1.8p52;
    // IEEE arithmetic: without -ffast-math no compiler folds (q + k) - k.
    return float(quantum_m_ * ((q + kRound) - kRound));
  }
  /// Zeroes the fluxes [applied_, end) of source a that the blade, the hull
  /// or a body now stands in the way of (the pass was examined in an
  /// earlier step, against where they were then); returns how many.
  std::int64_t drop_blocked_fluxes(std::uint32_t a, std::size_t end, const float* h);
  std::int64_t examine(std::uint32_t a, const float* h);
  /// The fluxes of source a (height ha) down its steep directions dirs[0,
  /// n) (the direction in the low byte, bit 8 set for one beyond an open
  /// edge); returns their count.
  std::int64_t fall_lines(std::uint32_t a, float ha, const float* h, const int* dirs, int n);
  std::int64_t fall_visits_ = 0;  // cells the last examination's fall lines walked
  void finish_pass(HeightGrid& grid, SoilStepResult& out);

  SoilFlowParams params_;
  BladeSpec blade_spec_{};
  double load_m3_ = 0.0;  // soil in the bucket
  float ceiling_m_ = std::numeric_limits<float>::infinity();  // set_ceiling
  int cols_ = 0;
  int rows_ = 0;
  double dx_ = 0.0;
  double dz_ = 0.0;
  double limit_[3] = {0.0, 0.0, 0.0};  // tan(repose) x distance: along X, along Z, diagonal
  float tolerance_m_ = 0.0f;
  double origin_x_ = 0.0;
  double origin_z_ = 0.0;
  // The rounding of a world coordinate on this terrain, metres: 64 double
  // steps of its largest |x| or |z| (1.4e-11 m at 1 km, 1.4e-7 m at 1e7 m).
  // A side of the blade's line or a motion across it is told from rounding
  // by at least this much, so that the answer does not turn with where the
  // terrain lies.
  double coord_rounding_m_ = 0.0;
  detail::IndexDivider row_div_;  // cell index / cols_
  // The 8 neighbours as index offsets and their repose limits (soil_internal.hpp's kNeighbours order).
  std::int64_t offset_[8] = {};
  float limit8_[8] = {};

  // The blade of the step, in plan relative to the grid: its first end, its
  // span, and its edge height above the ground at the first end and along it.
  // len2, len, half (half a cell's width across the edge's line, over
  // len) and the bounds half_lo/half_hi are set by mark_blade for blade_blocks.
  struct BladeLine {
    double ax = 0.0, az = 0.0, dx = 0.0, dz = 0.0, ay = 0.0, dy = 0.0;
    bool present = false;
    double len2 = 0.0, len = 0.0, half = 0.0, half_lo = 0.0, half_hi = 0.0;
    // Each end's motion across the edge's line since motion_origin's
    // origin by the ends (as n's numerator, dx z - dz x), 0 when it did not
    // cross it: the side the edge came from is the other one.
    double across_a = 0.0, across_b = 0.0;
  };
  BladeLine blade_{};

  // Per cell flags in queued_.
  static constexpr std::uint8_t kQueued = 1;  // in next_
  static constexpr std::uint8_t kHeld = 2;    // in held_
  static constexpr std::uint8_t kDirty = 4;   // in dirty_
  static constexpr std::uint8_t kHull = 8;    // under the bucket's hull (in hull_cells_)
  static constexpr std::uint8_t kNearBlade = 16;  // within reach of the step's blade (in marked_)
  static constexpr std::uint8_t kEdge = 32;   // on the grid's border (fewer than 8 neighbours); never cleared
  static constexpr std::uint8_t kCandidate = 64;     // in candidates_
  static constexpr std::uint8_t kCandLowered = 128;  // in candidates_, and lowered
  // A cell the cut, the displacement, the pour or an edit changed while a
  // pass was in progress: the pass's fluxes from or to it are dropped (they
  // came from heights it no longer has; it is examined again anyway). A
  // pass none of whose cells was examined yet has no fluxes: it reads the
  // new heights.
  void dirty(std::uint32_t cell) {
    if (examined_ == 0 || (queued_[cell] & kDirty)) return;
    set_flag(cell, kDirty);
    dirty_.push_back(cell);
  }
  std::vector<std::uint32_t> dirty_;
  // One flux of a pass: share x `excess` metres to cell `to` (kOutside:
  // over an open edge) from its source, a cell that sheds: a source's
  // fluxes are contiguous in fluxes_, and sources_ lists the sources in
  // that order with their counts and their share (the product is formed
  // where the flux is applied, so the share's division is off the
  // examination's critical path).
  struct Flux {
    std::uint32_t to;
    float excess;
  };
  struct Source {
    std::uint32_t cell;
    std::uint32_t fluxes;
    float share;
  };
  // The pass in progress: its cells (frozen list), how many were examined,
  // the fluxes found and how many were applied. A pass is examined whole
  // before any of its fluxes is applied (its fluxes come from one state),
  // but both halves may be spread over steps by the work cap.
  detail::CellList active_;
  std::size_t examined_ = 0;
  std::vector<Flux> fluxes_;
  std::size_t applied_ = 0;
  std::vector<Source> sources_;
  std::size_t applied_sources_ = 0;
  double quantum_m_ = 0.0;     // the relaxation's height quantum (quantized)
  double inv_quantum_m_ = 0.0;  // 1 / quantum_m_ (exact: a power of two)
  bool pass_spans_steps_ = false;  // the pass in progress was examined (in part) in an earlier step
  double pass_gained_m_ = 0.0;    // height the pass's writes gained by float rounding
  // The highest cells the pass lowered (all tied for highest, up to
  // kMaxTiedHighest of them, and how many there were): they take its rounding.
  static constexpr int kMaxTiedHighest = 8;
  std::uint32_t pass_highest_[kMaxTiedHighest] = {};
  int pass_highest_count_ = 0;
  float pass_highest_h_ = -1.0f;
  detail::CellList next_;    // cells to examine in the next pass (kQueued set)
  // The cells the displacement changed in this step (kCandidate set):
  // queued only where they stand too steep once it is done.
  detail::CellList candidates_;
  // The per-cell flags' byte: an enumeration, not std::uint8_t, because a
  // store through a character type may alias any object, so each flag
  // written made the compiler reload the lists' ends and the pass's sums
  // from memory; an enumeration's stores alias only its own type.
  enum CellFlags : std::uint8_t {};
  void set_flag(std::uint32_t cell, std::uint8_t bit) { queued_[cell] = CellFlags(queued_[cell] | bit); }
  void clear_flag(std::uint32_t cell, std::uint8_t bit) { queued_[cell] = CellFlags(queued_[cell] & ~unsigned(bit)); }
  std::vector<CellFlags> queued_;   // per cell: the flags above (one byte read gives them all)
  // Cells that kept an excess only because the blade stood in the way: they
  // are examined again once the blade has moved (held_edge_ is where it was).
  std::vector<std::uint32_t> held_;
  Segment held_edge_{};
  Segment held_heel_{};  // the bucket's heel where it held them (a turn about the lip moves it)
  // The bucket's hull of the step: the cells under it (kHull set) and its
  // underside over its bounding rectangle (+inf where it does not cover),
  // and its plan centre.
  std::vector<std::uint32_t> hull_cells_;
  std::vector<float> hull_under_;
  std::vector<float> shoulder_in_;  // per hull_under_ slot: soil the shoulder passed on to it this step, m
  // Per row of the rectangle, the columns [first, end) that a plate may
  // cover (mark_hull tests only those).
  std::vector<int> hull_row_c0_, hull_row_c1_;
  Rect hull_rect_{};
  Segment hull_heel_{};
  double hull_cx_ = 0.0, hull_cz_ = 0.0;
  // The plates' plans: a point (x, z) lies on one where s = ((x, z) - o) x b
  // / det and t = a x ((x, z) - o) / det are in [0, 1] (none where the
  // plate is seen edge-on, det 0). The shoulder's walks start past the
  // samples that lie deep inside one.
  struct HullPlan {
    double ox = 0.0, oz = 0.0, ax = 0.0, az = 0.0, bx = 0.0, bz = 0.0, det = 0.0, inv_det = 0.0;
    double margin_s = 0.0, margin_t = 0.0;  // a cell's diagonal in s and in t
  };
  HullPlan hull_plans_[2]{};
  /// The first sample of a shoulder's walk from the centre (x, z) along
  /// (nx, nz) x step that may lie outside the hull: those before it lie more
  /// than a cell's diagonal inside a plate's plan and inside the grid, so
  /// in cells the hull covers.
  int first_walk_sample(const GridSpec& spec, double x, double z, double nx, double nz, double step) const;
  std::vector<std::uint8_t> obstacle_;    // per cell: 1 + index into obstacles_, 0 for none
  std::vector<SoilObstacle> obstacles_;   // the obstacles, their cells clipped to the grid
  /// True when a body stands over the cell: no soil flows or is pushed into
  /// it, whatever the gap under the body (soil filling the gap would lift
  /// the body from below instead of banking against its side).
  bool obstructed(std::uint32_t cell) const { return obstacle_[cell] != 0; }
  std::vector<std::uint32_t> marked_;     // cells with kNearBlade set

  Rect before_rect_{};        // where before_ holds the pre-cut heights
  std::vector<float> before_;  // (rect rows) x (rect cols), row-major
  std::vector<float> after_cut_;  // the same samples after the cut, before the displacement writes

  MotionTrack motion_mid_;   // motion_origin by the edge's midpoint
  MotionTrack motion_ends_;  // and by its ends
};

}  // namespace terracut
