// Internal to the soil phase (soil.hpp), shared by its files, one per
// phase: soil.cpp (parameters, construction, the step's order), soil_displace.cpp
// (the blade's cut soil put down ahead, and the blade as a wall),
// soil_relax.cpp (relaxation by fall lines), soil_bucket.cpp (the bucket's
// hull, load and pour), soil_bodies.cpp (rigid bodies as obstacles). The
// constants every phase reads, and the two members the displacement and the
// relaxation both call on their hot paths (inline). Not part of the public API.
#pragma once

#include "terracut/core/soil.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <vector>

namespace terracut::soil_internal {
/// Radius around the edge, in cells, of the cells whose pairs are tested
/// against the blade (a pair is at most one diagonal long).
inline constexpr double kBladeRadiusCells = 1.5;
/// Distance beyond the edge's line, in cells, where displaced soil is put:
/// the cell there is the first whose centre is clear of the blade (0.5 to
/// 1.5 cells ahead), so that the push shifts the profile in front of the
/// blade as a whole (at 1.5 it skipped the cell against the blade and left
/// a dip there that drained the whole face).
inline constexpr double kDepositAheadCells = 1.0;
/// A slope moves only when it exceeds the repose limit of a cell pair by
/// more than this fraction of the limit: 2 % of tan(repose), at most about
/// 0.5 degree above the repose angle (34 degrees: 34.4). Smaller tolerances
/// only lengthen the tail of a settling pile.
inline constexpr double kToleranceOfLimit = 0.02;
/// How far, in cells, the blade's ends move before the soil it held up is
/// examined again.
inline constexpr double kHeldMoveCells = 0.25;
/// How far, in cells, the blade must have moved across its line for the
/// motion to say which side of it is the trench behind it (the spill round
/// the ends, the settle's wall): less is rounding or a device's tremor. The
/// motion is measured from where the blade stood before it last moved
/// twice that (SoilFlow::motion_origin), not over one step: at 0.1 m/s on
/// 1 cm cells a step moves 0.1 mm, 1 % of a cell, and a test of each
/// step's motion alone took such a push for a blade at rest.
inline constexpr double kMotionCells = 0.01;
/// Longest run of cells the blade pushes ahead of it, per cut sample.
inline constexpr int kMaxPushCells = 512;
/// Longest fall line a source's soil slides down in one pass, cells (what
/// lies beyond is reached in the next pass, from the line's end).
inline constexpr int kMaxFallCells = 32;
/// Rounds of the water fill after the first (each drops the cells that
/// stand above the line); what a source would still give past them stays
/// on it (a later pass moves it). Two settle nearly every source.
inline constexpr int kMaxExtraRounds = 2;
/// The most one examination can cost, in visits: its 8 neighbours, its
/// fall lines, and their cells read again in each further round. The work
/// cap admits a cell only with this much room left, so a step never passes
/// it (and the minimum cap, 1000, leaves room for one).
inline constexpr std::int64_t kMostExamineVisits = 8 + 8 * kMaxFallCells * (1 + kMaxExtraRounds);
static_assert(kMostExamineVisits <= 1000);
/// The window round each end of the blade that spill_round_ends builds
/// in: this many cells each way from the end's apex (24 cm on 5 mm cells;
/// sets that reach its border stop there, and the passes do the rest).
inline constexpr int kEndWindowCells = 48;
/// Rounds of spill_round_ends' search for the cone's height (each finds the
/// sets for the last height and solves the balance over them).
inline constexpr int kEndRounds = 6;
/// The settle's window (soil_settle.cpp): the cells the step changed and
/// this many more round them. At 16 the patches of a large pile's flanks
/// reached the window's border, which takes values but passes none on: the
/// seam came down by a wave of passes one cell a pass, about 20 passes in
/// every row crossing of a 1 m blade on 5 mm cells once the pile stood
/// 0.6 m long (docs/soil.md, "The settle's window").
inline constexpr int kSettleMarginCells = 32;
/// What the work cap charges the settle for a cell it handles in any of its
/// phases (a seed's test, a cell of either spread, a cell of a patch), in
/// the cap's unit, the passes' neighbour visit: its 8 neighbours are read
/// and compared in one pair of SSE loads, so a cell costs about 27 ns on
/// the project's 2-core machine (3.3 to 3.5 ns for each of 8 visits
/// charged until 2026-12-06), about 4.6 of the collapse's pass visits
/// (5.9 ns in its worst tick). At 8 it was charged twice its time against
/// the passes, and the settle of a 1 m/s push on 5 mm cells outgrew the cap
/// (docs/soil.md, "The settle charged for its time").
inline constexpr std::int64_t kSettleCellVisits = 4;
/// What the displacement's walk costs a cell it passes (the cell found,
/// its height shifted or filled and written, queued for the settle), in
/// visits: 55 to 61 cycles against the settle's 21 to 24 a visit, 2.6 of
/// them, rounded up (the TSC over whole pushes of a 2 m blade on 1 cm cells
/// and a 1 m blade on 5 mm cells, 2026-12-07; SoilFlow::after_cut).
inline constexpr std::int64_t kDisplaceCellVisits = 3;
/// The steps in a row whose relaxation finished within the cap after
/// which a step's displacement is charged to its relaxation (after_cut):
/// pushes on 1 cm cells at up to 1 m/s cross a row every 10 steps or more
/// and settle it in one or two; on 5 mm cells at 0.5 m/s and over they
/// cross every 10 or fewer and are at the cap for about 3 steps after
/// each, and the work put off would wait on the next crossing's.
inline constexpr int kRestStepsBeforeCharge = 8;
/// The run of steps at rest after a step whose relaxation did, or did not,
/// reach the cap (counted up to kRestStepsBeforeCharge).
inline int rest_run_after(int run, bool reached_cap) {
  return reached_cap ? 0 : std::min(run + 1, kRestStepsBeforeCharge);
}
/// Two values of the settle's surfaces closer than this are a tie (the
/// float sums along two mirror-image paths differ in their last bits),
/// metres: the nearer source takes the cell (soil_settle.cpp).
inline constexpr float kSettleTie_m = 1e-6f;
/// The fans (SoilSettle::kFans): a cell whose surfaces the spreads moved by
/// no more than this many of the passes' tolerances belongs to no fan but
/// its own; a fan whose room (its widths less its soil) is less than this
/// share of its soil joins every fan it borders (half: a fan of a steep
/// pair's two cells has room equal to its soil exactly, and float sums put
/// it on either side of a share of one).
inline constexpr double kFanMarginOfTolerance = 2.0;
inline constexpr double kStuckRoomOfExcess = 0.5;
/// A patch cell's share of it, by what the patch does with the cell: find
/// it (its 8 neighbours tested, about 10 ns), balance it (its excess and
/// width summed, the level selected: about 8 ns) and write it (about 7 ns;
/// the 1.5 m blade's push on 5 mm cells, 2.4 m, cap lifted, 2026-12-06).
inline constexpr std::int64_t kPatchSearchVisits = 2, kPatchSolveVisits = 1, kPatchWriteVisits = 1;
static_assert(kPatchSearchVisits + kPatchSolveVisits + kPatchWriteVisits == kSettleCellVisits);
/// The most balances of one patch whose cells other writers change between
/// its balance and its write (the next crossing's displacement shifts the
/// pile under it); after them it is left to the passes unwritten.
inline constexpr int kPatchBalances = 3;
/// The room under the ceiling of a cell the settle or the displacement gives
/// its rounding back to (far more than the rounding), metres.
inline constexpr float kGiveBackRoom_m = 1e-3f;
/// The cell a writer gives its rounding `delta_m` back to: the last it
/// wrote, or, where that would rise past the ceiling (whose clamp would
/// delete it), the last it wrote with kGiveBackRoom_m of room, if any.
inline std::int64_t give_back_cell(const float* h, std::int64_t last, std::int64_t last_with_room, double delta_m,
                                   float ceiling_m) {
  return double(h[last]) + delta_m > double(ceiling_m) && last_with_room >= 0 ? last_with_room : last;
}
/// Its buckets of keys, each an axis pair's limit wide: heights up to this
/// many limits apart (13.8 m on 5 mm cells at 34 degrees); what lies beyond
/// is left to the passes.
inline constexpr std::size_t kSettleBuckets = 4096;
/// Rows of pile ahead of the blade that the settle's scratch is sized for, beside the blade's square and the spill's windows round its ends
/// (a larger window is left to the passes).
inline constexpr int kSettlePileCells = 64;
/// Fluxes a pass may hold per cell of the reserved active set.
inline constexpr std::size_t kFluxesPerActiveCell = 32;
/// The work cap's charge for a source's fall test (lowered): its 8
/// neighbours read again.
inline constexpr std::int64_t kFallTestVisits = 8;
/// The most an examination's fluxes cost to apply: one visit a flux (8 fall
/// lines of kMaxFallCells cells) and its source's fall test.
inline constexpr std::int64_t kMostExamineFluxVisits = 8 * kMaxFallCells + kFallTestVisits;
/// The least cap at which a pass is split at the cap with a tool in the soil
/// (run_passes): four times the room one examination and its fluxes keep
/// (4160 visits); under it the pass is carried over.
inline constexpr std::int64_t kLeastSplitCap = 4 * (kMostExamineVisits + kMostExamineFluxVisits);
static_assert(kLeastSplitCap == 4160, "the docs and tests/core/soil_converge_test.cpp quote 4160");

// The 8 neighbours: offsets and which limit applies (0 along X, 1 along Z, 2 diagonal).
struct Neighbour {
  int dc;
  int dr;
  int kind;
};
/// The cell index standing for the bare ground beyond an open edge.
inline constexpr std::uint32_t kOutside = 0xffffffffu;

inline constexpr Neighbour kNeighbours[8] = {{1, 0, 0},  {-1, 0, 0}, {0, 1, 1},  {0, -1, 1},
                                             {1, 1, 2},  {-1, 1, 2}, {1, -1, 2}, {-1, -1, 2}};

inline double to_cells(double v, double origin, double cell) { return (v - origin) / cell; }

/// How far the edge's midpoint moved in plan from `from` to `to` (over a
/// step, or since SoilFlow::motion_origin's origin): {x, z}, metres (the
/// bucket's lip, the displacement's push and the spill's and the settle's
/// side the edge came from all read it).
struct PlanMotion {
  double x, z;
};
inline PlanMotion midpoint_motion(const Segment& from, const Segment& to) {
  return {0.5 * ((to.a.x + to.b.x) - (from.a.x + from.b.x)), 0.5 * ((to.a.z + to.b.z) - (from.a.z + from.b.z))};
}

/// floor(v) as an int within [lo, hi]: clamped in double first, so that a
/// point far off the grid (a blade kilometres long is valid input) never
/// overflows the conversion. NaN gives lo.
inline int floor_within(double v, int lo, int hi) {
  const double f = std::floor(v);
  return f >= double(hi) ? hi : f >= double(lo) ? int(f) : lo;
}
/// The same for ceil(v).
inline int ceil_within(double v, int lo, int hi) {
  const double f = std::ceil(v);
  return f >= double(hi) ? hi : f >= double(lo) ? int(f) : lo;
}

/// Writes every element of v's reserved storage once and empties it again:
/// the pages are the process's from construction on, so the first tick to
/// fill a list does not stop on page faults (a first touch of a few MiB of
/// fresh pages costs the system a millisecond or more).
template <typename T>
void touch_reserved(std::vector<T>& v) {
  v.resize(v.capacity());
  v.clear();
}

#if defined(__SSE2__)
/// The heights of an inner cell's 8 neighbours (p points at the cell; up is
/// one row along +Z), in kNeighbours' order: n0 holds k = 0..3, n1 k = 4..7.
inline void load_neighbours(const float* p, std::int64_t up, __m128& n0, __m128& n1) {
  n0 = _mm_setr_ps(p[1], p[-1], p[up], p[-up]);
  n1 = _mm_setr_ps(p[up + 1], p[up - 1], p[1 - up], p[-1 - up]);
}

/// Bit k set where lane k of (e0, e1) (k = 0..3, 4..7) is above tol.
inline unsigned above_mask(__m128 e0, __m128 e1, float tol) {
  const __m128 vt = _mm_set1_ps(tol);
  return unsigned(_mm_movemask_ps(_mm_cmpgt_ps(e0, vt))) | unsigned(_mm_movemask_ps(_mm_cmpgt_ps(e1, vt))) << 4;
}
#endif

}  // namespace terracut::soil_internal

