// Soil that flows, the displaced pile settled in one construction (soil.hpp,
// docs/soil.md "The displaced pile settled at once"): what the displacement
// and the spill round the blade's ends left steeper than the stencil allows
// is brought, in each connected patch, to a stable surface that keeps the
// patch's volume, rather than by hundreds of relaxation passes.
#include "terracut/core/soil.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <span>
#include <tuple>

#include "soil_internal.hpp"

namespace terracut {

using namespace soil_internal;

namespace {

/// The delta >= 0 with sum over w of (w - delta)+ = excess, for widths
/// w > 0 whose sum is at least excess: a selection in expected linear time
/// (the widths are reordered).
double level_below(std::span<float> w, double excess) {
  double acc_sum = 0.0;  // the widths known to lie above delta, and their count
  std::int64_t acc_n = 0;
  std::size_t lo = 0, hi = w.size();  // the widths not placed yet
  while (lo < hi) {
    // The middle of three as the pivot; the widths above it to the front.
    const float a = w[lo], b = w[lo + (hi - lo) / 2], c = w[hi - 1];
    const float p = std::max(std::min(a, b), std::min(std::max(a, b), c));
    std::size_t m = lo;
    double sum_above = 0.0;
    for (std::size_t j = lo; j < hi; ++j)
      if (w[j] > p) {
        sum_above += double(w[j]);
        std::swap(w[j], w[m++]);
      }
    const std::int64_t n_above = std::int64_t(m - lo);
    if ((acc_sum + sum_above) - double(p) * double(acc_n + n_above) > excess) {
      hi = m;  // delta above p: those at or below it take nothing
    } else {
      // delta at or below p: those above it, and those equal, take their share.
      std::size_t e = m;
      for (std::size_t j = m; j < hi; ++j)
        if (w[j] == p) std::swap(w[j], w[e++]);
      acc_sum += sum_above + double(p) * double(e - m);
      acc_n += n_above + std::int64_t(e - m);
      lo = e;
    }
  }
  return acc_n > 0 ? std::max((acc_sum - excess) / double(acc_n), 0.0) : 0.0;
}

/// A window index split into its row and column with detail::IndexDivider
/// (no divide instruction): the settle does it for every cell it visits,
/// and a division by the window's width, known only at run time, takes 20
/// to 40 cycles.
struct WindowSplit {
  int ww;
  detail::IndexDivider div;
  explicit WindowSplit(int width) : ww(width), div(std::uint32_t(width)) {}
  void operator()(std::int32_t l, int& r, int& c) const {
    r = int(div.quotient(std::uint32_t(l)));
    c = l - r * ww;
  }
};

}  // namespace

void SoilFlow::reserve_settle(std::size_t window_cells) {
  settle_done_.assign(window_cells, 0);
  settle_low_.assign(window_cells, 0.0f);
  settle_high_.assign(window_cells, 0.0f);
  settle_root_low_.assign(window_cells, -1);
  settle_root_high_.assign(window_cells, -1);
  settle_wrote_.reserve(window_cells);
  settle_fan_slot_.assign(window_cells, -1);
  settle_cell_slot_.assign(window_cells, -1);
  settle_cell_fan_.reserve(window_cells);
  settle_fans_.reserve(window_cells);
  touch_reserved(settle_cell_fan_);
  touch_reserved(settle_fans_);
  settle_fresh_.reserve(window_cells);
  touch_reserved(settle_fresh_);
  settle_excluded_.reserve(window_cells);
  touch_reserved(settle_excluded_);
  touch_reserved(settle_wrote_);
  settle_row_lo_.assign(std::size_t(rows_), 0);
  settle_row_hi_.assign(std::size_t(rows_), 0);
  settle_follow_lo_.assign(std::size_t(rows_), 0);
  settle_follow_hi_.assign(std::size_t(rows_), 0);
  settle_cells_.reserve(window_cells);
  settle_patch_.reserve(window_cells);
  settle_widths_.reserve(window_cells);
  settle_seeds_[0].reserve(window_cells);
  settle_seeds_[1].reserve(window_cells);
  settle_entries_.reserve(2 * window_cells);
  settle_heads_.assign(kSettleBuckets, -1);
  touch_reserved(settle_cells_);
  touch_reserved(settle_patch_);
  touch_reserved(settle_widths_);
  touch_reserved(settle_seeds_[0]);
  touch_reserved(settle_seeds_[1]);
  touch_reserved(settle_entries_);
}

void SoilFlow::settle_keep(std::uint32_t cell, bool in_active) {
  if (in_active) active_.set(examined_ + settle_keep_active_++, cell);
  else next_.set(settle_keep_next_++, cell);
}

void SoilFlow::settle_compact_rest() {
  const std::size_t from_active = active_.size() - examined_;
  const std::size_t total = from_active + next_.size();
  for (; settle_q_ < total; ++settle_q_) {
    const bool in_active = settle_q_ < from_active;
    settle_keep(in_active ? active_[examined_ + settle_q_] : next_[settle_q_ - from_active], in_active);
  }
  active_.truncate(examined_ + settle_keep_active_);
  next_.truncate(settle_keep_next_);
}

void SoilFlow::settle_abort() {
  settle_again_ = false;
  if (settle_phase_ == SettlePhase::kIdle) return;
  if (settle_phase_ == SettlePhase::kSeed) settle_compact_rest();
  // The buckets' lists still holding entries are emptied.
  std::fill(settle_heads_.begin(), settle_heads_.end(), -1);
  settle_phase_ = SettlePhase::kIdle;
  settle_patch_stage_ = PatchStage::kNone;
}

void SoilFlow::settle_exclude(const Rect& rect) {
  if (settle_phase_ == SettlePhase::kIdle || rect.empty()) return;
  const int c0 = std::max(rect.c0, settle_wc0_), c1 = std::min(rect.c1, settle_wc0_ + settle_ww_);
  const int r0 = std::max(rect.r0, settle_wr0_), r1 = std::min(rect.r1, settle_wr0_ + settle_wh_);
  for (int r = r0; r < r1; ++r)
    for (int c = c0; c < c1; ++c)
      settle_leave(std::size_t(r - settle_wr0_) * std::size_t(settle_ww_) + std::size_t(c - settle_wc0_));
  if (r0 < r1 && c0 < c1) settle_drop_ok_ = false;
}

void SoilFlow::settle_start(HeightGrid& grid, const Segment& from, const Segment& to, const Rect& changed, int round) {
  if (settle_phase_ != SettlePhase::kIdle) settle_abort();
  if (changed.empty() || settle_low_.empty()) return;
  // The window: the cells the step changed and a margin round them. One
  // larger than the scratch reserved at construction is left to the passes.
  const int wc0 = std::max(0, changed.c0 - kSettleMarginCells), wc1 = std::min(cols_, changed.c1 + kSettleMarginCells);
  const int wr0 = std::max(0, changed.r0 - kSettleMarginCells), wr1 = std::min(rows_, changed.r1 + kSettleMarginCells);
  const int ww = wc1 - wc0, wh = wr1 - wr0;
  if (ww < 3 || wh < 3 || std::size_t(ww) * std::size_t(wh) > settle_low_.size()) return;
  settle_wc0_ = wc0;
  settle_wr0_ = wr0;
  settle_round_ = round;
  settle_excluded_.clear();
  settle_lists_excluded_ = params_.settle == SoilSettle::kFans && round == 0;
  settle_written_ = Rect{};
  if (round == 0) settle_wrote_.clear();
  settle_from_ = from;
  settle_to_ = to;
  settle_ww_ = ww;
  settle_wh_ = wh;
  const std::size_t size = std::size_t(ww) * std::size_t(wh);
  const GridSpec& spec = grid.spec();
  const float* h = grid.heights();
  // The window's heights, twice: the low and the high surfaces start as
  // them. (Window cell l = lr * ww + lc is cell (wc0 + lc, wr0 + lr).)
  for (int lr = 0; lr < wh; ++lr) {
    const float* row = h + std::int64_t(wr0 + lr) * cols_ + wc0;
    std::copy(row, row + ww, settle_low_.data() + std::size_t(lr) * std::size_t(ww));
    std::copy(row, row + ww, settle_high_.data() + std::size_t(lr) * std::size_t(ww));
  }
  std::fill(settle_done_.begin(), settle_done_.begin() + std::ptrdiff_t(size), std::uint8_t(0));
  settle_wall_rows(spec, from, to, true, settle_row_lo_.data(), settle_row_hi_.data());
  if (params_.settle == SoilSettle::kFans)
    for (const std::int32_t l : settle_cells_) settle_root_low_[std::size_t(l)] = settle_root_high_[std::size_t(l)] = -1;
  settle_cells_.clear();
  settle_seeds_[0].clear();
  settle_seeds_[1].clear();
  settle_q_ = 0;
  settle_patch_stage_ = PatchStage::kNone;
  settle_keep_active_ = settle_keep_next_ = 0;
  settle_drop_ok_ = true;
  settle_phase_ = SettlePhase::kSeed;
}

void SoilFlow::settle_wall_rows(const GridSpec& spec, const Segment& from, const Segment& to, bool band,
                                int* row_lo, int* row_hi) const {
  // The blade's wall: a cell inside the blade, or behind it within its span
  // (on the side the edge came from, as spill_round_ends has it), is not
  // part of the pile's surface; nor is a cell under a body. Per row of the
  // window, the columns [row_lo, row_hi) the blade walls off: the centres
  // within its span (0 <= t <= 1) and on its side of the line n > -half
  // (or n < half, by the side it came from; with no side known, all of
  // them) form one interval.
  const double ex = to.b.x - to.a.x, ez = to.b.z - to.a.z;
  const double len2 = ex * ex + ez * ez;
  const double len = std::sqrt(len2);
  const double half = len > 0.0 ? 0.5 * (std::abs(ez) * dx_ + std::abs(ex) * dz_) / len : 0.0;
  const PlanMotion motion = midpoint_motion(from, to);
  const double across = len > 0.0 ? (ex * motion.z - ez * motion.x) / len : 0.0;
  const double behind = std::abs(across) > kMotionCells * std::max(dx_, dz_) ? -across : 0.0;
  const double ox = spec.origin_m.x - to.a.x;
  // The wall's reach across the line on the side ahead: the band's half
  // width, or (without the band) none: the cells the edge has passed.
  const double reach = band ? half : 0.0;
  for (int lr = 0; lr < settle_wh_; ++lr) {
    int& lo_c = row_lo[lr];
    int& hi_c = row_hi[lr];
    lo_c = hi_c = 0;
    if (!(len2 > 0.0) || (!band && behind == 0.0)) continue;
    const double z = spec.origin_m.z + (settle_wr0_ + lr + 0.5) * dz_ - to.a.z;
    double lo = -std::numeric_limits<double>::infinity(), hi = -lo;
    bool empty = false;
    // a x + b >= 0 (x: a centre's X relative to the edge's first end)
    const auto keep = [&](double a, double b) {
      if (a > 0.0) lo = std::max(lo, -b / a);
      else if (a < 0.0) hi = std::min(hi, -b / a);
      else if (b < 0.0) empty = true;
    };
    keep(ex, z * ez);          // t >= 0
    keep(-ex, len2 - z * ez);  // t <= 1
    // With no side known (a stroke's first hundredth of a cell, or a blade
    // sliding along its line), the whole span: the band alone is about a
    // cell wide across the line, a diagonal pair can stand on its two
    // sides, and the settle, which walls cells and does not test pairs,
    // moved soil through the blade (a 2 m blade on 1 cm cells sliding
    // along its line at yaw 45 degrees, on a dug trench: 3.0 cm behind
    // it). The passes, which test each pair's crossing of the line, settle
    // what lies in the span then.
    if (behind > 0.0) keep(-ez, ex * z + reach * len);  // n > -reach
    if (behind < 0.0) keep(ez, reach * len - ex * z);   // n < reach
    if (empty || lo > hi) continue;
    // Columns whose centre ox + (c + 0.5) dx lies in [lo, hi].
    const double c_lo = std::ceil((lo - ox) / dx_ - 0.5), c_hi = std::floor((hi - ox) / dx_ - 0.5);
    lo_c = int(std::clamp(c_lo - settle_wc0_, 0.0, double(settle_ww_)));
    hi_c = int(std::clamp(c_hi + 1.0 - settle_wc0_, 0.0, double(settle_ww_)));
  }
}

void SoilFlow::settle_follow(const GridSpec& spec, const Segment& from, const Segment& to) {
  if (settle_phase_ == SettlePhase::kIdle) return;
  settle_from_ = from;
  settle_to_ = to;
  // (A wobbling blade whose part backed up over the trench came forward
  // again across cells a settle started in between had taken for the
  // pile's; the settle, written steps later, stood the pile on them, behind
  // the blade: 21 cm behind a 2 m blade on 5 x 2.5 mm cells, wobbling 1.9
  // degrees while it turned.)
  // Only the cells the edge has passed: a push moves the band a fraction of
  // a cell a step, and excluding every cell the band entered broke the
  // settles of every push (the 1.5 m blade's capped pile over 3 m at 1 m/s
  // on 5 mm cells went from +5.5 % to +13.5 % of the converged one); a cell
  // in the band ahead of the line holds the pile against the blade, and
  // the cut takes it as the edge passes.
  int* lo = settle_follow_lo_.data();
  int* hi = settle_follow_hi_.data();
  settle_wall_rows(spec, from, to, false, lo, hi);
  // Per row, the passed columns less those walled when the settle started:
  // the parts of [lo, hi) before and after [was_lo, was_hi).
  for (int lr = 0; lr < settle_wh_; ++lr) {
    const int was_lo = settle_row_lo_[std::size_t(lr)], was_hi = settle_row_hi_[std::size_t(lr)];
    const int r = settle_wr0_ + lr;
    settle_exclude(Rect{settle_wc0_ + lo[lr], r, settle_wc0_ + std::min(hi[lr], was_lo), r + 1});
    settle_exclude(Rect{settle_wc0_ + std::max(lo[lr], was_hi), r, settle_wc0_ + hi[lr], r + 1});
  }
}

std::int64_t SoilFlow::settle_finish(HeightGrid& grid, Rect& changed, std::int64_t budget, std::int64_t work) {
  settle_phase_ = SettlePhase::kIdle;
  // The fans' seams (each fan lowered by its own amount): settled again,
  // one patch lowering as a whole, from what the first round wrote and
  // walled off what another writer changed since it began (a step's
  // displacement: taken into a patch that lowers as a whole, it went round
  // the blade's ends, as the first round's did before it had fans; docs/soil.md,
  // "The settle follows the fall lines").
  if (params_.settle == SoilSettle::kFans && settle_round_ == 0 && !settle_written_.empty()) {
    settle_fresh_.clear();
    const WindowSplit split(settle_ww_);
    for (const std::uint32_t l : settle_excluded_) {
      int lr, lc;
      split(std::int32_t(l), lr, lc);
      settle_fresh_.push_back(std::uint32_t(std::int64_t(settle_wr0_ + lr) * cols_ + settle_wc0_ + lc));
    }
    settle_start(grid, settle_from_, settle_to_, settle_written_, 1);
  }
  if (settle_phase_ != SettlePhase::kIdle) {
    const auto mark = [this](const std::vector<std::uint32_t>& cells, std::uint8_t bit) {
      for (const std::uint32_t cell : cells) {
        const int lc = col_of(cell) - settle_wc0_, lr = row_of(cell) - settle_wr0_;
        if (lc >= 0 && lr >= 0 && lc < settle_ww_ && lr < settle_wh_)
          settle_done_[std::size_t(lr) * std::size_t(settle_ww_) + std::size_t(lc)] |= bit;
      }
    };
    mark(settle_wrote_, kSettleWrote);
    mark(settle_fresh_, kSettleFresh);
    if (work < budget) work += settle_continue(grid, changed, budget - work);
    return work;
  }
  if (settle_again_) {
    // The next one, over what the steps since displaced.
    settle_again_ = false;
    settle_start(grid, settle_next_from_, settle_next_to_, settle_next_rect_);
    if (settle_phase_ != SettlePhase::kIdle && work < budget) work += settle_continue(grid, changed, budget - work);
  }
  return work;
}

std::int64_t SoilFlow::settle_continue(HeightGrid& grid, Rect& changed, std::int64_t budget) {
  if (settle_phase_ == SettlePhase::kIdle) return 0;
  const int wc0 = settle_wc0_, wr0 = settle_wr0_, ww = settle_ww_, wh = settle_wh_;
  const WindowSplit split(ww);
  float* h = grid.edit_layers().height_m;
  float* low = settle_low_.data();
  float* high = settle_high_.data();
  std::uint8_t* done = settle_done_.data();
  constexpr std::uint8_t kLowDone = 1, kHighDone = 2, kListed = 4;
  const int* row_lo = settle_row_lo_.data();
  const int* row_hi = settle_row_hi_.data();
  std::int64_t work = 0;
  // The second round (the seams): only what the first wrote seeds it, and
  // what another writer changed since the first began is walled off.
  const bool second = settle_round_ > 0;
  const bool fans_on = params_.settle == SoilSettle::kFans;
  const auto walled = [&](int lc, int lr) {
    return (lc >= row_lo[lr] && lc < row_hi[lr]) || obstacle_[std::int64_t(wr0 + lr) * cols_ + wc0 + lc] != 0 ||
           (second && (done[std::size_t(lr) * std::size_t(ww) + std::size_t(lc)] & kSettleFresh));
  };
  const auto inner = [&](int lc, int lr) { return lc > 0 && lr > 0 && lc < ww - 1 && lr < wh - 1; };
  std::int32_t offset[8];
  for (int k = 0; k < 8; ++k) offset[k] = kNeighbours[k].dr * ww + kNeighbours[k].dc;
  std::vector<std::int32_t>& touched = settle_cells_;
  const auto list = [&](std::int32_t l) {
    if (!(done[l] & kListed)) {
      done[l] |= kListed;
      touched.push_back(l);
    }
  };
  // The lanes k (bits) where sign ((a - b_k) - limit_k) > tol, b_k the 8
  // neighbours of window cell l in `v` (steep_now's test and order).
  const auto steep_from = [&](const float* v, std::int32_t l, float a, float tol, float sign) -> unsigned {
#if defined(__SSE2__)
    __m128 n0, n1;
    load_neighbours(v + l, ww, n0, n1);
    const __m128 va = _mm_set1_ps(a), vs = _mm_set1_ps(sign);
    const __m128 e0 = _mm_sub_ps(_mm_mul_ps(vs, _mm_sub_ps(va, n0)), _mm_loadu_ps(limit8_));
    const __m128 e1 = _mm_sub_ps(_mm_mul_ps(vs, _mm_sub_ps(va, n1)), _mm_loadu_ps(limit8_ + 4));
    return above_mask(e0, e1, tol);
#else
    unsigned m = 0;
    for (int k = 0; k < 8; ++k) m |= unsigned(sign * (a - v[l + offset[k]]) - limit8_[k] > tol) << k;
    return m;
#endif
  };
  std::vector<std::pair<float, std::int32_t>>& low_seeds = settle_seeds_[0];
  std::vector<std::pair<float, std::int32_t>>& high_seeds = settle_seeds_[1];

  // 1. The steep pairs: from each cell the passes would examine (those the
  // displacement and the spill left too steep, and any carried over), each
  // neighbour it stands above by more than the pair's limit and the
  // tolerance. Its low end seeds the low surface, its high end the high
  // one. A cell with no such neighbour would shed nothing in a pass: it
  // leaves the lists (the passes would drop it after the same test; a
  // change that makes it steep again queues it again). Without that, a
  // backlog the waiting passes left in the lists was tested again by every
  // settle after, which then took longer, and on a long push the settles
  // took every step's budget (docs/soil.md, "Long pushes"). (While a settle
  // is under way the passes wait, so the lists only grow at their end, and
  // settle_q_ stays valid across steps.)
  if (settle_phase_ == SettlePhase::kSeed) {
    const std::size_t from_active = active_.size() - examined_;
    const std::size_t total = from_active + next_.size();
    for (; settle_q_ < total && work + kSettleCellVisits <= budget; ++settle_q_) {
      const bool in_active = settle_q_ < from_active;
      const std::uint32_t a = in_active ? active_[examined_ + settle_q_] : next_[settle_q_ - from_active];
      const int lc = col_of(a) - wc0, lr = row_of(a) - wr0;
      if (lc < 0 || lr < 0 || lc >= ww || lr >= wh || !inner(lc, lr) || walled(lc, lr) ||
          (second && !(done[std::size_t(lr) * std::size_t(ww) + std::size_t(lc)] & kSettleWrote))) {
        settle_keep(a, in_active);
        continue;
      }
      work += kSettleCellVisits;
      const std::int32_t la = lr * ww + lc;
      const unsigned steep_mask = steep_from(low, la, low[la], tolerance_m_, 1.0f);
      if (steep_mask == 0 && settle_drop_ok_) {
        if (!in_active) clear_flag(a, kQueued);
        continue;
      }
      settle_keep(a, in_active);
      for (unsigned steep = steep_mask; steep != 0; steep &= steep - 1) {
        const int k = std::countr_zero(steep);
        if (walled(lc + kNeighbours[k].dc, lr + kNeighbours[k].dr) || low_seeds.size() == low_seeds.capacity())
          continue;
        const std::int32_t lb = la + offset[k];
        list(la);
        list(lb);
        low_seeds.push_back({low[lb], lb});
        high_seeds.push_back({-low[la], la});
      }
    }
    if (settle_q_ < total) return work;
    settle_compact_rest();
    if (low_seeds.empty()) return settle_finish(grid, changed, budget, work);
    settle_phase_ = SettlePhase::kLow;
    settle_b_ = settle_used_ = 0;
    settle_entries_.clear();
  }

  // 2, 3. The largest surface under the pile that meets every pair's limit
  // (low: min over cells y of h(y) + the limits along the stencil path to
  // y) and the least over it (high: max of h(y) less them), each found from
  // its seeds by Dijkstra with the limits as lengths. Its queue is buckets
  // of keys one axis limit wide (Dinitz): a step adds at least that, so the
  // cells of the lowest bucket are final in any order. Each bucket is a
  // list threaded through settle_entries_. The window's border cells take
  // values but do not pass them on; what passes the scratch is dropped
  // (low <= h <= high still holds, so the construction below keeps the
  // volume; the passes do the rest).
  const double width = std::min(limit_[0], limit_[1]);
  // Whether source a lies nearer to window cell m than source b (in metres);
  // of two as near, the one less far across X from it, then the one with
  // the lower row: an order that a mirror image across a line along Z
  // keeps (the one left is a source and its mirror image, equally near).
  // (m: at row mr, column mc of the window.)
  const auto nearer = [&](std::int32_t a, std::int32_t b, int mr, int mc) {
    int ar, ac, br, bc;
    split(a, ar, ac);
    split(b, br, bc);
    const double ax = double(ac - mc) * dx_, az = double(ar - mr) * dz_;
    const double bx = double(bc - mc) * dx_, bz = double(br - mr) * dz_;
    const double da = ax * ax + az * az, db = bx * bx + bz * bz;
    if (da != db) return da < db;
    if (std::abs(ac - mc) != std::abs(bc - mc)) return std::abs(ac - mc) < std::abs(bc - mc);
    return ar < br;
  };
  const auto spread = [&](std::vector<std::pair<float, std::int32_t>>& seeds, float* value, float sign,
                          std::uint8_t done_bit, std::int32_t* root) -> bool {
    std::vector<std::pair<std::int32_t, std::int32_t>>& entries = settle_entries_;  // (cell, next)
    const auto put = [&](float key, std::int32_t l, std::size_t at_least) {
      const std::size_t b =
          std::max(std::size_t(std::max(0.0, (double(key) - double(settle_kmin_)) / width)), at_least);
      if (b >= settle_heads_.size() || entries.size() == entries.capacity()) return;
      entries.push_back({l, settle_heads_[b]});
      settle_heads_[b] = std::int32_t(entries.size() - 1);
      settle_used_ = std::max(settle_used_, b + 1);
    };
    if (!seeds.empty()) {  // the spread's start
      settle_kmin_ = std::numeric_limits<float>::infinity();
      for (const auto& e : seeds) settle_kmin_ = std::min(settle_kmin_, e.first);
      for (const auto& e : seeds) {
        put(e.first, e.second, 0);
        if (fans_on) root[e.second] = e.second;
      }
      seeds.clear();
    }
    float cand[8];
    for (; settle_b_ < settle_used_; ++settle_b_) {
      const std::size_t b = settle_b_;
      while (settle_heads_[b] >= 0) {
        if (work + kSettleCellVisits > budget) return false;
        const auto [l, next] = entries[std::size_t(settle_heads_[b])];
        settle_heads_[b] = next;
        if (done[l] & done_bit) continue;
        done[l] |= done_bit;
        int lr, lc;
        split(l, lr, lc);
        if (!inner(lc, lr)) continue;
        work += kSettleCellVisits;
        // The neighbours this cell's value plus (less) the pair's limit
        // lowers (raises): those standing more than the limit above (below)
        // it, the steep test with no tolerance.
        const float v = value[l];
        unsigned better = steep_from(value, l, v, 0.0f, -sign);
        // A neighbour this cell's value reaches exactly, as another's did
        // (a tie, |value - cand| <= kSettleTie_m): its source is the one
        // nearer to it, so that the fans (below) do not depend on the order
        // of a bucket's cells (which would make a pile that is its own
        // mirror image settle as though it were not).
        unsigned ties = 0;
#if defined(__SSE2__)
        {
          const __m128 vv = _mm_set1_ps(v), vs = _mm_set1_ps(sign);
          const __m128 c0 = _mm_add_ps(vv, _mm_mul_ps(vs, _mm_loadu_ps(limit8_)));
          const __m128 c1 = _mm_add_ps(vv, _mm_mul_ps(vs, _mm_loadu_ps(limit8_ + 4)));
          _mm_storeu_ps(cand, c0);
          _mm_storeu_ps(cand + 4, c1);
          if (fans_on) {
            __m128 n0, n1;
            load_neighbours(value + l, ww, n0, n1);
            const __m128 magnitude = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff)), vt = _mm_set1_ps(kSettleTie_m);
            ties = unsigned(_mm_movemask_ps(_mm_cmple_ps(_mm_and_ps(_mm_sub_ps(n0, c0), magnitude), vt))) |
                   unsigned(_mm_movemask_ps(_mm_cmple_ps(_mm_and_ps(_mm_sub_ps(n1, c1), magnitude), vt))) << 4;
          }
        }
#else
        for (int k = 0; k < 8; ++k) {
          cand[k] = v + sign * limit8_[k];
          ties |= unsigned(fans_on && std::abs(value[l + offset[k]] - cand[k]) <= kSettleTie_m) << k;
        }
#endif
        for (; ties != 0; ties &= ties - 1) {
          const int k = std::countr_zero(ties);
          const std::int32_t m = l + offset[k];
          if (root[m] < 0 || root[m] == root[l]) continue;
          if (nearer(root[l], root[m], lr + kNeighbours[k].dr, lc + kNeighbours[k].dc)) root[m] = root[l];
        }
        if (better == 0) continue;
        for (; better != 0; better &= better - 1) {
          const int k = std::countr_zero(better);
          const std::int32_t m = l + offset[k];
          if (!(sign * cand[k] < sign * value[m]) || walled(lc + kNeighbours[k].dc, lr + kNeighbours[k].dr)) continue;
          // (within a tie of the value it had: the nearer source, as above)
          if (fans_on && (!(sign * (value[m] - cand[k]) <= kSettleTie_m) || root[m] < 0 ||
                          nearer(root[l], root[m], lr + kNeighbours[k].dr, lc + kNeighbours[k].dc)))
            root[m] = root[l];
          value[m] = cand[k];
          list(m);
          put(sign * cand[k], m, b + 1);
        }
      }
    }
    entries.clear();
    settle_b_ = settle_used_ = 0;
    return true;
  };
  if (settle_phase_ == SettlePhase::kLow) {
    if (!spread(low_seeds, low, 1.0f, kLowDone, settle_root_low_.data())) return work;
    settle_phase_ = SettlePhase::kHigh;
  }
  if (settle_phase_ == SettlePhase::kHigh) {
    if (!spread(high_seeds, high, -1.0f, kHighDone, settle_root_high_.data())) return work;
    settle_phase_ = SettlePhase::kPatches;
    settle_q_ = 0;
  }

  // 4. Each 8-connected patch of cells where the two differ settles on its
  // own: its excess over the low surface is put back as the high one
  // lowered by one amount, max(low, high - delta), which keeps the patch's
  // volume and, both surfaces meeting every limit, meets them too. A patch
  // is searched over as many calls as it needs (kPatchSearchVisits a cell),
  // then balanced in one call (kPatchSolveVisits a cell) and written in one
  // call (kPatchWriteVisits a cell), both in the same one when it has room:
  // a pushed pile's face, one patch of tens of thousands of cells, keeps
  // its volume as a whole. (Cut where a call's budget ran out, each piece
  // kept its own, and the middle of the face could not pass its share
  // along the ridge to the ends: docs/soil.md, "A patch is found across
  // steps".) A cell another writer changes meanwhile (kSettleExcluded)
  // leaves the patch: it is not balanced, and if one leaves between the
  // balance and the write the patch is balanced again; after
  // kPatchBalances balances in all it is left to the passes unwritten.
  // A patch is cut at half the cap; a call without the room to balance or
  // write the patch under way leaves it to the next (while the blade
  // pushes, the spill round the ends can leave a step too little for a
  // large patch; the settle, and the passes behind it, then wait for a
  // step with the room, at the latest the first after the blade stops).
  std::vector<std::int32_t>& patch = settle_patch_;
  std::vector<float>& widths = settle_widths_;
  const std::int64_t cap = params_.max_pair_checks_per_step;
  const std::size_t most_cells =
      std::size_t(std::max<std::int64_t>(1, cap / (2 * std::max(kPatchSolveVisits, kPatchWriteVisits))));
  const auto open = [&](std::int32_t l) {
    return !(done[l] & (kSettleInPatch | kSettleExcluded)) && high[l] > low[l];
  };
  // A cell's fan: the seed its high surface came from (where its soil
  // comes from) if the spread raised it; else, if the low one lowered it,
  // the fan of the seed its low surface came from (where its soil goes);
  // else its own. (A seed of the high surface that nothing raised goes
  // with where its soil goes: alone, with no room in its fan, it kept its
  // soil, a column 0.16 m above its neighbours against a body. settle_start
  // clears what the last settle's spreads set; a cell the high spread
  // raised came from another.)
  const std::int32_t* from_low = settle_root_low_.data();
  const std::int32_t* from_high = settle_root_high_.data();
  // (A cell the spreads changed by no more than kFanMarginOfTolerance
  // tolerances takes no part in the fans: whether a pair just past the
  // passes' threshold seeds them differs in the last bits of float sums, and
  // it moved whole fans from one side of a pile to its mirror image.)
  const float margin = float(kFanMarginOfTolerance) * tolerance_m_;
  const auto height_at = [&](std::int32_t l) {
    int lr, lc;
    split(l, lr, lc);
    return h[std::int64_t(wr0 + lr) * cols_ + wc0 + lc];
  };
  const auto raised = [&](std::int32_t l) {
    return from_high[l] >= 0 && from_high[l] != l && high[l] - height_at(l) > margin;
  };
  // (hl: the cell's height.)
  const auto fan_at = [&](std::int32_t l, float hl) -> std::int32_t {
    if (!fans_on || second) return 0;  // one patch lowering as a whole (patches; the fans' seams)
    if (from_high[l] >= 0 && from_high[l] != l && high[l] - hl > margin) return from_high[l];
    const std::int32_t r = from_low[l];
    if (r < 0 || r == l || !(hl - low[l] > margin)) return l;
    return raised(r) ? from_high[r] : r;
  };
  // Whether this call can still pay per_cell visits for each cell of the
  // patch under way.
  const auto room_for = [&](std::int64_t per_cell) {
    return per_cell * std::int64_t(patch.size()) <= budget - work;
  };
  // The patch under way given up, unwritten: the next one.
  const auto drop_patch = [&] {
    for (const std::int32_t l : patch) done[l] &= std::uint8_t(~kSettleCurrent);
    settle_patch_stage_ = PatchStage::kNone;
    ++settle_q_;
  };
  double gained = 0.0;
  // The last cell written, and the last with a millimetre of room under the
  // ceiling (the rounding is given back there when the last has none).
  std::int64_t last = -1, last_with_room = -1;
  for (;;) {
    if (settle_patch_stage_ == PatchStage::kNone) {
      while (settle_q_ < touched.size() && !open(touched[settle_q_])) ++settle_q_;
      if (settle_q_ == touched.size() || work + kPatchSearchVisits > budget) break;
      const std::int32_t l0 = touched[settle_q_];
      patch.clear();
      patch.push_back(l0);
      done[l0] |= kSettleInPatch | kSettleCurrent;
      work += kPatchSearchVisits;
      settle_patch_next_ = 0;
      settle_patch_balances_ = 0;
      settle_patch_stage_ = PatchStage::kSearch;
    }
    if (settle_patch_stage_ == PatchStage::kSearch) {
      // Breadth first from the first cell; a cell's neighbours are paid for
      // as they join (a cell whose expansion the budget stopped is expanded
      // again in the next call, its joined neighbours already marked).
      bool paid_out = false, cut = false;
      for (; settle_patch_next_ < patch.size() && !paid_out && !cut; ++settle_patch_next_) {
        const std::int32_t l = patch[settle_patch_next_];
        int lr, lc;
        split(l, lr, lc);
        for (int k = 0; k < 8; ++k) {
          const int mc = lc + kNeighbours[k].dc, mr = lr + kNeighbours[k].dr;
          if (mc < 0 || mr < 0 || mc >= ww || mr >= wh) continue;
          const std::int32_t m = l + offset[k];
          if (!open(m)) continue;
          if (patch.size() >= most_cells) {
            cut = true;
            break;
          }
          if (work + kPatchSearchVisits > budget) {
            paid_out = true;
            break;
          }
          done[m] |= kSettleInPatch | kSettleCurrent;
          patch.push_back(m);
          work += kPatchSearchVisits;
        }
      }
      if (paid_out) {
        --settle_patch_next_;
        break;
      }
      settle_patch_stage_ = PatchStage::kSolve;
    }
    if (settle_patch_stage_ == PatchStage::kWrite && settle_patch_left_ != settle_balanced_at_) {
      if (settle_patch_balances_ < kPatchBalances) {
        settle_patch_stage_ = PatchStage::kSolve;  // balanced again, without the cells that left
      } else {
        drop_patch();  // its cells keep changing under it: left to the passes
        continue;
      }
    }
    if (settle_patch_stage_ == PatchStage::kSolve) {
      if (!room_for(kPatchSolveVisits)) break;
      work += kPatchSolveVisits * std::int64_t(patch.size());
      // Each fan's excess and room (its widths less its excess), by slot
      // (fan_slot: a fan's slot in the patch, by the fan's id; cell_fan: a
      // patch cell's slot, -1 if it left).
      std::vector<FanBalance>& fans = settle_fans_;
      std::int32_t* fan_slot = settle_fan_slot_.data();
      std::vector<std::int32_t>& cell_fan = settle_cell_fan_;
      std::int32_t* cell_slot = settle_cell_slot_.data();
      fans.clear();
      cell_fan.clear();
      double excess = 0.0, sum_widths = 0.0;
      // (The stuck fans' union below runs only over the fans' first round:
      // the patches and the seams balance a patch as one fan.)
      const bool union_fans = fans_on && !second;
      for (const std::int32_t l : patch) {
        if (done[l] & kSettleExcluded) {
          cell_fan.push_back(-1);
          continue;
        }
        int lr, lc;
        split(l, lr, lc);
        const float hl = h[std::int64_t(wr0 + lr) * cols_ + wc0 + lc];
        const std::int32_t f = fan_at(l, hl);
        if (fan_slot[f] < 0) {
          fan_slot[f] = std::int32_t(fans.size());
          fans.push_back({f, std::int32_t(fans.size()), std::int32_t(fans.size())});
        }
        FanBalance& b = fans[std::size_t(fan_slot[f])];
        const double e = double(hl) - double(low[l]);
        const double w = double(high[l] - low[l]);
        b.excess += e;
        b.room += w - e;
        excess += e;
        sum_widths += w;
        cell_fan.push_back(fan_slot[f]);
        if (union_fans) cell_slot[l] = fan_slot[f];
      }
      // A fan with less room than soil to put in it (its fall lines taken
      // by its neighbours', or blocked: soil pushed against a body) shares
      // its neighbours' room: it joins every fan it borders.
      const auto find = [&](std::int32_t a) {
        while (fans[std::size_t(a)].parent != a) {
          FanBalance& b = fans[std::size_t(a)];
          b.parent = fans[std::size_t(b.parent)].parent;  // (halving the path)
          a = b.parent;
        }
        return a;
      };
      for (std::size_t j = 0; j < patch.size() && union_fans; ++j) {
        const std::int32_t a = cell_fan[j];
        if (a < 0 || !(fans[std::size_t(a)].room < kStuckRoomOfExcess * fans[std::size_t(a)].excess)) continue;
        const std::int32_t l = patch[j];
        int lr, lc;
        split(l, lr, lc);
        // (A group's root is its least slot, so after a union ra is the
        // lesser of the two; a neighbour in the fan just joined is skipped.
        // The cell's root found once, not at every neighbour: the same
        // unions, a tenth less of a row crossing's balance.)
        std::int32_t ra = -1, joined = -1;
        for (int k = 0; k < 8; ++k) {
          const int mc = lc + kNeighbours[k].dc, mr = lr + kNeighbours[k].dr;
          if (mc < 0 || mr < 0 || mc >= ww || mr >= wh) continue;
          const std::int32_t m = l + offset[k];
          if (!(done[m] & kSettleCurrent) || (done[m] & kSettleExcluded)) continue;
          const std::int32_t bm = cell_slot[m];
          if (bm < 0 || bm == a || bm == joined) continue;
          joined = bm;
          if (ra < 0) ra = find(a);
          const std::int32_t rb = find(bm);
          if (ra != rb) {
            fans[std::size_t(std::max(ra, rb))].parent = std::min(ra, rb);
            ra = std::min(ra, rb);
          }
        }
      }
      if (union_fans)
        for (const std::int32_t l : patch) cell_slot[l] = -1;
      // Each joined group's cells' widths side by side in `widths`, from its
      // root's start; the group's excess and count on its root.
      for (FanBalance& b : fans) {
        fan_slot[b.id] = -1;
        b.group_excess = 0.0;
        b.cells = 0;
      }
      for (std::size_t j = 0; j < patch.size(); ++j) {
        if (cell_fan[j] < 0) continue;
        FanBalance& r = fans[std::size_t(find(cell_fan[j]))];
        ++r.cells;
      }
      std::size_t at = 0;
      for (FanBalance& b : fans) {
        if (b.parent != b.slot) continue;
        b.start = at;
        at += b.cells;
        b.cells = 0;
      }
      for (FanBalance& b : fans) fans[std::size_t(find(b.slot))].group_excess += b.excess;
      widths.resize(at);
      for (std::size_t j = 0; j < patch.size(); ++j) {
        if (cell_fan[j] < 0) continue;
        FanBalance& r = fans[std::size_t(find(cell_fan[j]))];
        widths[r.start + r.cells++] = high[patch[j]] - low[patch[j]];
        cell_fan[j] = r.slot;
      }
      // A height some writer changed without a word (outside low..high)
      // would make the balance put soil where none was: left to the passes.
      if (!(excess >= 0.0 && excess <= sum_widths)) {
        drop_patch();
        continue;
      }
      for (FanBalance& b : fans)
        if (b.parent == b.slot)
          b.delta = level_below(std::span<float>(widths.data() + b.start, b.cells), std::max(b.group_excess, 0.0));
      settle_balanced_at_ = settle_patch_left_;
      ++settle_patch_balances_;
      settle_patch_stage_ = PatchStage::kWrite;
    }
    if (settle_patch_stage_ == PatchStage::kWrite) {
      if (!room_for(kPatchWriteVisits)) break;
      work += kPatchWriteVisits * std::int64_t(patch.size());
      for (std::size_t j = 0; j < patch.size(); ++j) {
        const std::int32_t l = patch[j];
        done[l] &= std::uint8_t(~kSettleCurrent);
        if (done[l] & kSettleExcluded) continue;
        int lr, lc;
        split(l, lr, lc);
        const std::int64_t i = std::int64_t(wr0 + lr) * cols_ + wc0 + lc;
        const double delta = settle_fans_[std::size_t(settle_cell_fan_[j])].delta;
        const float now = quantized(std::max(double(low[l]), double(high[l]) - delta));
        const float old = h[i];
        // (The second round starts from every cell of the first's patches,
        // written or not: a fan with no room down its fall line, such as
        // soil pushed against a body, keeps its soil, which then goes
        // round along the seams.)
        if (fans_on && !second) {
          settle_written_.include(wc0 + lc, wr0 + lr);
          if (settle_wrote_.size() < settle_wrote_.capacity()) settle_wrote_.push_back(std::uint32_t(i));
        }
        if (now == old) continue;
        gained += double(now) - double(old);
        dirty(std::uint32_t(i));
        h[i] = now;
        last = i;
        if (now <= ceiling_m_ - kGiveBackRoom_m) last_with_room = i;
        candidate(std::uint32_t(i), now < old);
        changed.include(wc0 + lc, wr0 + lr);
      }
      settle_patch_stage_ = PatchStage::kNone;
      ++settle_q_;
    }
  }
  // The quantizing's rounding given back on the last cell written; on one
  // with room where that would rise past the ceiling, which would clamp it
  // away (soil pushed into a pocket stands at the ceiling: 9e-9 m^3 lost in
  // 41 settles of a 1.25 m blade driven through a wall; docs/soil.md, "Soil
  // slides along a body's face").
  if (last >= 0 && gained != 0.0) give_back(h[give_back_cell(h, last, last_with_room, -gained, ceiling_m_)], -gained);
  settle_candidates(h);
  if (settle_q_ == touched.size()) return settle_finish(grid, changed, budget, work);
  return work;
}

}  // namespace terracut
