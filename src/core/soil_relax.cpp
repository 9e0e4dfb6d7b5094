// Soil that flows, the relaxation (soil.hpp, docs/soil.md "Relaxation:
// fall lines"): steep cells' soil slides down their fall lines in Jacobi
// passes, bounded per step by the work cap.
#include "terracut/core/soil.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "soil_internal.hpp"

namespace terracut {

using namespace soil_internal;

std::int64_t SoilFlow::examine(std::uint32_t a, const float* h) {
  // Cell a, if it stands steeper than the repose angle toward some
  // neighbours, lets the soil above the repose line slide down its fall
  // lines (fall_lines): its fluxes, from the heights frozen at the pass's
  // start, are appended to the pass's list.
  // One byte holds the cell's flags (border, near the blade, ...).
  const std::uint8_t flags = queued_[a];
  const float ha = h[a];
  const float tol = tolerance_m_;
  float excess[8];
  // Bit k: neighbour k is lower by more than its limit and the tolerance;
  // bit 8 + k: neighbour k lies beyond the grid's edge. The pairs are
  // tested without a branch each (which of them is steep changes from
  // cell to cell, so a branch per pair is mispredicted often).
  unsigned steep = 0, outside = 0;
  if (!(flags & kEdge)) {
    // Inside the grid: all 8 neighbours exist.
#if defined(__SSE2__)
    // Four pairs to an instruction, in kNeighbours' order, with the same
    // operations as the scalar form below (the same bits).
    __m128 hb0, hb1;
    load_neighbours(h + a, offset_[2], hb0, hb1);
    const __m128 va = _mm_set1_ps(ha);
    const __m128 e0 = _mm_sub_ps(_mm_sub_ps(va, hb0), _mm_loadu_ps(limit8_));
    const __m128 e1 = _mm_sub_ps(_mm_sub_ps(va, hb1), _mm_loadu_ps(limit8_ + 4));
    _mm_storeu_ps(excess, e0);
    _mm_storeu_ps(excess + 4, e1);
    steep = above_mask(e0, e1, tol);
#else
    for (int k = 0; k < 8; ++k) {
      excess[k] = ha - h[std::int64_t(a) + offset_[k]] - limit8_[k];
      steep |= unsigned(excess[k] > tol) << k;
    }
#endif
  } else {
    const int ca = col_of(a), ra = row_of(a);
    for (int k = 0; k < 8; ++k) {
      const int cb = ca + kNeighbours[k].dc, rb = ra + kNeighbours[k].dr;
      if (cb < 0 || rb < 0 || cb >= cols_ || rb >= rows_) {
        // Beyond an open edge lies bare ground (height 0) that takes what
        // slides onto it; a wall takes nothing.
        outside |= 1u << k;
        excess[k] = params_.edge == SoilEdge::kOpen ? ha - limit8_[k] : 0.0f;
      } else {
        excess[k] = ha - h[std::int64_t(a) + offset_[k]] - limit8_[k];
      }
      steep |= unsigned(excess[k] > tol) << k;
    }
  }
  if (steep == 0) return 0;  // most examined cells cannot move
  const bool blade = blade_.present && (flags & kNearBlade);
  // The cell's column and row, for the blade's test only.
  const int ca = blade ? col_of(a) : 0, ra = blade ? row_of(a) : 0;
  const bool obstacles = !obstacles_.empty();
  const bool hull = !hull_cells_.empty();
  int dirs[8];
  int n = 0;
  for (unsigned bits = steep; bits != 0; bits &= bits - 1) {
    const int k = std::countr_zero(bits);
    if (!(outside & (1u << k))) {
      const std::uint32_t b = std::uint32_t(std::int64_t(a) + offset_[k]);
      if (blade || obstacles || hull) {
        const std::uint8_t fb = queued_[b];
        // The blade is a wall between the cells on its two sides, and soil
        // does not flow into the cells it passes through. What it holds up
        // is examined again once it has moved.
        if (blade && (fb & kNearBlade) &&
            blade_blocks(ca, ra, ca + kNeighbours[k].dc, ra + kNeighbours[k].dr, ha)) {
          hold(a);
          continue;
        }
        // Nor into a rigid body's footprint (soil under it may slide out).
        if (obstacles && obstructed(b)) continue;
        // Nor into a cell under the bucket's hull from higher than the hull's
        // underside there (a flux never raises a cell above its source).
        if ((fb & kHull) && ha > hull_under(b)) {
          hold(a);
          continue;
        }
      }
    }
    dirs[n++] = k | int((outside >> k) & 1u) << 8;
  }
  if (n == 0) return 0;
  return fall_lines(a, ha, h, dirs, n);
}

bool SoilFlow::steep_now(std::uint32_t a, const float* h) const {
  const float ha = h[a];
  const float tol = tolerance_m_;
  if (!(queued_[a] & kEdge)) {
    unsigned steep = 0;
#if defined(__SSE2__)
    __m128 hb0, hb1;
    load_neighbours(h + a, offset_[2], hb0, hb1);
    const __m128 va = _mm_set1_ps(ha);
    const __m128 e0 = _mm_sub_ps(_mm_sub_ps(va, hb0), _mm_loadu_ps(limit8_));
    const __m128 e1 = _mm_sub_ps(_mm_sub_ps(va, hb1), _mm_loadu_ps(limit8_ + 4));
    steep = above_mask(e0, e1, tol);
#else
    for (int k = 0; k < 8; ++k) steep |= unsigned(ha - h[std::int64_t(a) + offset_[k]] - limit8_[k] > tol) << k;
#endif
    return steep != 0;
  }
  const int ca = col_of(a), ra = row_of(a);
  for (int k = 0; k < 8; ++k) {
    const int cb = ca + kNeighbours[k].dc, rb = ra + kNeighbours[k].dr;
    float excess;
    if (cb < 0 || rb < 0 || cb >= cols_ || rb >= rows_)
      excess = params_.edge == SoilEdge::kOpen ? ha - limit8_[k] : 0.0f;
    else
      excess = ha - h[std::int64_t(a) + offset_[k]] - limit8_[k];
    if (excess > tol) return true;
  }
  return false;
}

void SoilFlow::settle_candidates(const float* h) {
  for (std::uint32_t cell : candidates_) {
    const bool was_lowered = (queued_[cell] & kCandLowered) != 0;
    clear_flag(cell, CellFlags(kCandidate | kCandLowered));
    if (was_lowered) {
      if (steep_now(cell, h)) activate(cell);
      lowered(cell, h, false);
    } else if (steep_now(cell, h)) {
      activate(cell);
    }
  }
  candidates_.clear();
}

std::int64_t SoilFlow::fall_lines(std::uint32_t a, float ha, const float* h, const int* dirs, int n) {
  // The soil above the repose line through the source slides down its fall
  // lines and comes to rest where the line meets the ground: along each
  // steep direction k the cells from the neighbour on, as long as they
  // stand below the source by more than the repose drop back to it (their
  // reach, height + drop, under the source's height), up to the first that
  // does not, the grid's edge, the blade, the hull's underside or a body.
  // The source comes down to s and every cell of those runs whose reach is
  // below s comes up to s less its drop:
  // one line at the repose slope from the source down each fall line (the
  // 1-D water fill of fill_ahead, from a point). s balances the volume:
  // s = (h_a + sum of the reaches taken) / (1 + their count). The drop per
  // cell is the pair's limit less the tolerance, so the lines it leaves
  // stand a tolerance gentler than the threshold that moves them.
  struct Line {
    std::uint32_t cell[kMaxFallCells];
    float reach[kMaxFallCells];
    int live = 0;  // the cells walked; after a round, the first `live` (compacted) are not humps
  };
  Line lines[8];
  const float tol = tolerance_m_;
  // A fall line from a cell far from the blade may still run into it.
  const bool blade = blade_.present;
  double total = ha;
  int count = 1;
  int walked = 0;  // the cells of all the lines, for the visits of a further round
  bool steep_below = false;
  // The highest reach taken: when it is below s, no cell is a hump and
  // the rounds below have nothing to drop (skipped: the same result).
  float highest_reach = -std::numeric_limits<float>::infinity();
  const bool obstacles = !obstacles_.empty();
  for (int j = 0; j < n; ++j) {
    const int k = dirs[j] & 0xff;
    const float drop = limit8_[k] - 0.25f * tol;
    Line& line = lines[j];
    // The line's length in a local: a store to the cells (unsigned) may
    // alias the struct's int, and kept the length in memory.
    int len = 0;
    if (dirs[j] >> 8) {
      // Beyond an open edge: bare ground at height 0 that takes what comes.
      line.cell[0] = kOutside;
      line.reach[0] = drop;
      len = 1;
      total += drop;
      highest_reach = std::max(highest_reach, drop);
    } else {
      const std::int64_t step = offset_[k];
      std::uint32_t cur = std::uint32_t(std::int64_t(a) + step);
      std::uint8_t fc = queued_[cur];
      for (int m = 1;; ++m) {
        const float reach = h[cur] + drop * float(m);
        if (!(reach < ha)) break;
        // Summed as walked: the same order as a loop over the line after.
        total += reach;
        highest_reach = std::max(highest_reach, reach);
        line.cell[len] = cur;
        line.reach[len++] = reach;
        if (len == kMaxFallCells || (fc & kEdge)) break;
        const std::uint32_t next = std::uint32_t(std::int64_t(cur) + step);
        const std::uint8_t fn = queued_[next];
        // A cell itself steeper than the threshold toward the next sheds
        // in this pass too: the line ends on it (beyond it the frozen
        // heights are not where the soil will rest, and two sources filling
        // the same steep slope at once would flatten it).
        if (m == 1 && h[cur] - h[next] - limit8_[k] > tol) steep_below = true;
        if (obstacles && obstructed(next)) break;
        if ((fn & kHull) && ha > hull_under(next)) break;
        if (blade && (fc & kNearBlade) && (fn & kNearBlade) &&
            blade_blocks(col_of(cur), row_of(cur), col_of(next), row_of(next), ha))
          break;
        cur = next;
        fc = fn;
      }
    }
    fall_visits_ += len;
    line.live = len;
    count += len;
    walked += len;
  }
  // A cell whose reach is at or above s stands above the final line (a
  // hump) and takes nothing; without it s comes lower, until no more drop
  // out (as in fill_ahead). s only comes down as cells drop out, and at
  // least one cell stays (every reach is below h_a). Two or three rounds
  // settle nearly every source; after 1 + kMaxExtraRounds a cell still at
  // or above s gets nothing (its share would not be positive) and the
  // source keeps that soil for a later pass.
  double s = total / count;
  for (int round = double(highest_reach) >= s ? 0 : kMaxExtraRounds + 1; round <= kMaxExtraRounds; ++round) {
    // A further round reads every walked cell again (the work counts them
    // all, humps included, as when humps were marked in place).
    if (round > 0) fall_visits_ += walked;
    // A float r is at or above s exactly when it is at or above the least
    // float at or above s: the test in float, the same answers.
    float at_least = float(s);
    if (double(at_least) < s) at_least = std::nextafter(at_least, std::numeric_limits<float>::infinity());
    bool changed = false;
    float highest_left = -std::numeric_limits<float>::infinity();
    for (int j = 0; j < n; ++j) {
      Line& line = lines[j];
      // Without a branch per cell (which cells are humps is data, and a
      // mispredicted branch cost more than the test): a cell that drops
      // out takes its reach off the total (in the lines' order, as before:
      // subtracting 0 leaves a double as it is), and the cells left are
      // moved up in their order, so later rounds and the fluxes read only
      // them. (Listing the humps and taking them off after the loop, a
      // shorter chain of subtractions, measured slower.)
      int kept = 0;
      for (int m = 0; m < line.live; ++m) {
        const float r = line.reach[m];
        const bool hump = r >= at_least;
        total -= hump ? double(r) : 0.0;
        count -= int(hump);
        changed |= hump;
        line.reach[kept] = r;
        line.cell[kept] = line.cell[m];
        highest_left = hump ? highest_left : std::max(highest_left, r);
        kept += int(!hump);
      }
      line.live = kept;
    }
    s = total / count;
    if (!changed) break;
    // Every cell left below the new s: a further round would drop none and
    // end the rounds. Its visits are counted; it is not run.
    if (round < kMaxExtraRounds && !(double(highest_left) >= s)) {
      fall_visits_ += walked;
      break;
    }
  }
  std::uint32_t fluxes = 0;
  for (int j = 0; j < n; ++j)
    for (int m = 0; m < lines[j].live; ++m) {
      const float give = quantized((steep_below ? 0.5 : 1.0) * (s - double(lines[j].reach[m])));
      if (!(give > 0.0f)) continue;
      fluxes_.push_back({lines[j].cell[m], give});
      ++fluxes;
    }
  if (fluxes == 0) return 0;
  sources_.push_back({a, fluxes, 1.0f});
  return fluxes;
}

std::int64_t SoilFlow::drop_blocked_fluxes(std::uint32_t a, std::size_t end, const float* h) {
  const std::uint8_t fa = queued_[a];
  const bool blade = blade_.present && (fa & kNearBlade);
  if (!blade && hull_cells_.empty() && obstacles_.empty()) return 0;
  std::int64_t dropped = 0;
  const int ca = col_of(a), ra = row_of(a);
  for (std::size_t j = applied_; j < end; ++j) {
    Flux& f = fluxes_[j];
    if (f.to == kOutside) continue;
    const std::uint8_t fb = queued_[f.to];
    const bool across = blade && (fb & kNearBlade) && blade_blocks(ca, ra, col_of(f.to), row_of(f.to), h[a]);
    const bool into_hull = (fb & kHull) && h[a] > hull_under(f.to);
    if (across || into_hull) hold(a);
    if ((across || into_hull || (!obstacles_.empty() && obstructed(f.to))) && f.excess != 0.0f) {
      f.excess = 0.0f;
      ++dropped;
    }
  }
  return dropped;
}

void SoilFlow::finish_pass(HeightGrid& grid, SoilStepResult& out) {
  // The fluxes cancel exactly; the float heights do not quite: what the
  // pass gained or lost by rounding was measured in double and is given
  // back to the highest cell it changed, so no bias builds up over a run.
  // When cells tie for highest (a mirror image would pick another of
  // them), they share it, so a mirrored terrain gives it to the mirrored
  // cells; more than kMaxTiedHighest, it waits for a later pass.
  const HeightGrid::EditLayers layers = grid.edit_layers();
  // The highest sources once the pass is applied (their final heights do
  // not depend on the order they were applied in).
  for (std::size_t j = 0; j < applied_sources_; ++j) {
    const std::uint32_t a = sources_[j].cell;
    const float now = layers.height_m[a];
    if (now > pass_highest_h_) {
      pass_highest_h_ = now;
      pass_highest_[0] = a;
      pass_highest_count_ = 1;
    } else if (now == pass_highest_h_ && a != pass_highest_[0]) {
      if (pass_highest_count_ < kMaxTiedHighest) pass_highest_[pass_highest_count_] = a;
      ++pass_highest_count_;
    }
  }
  if (pass_gained_m_ != 0.0 && pass_highest_h_ > 0.0f && pass_highest_count_ <= kMaxTiedHighest) {
    // Shared equally by the cells tied for highest (the same set, mirrored,
    // in a mirror image), in whole quanta (what is left under one waits for
    // a later pass), never below the floor nor above the ceiling.
    const double share = -pass_gained_m_ / pass_highest_count_;
    for (int j = 0; j < pass_highest_count_; ++j) {
      float& hh = layers.height_m[pass_highest_[j]];
      const float old = hh;
      hh = std::min(quantized(std::max(0.0, double(hh) + share)), std::max(ceiling_m_, old));
      pass_gained_m_ += double(hh) - double(old);
    }
  }
  pass_highest_h_ = -1.0f;
  pass_highest_count_ = 0;
  for (std::uint32_t cell : dirty_) clear_flag(cell, kDirty);
  dirty_.clear();
  active_.clear();
  fluxes_.clear();
  sources_.clear();
  examined_ = applied_ = applied_sources_ = 0;
  ++out.passes;
}

void SoilFlow::run_passes(HeightGrid& grid, SoilStepResult& out) {
  const HeightGrid::EditLayers layers = grid.edit_layers();
  float* h = layers.height_m;
  const double cell_area = dx_ * dz_;
  // The work of the step, in neighbour visits: 8 per cell examined, 1 per
  // flux applied and 8 per source's fall test (its neighbours read again),
  // so that a step's work tracks its time whether it examines or applies.
  // It never passes the cap: a pass too large for what is left is carried on
  // in the next step, where it stopped (its heights stay those it started
  // from until all its cells are examined), so a collapse of any size is
  // spread over ticks of bounded work.
  // With a tool in the soil the next step displaces soil again, and the
  // fluxes of a pass carried over would be dropped wherever it did (they
  // came from heights those cells no longer have). So there the cap splits
  // the pass instead: examination stops while the work left leaves room to
  // apply every flux found, those are applied in this step, and the cells
  // not examined wait for the next pass (a smaller Jacobi pass, not the
  // same bits as the whole one). No pass with fluxes then spans steps. A
  // cap under kLeastSplitCap would spend too much of itself on that room
  // and carries the pass over as without a tool.
  // (The cap less what the step's displacement took: after_cut.)
  const std::int64_t cap = step_cap_;
  const bool hull = !hull_cells_.empty();
  const bool split_at_cap = (blade_.present || hull) && params_.max_pair_checks_per_step >= kLeastSplitCap;
  // What the spill round the blade's ends and the settle spent this step counts too.
  std::int64_t work = ends_work_;
  ends_work_ = 0;
  // A pass left over from an earlier step was examined against the blade,
  // hull and bodies of that step.
  pass_spans_steps_ = !active_.empty();
  // The rectangle of the cells that shed soil; the cells they shed to are
  // their neighbours, so the changed rectangle is that plus a cell.
  int changed_c0 = cols_, changed_c1 = -1, changed_r0 = rows_, changed_r1 = -1;
  bool out_of_work = false;
  while (!out_of_work) {
    if (active_.empty()) {
      // The next pass starts from the cells queued for it.
      if (next_.empty()) break;
      active_.swap(next_);
      for (std::uint32_t a : active_) clear_flag(a, kQueued);
      pass_spans_steps_ = false;
    }
    if (examined_ < active_.size()) {
      // 8 visits per cell examined and one per cell of the fall lines it
      // walks (fall_visits_), cell by cell while the cap leaves room for one
      // more examination and a full fall line each way.
      std::int64_t moved = 0;
      // A pass whose fluxes would outgrow their list is split: the cells
      // not examined yet go on to the next pass (a pass that large is a
      // collapse of most of a reserved active set, or a grid's worth).
      // Splitting at the cap, the room kept is what applying the fluxes
      // found so far and those of one more examination would cost.
      auto room = [&] {
        const std::int64_t to_apply = split_at_cap ? std::int64_t(fluxes_.size() - applied_) +
                                                         kFallTestVisits * std::int64_t(sources_.size() - applied_sources_) +
                                                         kMostExamineFluxVisits
                                                   : 0;
        return work + to_apply + kMostExamineVisits <= cap;
      };
      while (examined_ < active_.size() && room() && fluxes_.size() + 8 * kMaxFallCells <= fluxes_.capacity()) {
        fall_visits_ = 0;
        moved += examine(active_[examined_++], h);
        work += 8 + fall_visits_;
      }
      out.moved_pairs += moved;
      if (examined_ < active_.size()) {
        const bool fits = room();
        if (examined_ > 0 && (fits || split_at_cap)) {
          // Split: the rest of the list is examined in the next pass.
          if (!fits) out.reached_cap = true;
          for (std::size_t j = examined_; j < active_.size(); ++j) activate(active_[j]);
          active_.truncate(examined_);
        } else {
          out.reached_cap = true;
          break;  // the rest in the next step
        }
      }
    }
    while (applied_sources_ < sources_.size()) {
      // A source's fluxes are contiguous: applied together, then its fall
      // tested against its neighbours.
      const std::uint32_t a = sources_[applied_sources_].cell;
      const std::size_t end = applied_ + sources_[applied_sources_].fluxes;
      const float share = sources_[applied_sources_].share;
      // No cell is dirty while dirty_ is empty (most passes: the cut marks
      // cells only in a pass it interrupts), and then nothing is read for it.
      const bool any_dirty = !dirty_.empty();
      const bool stale = any_dirty && (queued_[a] & kDirty) != 0;
      const std::int64_t cost = std::int64_t(end - applied_) + (stale ? 0 : kFallTestVisits);
      if (work + cost > cap) {
        out_of_work = true;
        out.reached_cap = true;
        break;
      }
      work += cost;
      if (stale) {
        out.stale_fluxes += std::int64_t(end - applied_);
        applied_ = end;  // changed since it was examined: examined again
        ++applied_sources_;
        continue;
      }
      // A pass examined in an earlier step met the blade, the hull and the
      // bodies where they were then; they have moved since. A flux that
      // would now cross the blade, climb into the hull or enter a body is
      // dropped (its source is held, and examined again).
      if (pass_spans_steps_) out.stale_fluxes += drop_blocked_fluxes(a, end, h);
      // Multiples of the quantum, summed exactly in double: the order of the
      // source's fall lines (which a mirror image permutes) does not matter.
      double total_d = 0.0;
      for (std::size_t j = applied_; j < end; ++j)
        if (!any_dirty || fluxes_[j].to == kOutside || !(queued_[fluxes_[j].to] & kDirty))
          total_d += double(share * fluxes_[j].excess);
      const float total = float(total_d);
      // What the cell can give: never below the floor (the blade may have
      // cut it since the pass was examined).
      const float before = h[a];
      const float scale = total > before ? before / total : 1.0f;
      const float now = total > before ? 0.0f : quantized(double(before) - total_d);
      h[a] = now;
      // The grid's change in double: float rounding is what it gains.
      double gained = double(now) - double(before);
      // What a cell under the hull could not take (below) stays with the source.
      double kept = 0.0;
      const int ca = col_of(a), ra = row_of(a);
      changed_c0 = std::min(changed_c0, ca);
      changed_c1 = std::max(changed_c1, ca);
      changed_r0 = std::min(changed_r0, ra);
      changed_r1 = std::max(changed_r1, ra);
      for (; applied_ < end; ++applied_) {
        const Flux& f = fluxes_[applied_];
        if (any_dirty && f.to != kOutside && (queued_[f.to] & kDirty)) {
          ++out.stale_fluxes;
          continue;
        }
        const float give = (share * f.excess) * scale;
        if (f.to == kOutside) {
          out.left_over_edge_m3 += double(give) * cell_area;
          gained += double(give);  // what left is no rounding gain
          continue;
        }
        // Multiples of the quantum added to a multiple of it: exact, so a
        // cell's sum does not depend on the order its sources were met in.
        const float old = h[f.to];
        float raised = quantized(double(old) + double(give));
        // Each source's fall line ends below its own height, so one source
        // never raises a cell under the hull above its underside; several
        // filling the same cell in one pass could (a cell at the end of the
        // back wall, between piles, rose 20 cm in a step, 10 cm above it).
        // The sources met after the cell is full keep the rest.
        if (hull && (queued_[f.to] & kHull) && raised > hull_under(f.to)) {
          float room = std::max(old, quantized(double(hull_under(f.to))));
          if (room > hull_under(f.to) && room > old) room = std::max(old, quantized(double(room) - quantum_m_));
          raised = room;
          kept += double(give) - (double(raised) - double(old));
        }
        // Nor above the ceiling (the rigid bodies' heightfield's bound, which
        // deletes what stands above it): the source keeps the rest.
        if (raised > ceiling_m_ && raised > old) {
          float room = std::max(old, quantized(double(ceiling_m_)));
          if (room > ceiling_m_ && room > old) room = std::max(old, quantized(double(room) - quantum_m_));
          kept += double(raised) - double(room);
          raised = room;
        }
        h[f.to] = raised;
        gained += double(raised) - double(old);
        activate(f.to);
        const int ct = col_of(f.to), rt = row_of(f.to);
        changed_c0 = std::min(changed_c0, ct);
        changed_c1 = std::max(changed_c1, ct);
        changed_r0 = std::min(changed_r0, rt);
        changed_r1 = std::max(changed_r1, rt);
      }
      if (kept > 0.0) {
        // The source keeps it, and is examined again (held, next pass,
        // while the hull stands over the cells it would fill).
        const float back = quantized(double(h[a]) + kept);
        gained += double(back) - double(h[a]);
        h[a] = back;
        activate(a);
      }
      pass_gained_m_ += gained;
      ++applied_sources_;
      lowered(a, h);
    }
    if (applied_sources_ < sources_.size()) break;
    finish_pass(grid, out);
  }
  out.pair_checks += work;
  if (changed_c1 >= 0) {
    out.changed.include(std::max(changed_c0 - 1, 0), std::max(changed_r0 - 1, 0));
    out.changed.include(std::min(changed_c1 + 1, cols_ - 1), std::min(changed_r1 + 1, rows_ - 1));
  }
  out.backlog_cells = active_cells();
}

SoilStepResult SoilFlow::relax(HeightGrid& grid) {
  SoilStepResult out;
  wake_held(nullptr);  // no blade now
  clear_hull();        // nor a bucket
  step_cap_ = params_.max_pair_checks_per_step;  // (no displacement)
  out.relax_budget = step_cap_;
  if (settle_phase_ != SettlePhase::kIdle) {
    // A settle under way goes on first; the passes wait for it.
    out.settle_visits = settle_charged(grid, out.changed, step_cap_);
    if (settle_phase_ != SettlePhase::kIdle) {
      out.pair_checks = ends_work_;
      ends_work_ = 0;
      out.reached_cap = true;
      out.backlog_cells = active_cells();
      rest_steps_ = rest_run_after(rest_steps_, out.reached_cap);
      return out;
    }
  }
  run_passes(grid, out);
  rest_steps_ = rest_run_after(rest_steps_, out.reached_cap);
  return out;
}

}  // namespace terracut