namespace terracut {

inline void SoilFlow::lowered(std::uint32_t cell, const float* h, bool self) {
  // Only the pairs of this cell changed: a neighbour that now stands too
  // steep above it is examined in the next pass (the same test as a pass's),
  // and the cell itself (unless the caller has tested it: self false).
  if (self) activate(cell);
  const float hc = h[cell];
  if (!(queued_[cell] & kEdge)) {
    // All 8 tested without a branch each; the steep ones then activated.
    unsigned steep = 0;
#if defined(__SSE2__)
    // As examine's: four pairs to an instruction, the same bits.
    __m128 hb0, hb1;
    soil_internal::load_neighbours(h + cell, offset_[2], hb0, hb1);
    const __m128 vc = _mm_set1_ps(hc);
    const __m128 e0 = _mm_sub_ps(_mm_sub_ps(hb0, vc), _mm_loadu_ps(limit8_));
    const __m128 e1 = _mm_sub_ps(_mm_sub_ps(hb1, vc), _mm_loadu_ps(limit8_ + 4));
    steep = soil_internal::above_mask(e0, e1, tolerance_m_);
#else
    for (int k = 0; k < 8; ++k)
      steep |= unsigned(h[std::int64_t(cell) + offset_[k]] - hc - limit8_[k] > tolerance_m_) << k;
#endif
    for (; steep != 0; steep &= steep - 1)
      activate(std::uint32_t(std::int64_t(cell) + offset_[std::countr_zero(steep)]));
    return;
  }
  const int c = col_of(cell), r = row_of(cell);
  for (int k = 0; k < 8; ++k) {
    const int cb = c + soil_internal::kNeighbours[k].dc, rb = r + soil_internal::kNeighbours[k].dr;
    if (cb < 0 || rb < 0 || cb >= cols_ || rb >= rows_) continue;
    const std::uint32_t b = std::uint32_t(std::int64_t(cell) + offset_[k]);
    if (h[b] - hc - limit8_[k] > tolerance_m_) activate(b);
  }
}

inline bool SoilFlow::blade_blocks(int hc, int hr, int lc, int lr, float top_m) const {
  // Cell centres relative to the edge's first end, in plan.
  const double xa = (double(hc) + 0.5) * dx_ + origin_x_ - blade_.ax;
  const double za = (double(hr) + 0.5) * dz_ + origin_z_ - blade_.az;
  const double xb = (double(lc) + 0.5) * dx_ + origin_x_ - blade_.ax;
  const double zb = (double(lr) + 0.5) * dz_ + origin_z_ - blade_.az;
  const double len2 = blade_.len2;
  const double len = blade_.len;
  // Signed distances to the edge's line (their numerators na, nb over
  // len), and the half width of a cell across it (blade_.half): a cell
  // closer than that is inside the blade (the edge passes through it).
  // Most pairs lie on one side, outside the blade, and are told so without
  // a division: the sign of na / len is na's, and a |n| away from the half
  // width's numerator by more than rounding (blade_.half_lo, half_hi)
  // compares as |n| / len would.
  const double na = blade_.dx * za - blade_.dz * xa;
  const double nb = blade_.dx * zb - blade_.dz * xb;
  const double half = blade_.half;
  const auto inside = [&](double n) {
    const double q = std::abs(n);
    return q < blade_.half_lo ? true : q > blade_.half_hi ? false : std::abs(n / len) < half;
  };
  bool low_inside = inside(nb);
  // A source inside the blade is on neither side: its soil stands against
  // the blade (the cut takes it when the edge passes its centre), and the
  // side a centre on or next to the edge's line falls on is a matter of
  // rounding (a centre exactly on the line gave na = 0, counted on the
  // negative side, and a pile stood against the blade collapsed into the
  // cut behind it). It sheds nothing across or along the blade.
  bool high_inside = inside(na);
  // Except a cell inside the blade whose centre the edge has passed (on the
  // side it came from, by more than rounding): cut, it lies behind the
  // plate and is the trench's, a cell of that side. A centre on the line
  // (within rounding) is under the plate: it takes no soil from either side
  // and sheds none (it may hold soil the cut has not taken yet: a blade at
  // 45 degrees stands on the centres it has not cut). It once took soil
  // from the side the edge came from; the next step's cut takes such a
  // centre with its region's first line (the region is closed) and pushes
  // what stands on it the way the edge goes, so soil crossed the blade: the
  // trench's slump onto the pile's side as the blade pushed, and a pile onto
  // the trench's side as the blade backed away from it (4.75 cm behind a
  // blade whose line landed on a row of centres every few steps).
  bool a_side = na > 0.0, b_side = nb > 0.0;
  if (low_inside || high_inside) {
    const double margin = std::max(1e-9 * blade_.half_lo, coord_rounding_m_ * len);
    const auto along = [&](double x, double z) { return std::clamp((x * blade_.dx + z * blade_.dz) / len2, 0.0, 1.0); };
    const auto behind_sign = [&](double t) { return -((1.0 - t) * blade_.across_a + t * blade_.across_b); };
    if (low_inside) {
      const double t = along(xb, zb), b = behind_sign(t);
      if (b != 0.0 && std::abs(nb) > margin && nb * b > 0.0) {
        low_inside = false;
        b_side = b > 0.0;  // past the line: on the side the edge came from
      }
    }
    if (high_inside) {
      const double t = along(xa, za), b = behind_sign(t);
      if (na * b > 0.0 && std::abs(na) > margin) high_inside = false;  // na's sign is b's
    }
  }
  if (!low_inside && !high_inside && a_side == b_side) return false;  // one side, outside the blade
  // Where along the edge: at the low cell when it is inside the blade, at
  // the source when it is, else where the pair's segment meets the line.
  double px = xb, pz = zb;
  if (!low_inside) {
    if (high_inside) {
      px = xa;
      pz = za;
    } else {
      const double da = na / len, db = nb / len;
      const double w = da / (da - db);
      px = xa + (xb - xa) * w;
      pz = za + (zb - za) * w;
    }
  }
  const double t = (px * blade_.dx + pz * blade_.dz) / len2;
  if (t < 0.0 || t > 1.0) return false;  // around an end of the blade
  // The blade stops soil whose surface there is above its edge.
  return double(top_m) > blade_.ay + blade_.dy * t;
}

}  // namespace terracut
