// Soil that flows, the blade's ends (soil.hpp, docs/soil.md "The spill round
// the blade's ends"): what stands above the repose cone through an end of
// the blade slides round it, down to what lies below the cone, in one
// construction per step rather than hundreds of relaxation passes.
#include "terracut/core/soil.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>

#include "soil_internal.hpp"

namespace terracut {

using namespace soil_internal;

namespace {

/// The root t of sum over donors of (a - t)+ = sum over receivers of
/// (t - b)+: the soil above the upper cone through t against the room under
/// the lower one. The function is continuous and decreasing in t, linear
/// between the keys. `keys` holds (key, +1 for a donor's a, -1 for a
/// receiver's b) and is sorted here; walking down from the highest key, each
/// donor's key passed starts counting and each receiver's stops.
double balance(std::vector<std::pair<double, int>>& keys) {
  std::sort(keys.begin(), keys.end());
  double sum_a = 0.0, sum_b = 0.0;
  std::int64_t n_a = 0, n_b = 0;
  for (const auto& [key, kind] : keys)
    if (kind < 0) sum_b += key, ++n_b;
  for (std::size_t i = keys.size(); i-- > 0;) {
    // f at this key, with the donors above it and the receivers below it
    // (one at the key adds nothing): at or above 0, the root lies between
    // this key and the one above, on the line through f's piece there.
    const double t = keys[i].first;
    const double f = (sum_a - double(n_a) * t) - (double(n_b) * t - sum_b);
    if (f >= 0.0) {
      const double count = double(n_a + n_b);
      return count > 0.0 ? (sum_a + sum_b) / count : t;
    }
    if (keys[i].second > 0) {
      sum_a += t;
      ++n_a;
    } else {
      sum_b -= t;
      --n_b;
    }
  }
  const double count = double(n_a + n_b);
  return count > 0.0 ? (sum_a + sum_b) / count : (keys.empty() ? 0.0 : keys.front().first);
}

}  // namespace

void SoilFlow::spill_round_ends(HeightGrid& grid, const Segment& from, const Segment& to, SoilStepResult& out) {
  const GridSpec& spec = grid.spec();
  const double ex = to.b.x - to.a.x, ez = to.b.z - to.a.z;
  const double len2 = ex * ex + ez * ez;
  if (!(len2 > 0.0)) return;
  const double len = std::sqrt(len2);
  // Half a cell's width across the edge's line: a centre closer than that
  // is inside the blade (as blade_blocks has it).
  const double half = 0.5 * (std::abs(ez) * dx_ + std::abs(ex) * dz_) / len;
  // The side the edge came from, by the sign of the motion across its line
  // (from motion_origin, so a blade at rest keeps the side it came from;
  // none when it moved along the line, or less than kMotionCells of a cell
  // since its stroke began): the cells inside the
  // blade on that side are behind it, cut, and take what comes round the
  // ends as the trench behind them does. Those ahead hold the pile against
  // the blade and take nothing here.
  const PlanMotion motion = midpoint_motion(from, to);
  const double across = (ex * motion.z - ez * motion.x) / len;
  const double behind = std::abs(across) > kMotionCells * std::max(dx_, dz_) ? -across : 0.0;
  const double slope = std::tan(params_.material.repose_deg * std::numbers::pi / 180.0);
  const double diag = std::hypot(dx_, dz_);
  float* h = grid.edit_layers().height_m;
  constexpr int radius = kEndWindowCells;
  constexpr int side = 2 * radius + 1;
  // A cell's place: off, or its side of the edge's line, with kInside when
  // the edge passes through it (behind the blade: a receiver only).
  constexpr std::uint8_t kUnknown = 0, kOff = 1, kPlus = 2, kMinus = 3, kSide = 3, kInside = 4;
  constexpr std::uint8_t kDonor = 1, kReceiver = 2;
  // Cell (c, r)'s centre relative to the edge's first end, in plan.
  const auto centre = [&](int c, int r) {
    return std::pair{spec.origin_m.x + (c + 0.5) * dx_ - to.a.x, spec.origin_m.z + (r + 0.5) * dz_ - to.a.z};
  };
  // (The window's scratch is sized at construction, and its states are all
  // 0 between calls: a 1 kHz tick allocates nothing and clears only the
  // cells it marked.)
  for (int end = 0; end < 2; ++end) {
    // The apex: the first cell past this end of the edge (its centre beyond
    // the edge's span, outside the blade), through which every path round
    // the end passes. Distances are counted from its centre along the
    // 8-neighbour stencil's octagonal norm, so a cone in them stands at the
    // repose limit of every pair of neighbours and no steeper, and a cell on
    // one side and one on the other stand no further apart than their
    // stencil path round the end allows. No such cell (the end at the
    // grid's edge, in a body): no way round.
    const Vec3& tip = end == 0 ? to.a : to.b;
    const double out_x = (end == 0 ? -ex : ex) / len, out_z = (end == 0 ? -ez : ez) / len;
    int apex_c = -1, apex_r = -1;
    for (double reach = 0.5; reach <= 2.0 && apex_c < 0; reach += 0.5) {
      const double step = reach * std::min(dx_, dz_);
      const double px = tip.x + out_x * step, pz = tip.z + out_z * step;
      const int c = floor_within(to_cells(px, spec.origin_m.x, dx_), -1, cols_);
      const int r = floor_within(to_cells(pz, spec.origin_m.z, dz_), -1, rows_);
      if (c < 0 || r < 0 || c >= cols_ || r >= rows_) break;
      const auto [cx, cz] = centre(c, r);
      const double t = (cx * ex + cz * ez) / len2;
      if (end == 0 ? t < 0.0 : t > 1.0) apex_c = c, apex_r = r;
    }
    if (apex_c < 0) continue;
    const int wc0 = apex_c - radius, wr0 = apex_r - radius;
    std::fill(ends_place_.begin(), ends_place_.end(), kUnknown);
    // Where window cell w lies, found once a call: off (beyond the grid,
    // under a body, inside the blade ahead of it, or nearer the other end)
    // or on one side of the edge's line; and its distance to the apex.
    const auto place = [&](int w) -> std::uint8_t {
      std::uint8_t& p = ends_place_[std::size_t(w)];
      if (p != kUnknown) return p;
      const int c = wc0 + w % side, r = wr0 + w / side;
      p = kOff;
      if (c < 0 || r < 0 || c >= cols_ || r >= rows_ || obstacle_[std::int64_t(r) * cols_ + c] != 0) return p;
      const auto [x, z] = centre(c, r);
      const double t = (x * ex + z * ez) / len2;
      if (end == 0 ? !(t < 0.5) : !(t > 0.5)) return p;
      const double n = (ex * z - ez * x) / len;
      const bool inside = std::abs(n) < half && t >= 0.0 && t <= 1.0;
      // A centre on the line itself is the row the edge cuts now: behind.
      if (inside && !(behind != 0.0 && n * behind >= 0.0)) return p;
      const int uc = std::abs(w % side - radius), ur = std::abs(w / side - radius);
      ends_dist_[std::size_t(w)] =
          float(uc >= ur ? (uc - ur) * dx_ + ur * diag : (ur - uc) * dz_ + uc * diag);
      p = inside ? std::uint8_t((behind > 0.0 ? kPlus : kMinus) | kInside) : n > 0.0 ? kPlus : kMinus;
      return p;
    };
    // Whether the edge stands between two neighbouring cells in the window
    // (their centres on its two sides, the crossing within its span).
    const auto blocked = [&](int v, int w) {
      if ((place(v) & kSide) == (place(w) & kSide)) return false;
      const auto [xa, za] = centre(wc0 + v % side, wr0 + v / side);
      const auto [xb, zb] = centre(wc0 + w % side, wr0 + w / side);
      const double na = ex * za - ez * xa, nb = ex * zb - ez * xb;
      const double u = na / (na - nb);
      const double t = ((xa + (xb - xa) * u) * ex + (za + (zb - za) * u) * ez) / len2;
      return t >= 0.0 && t <= 1.0;
    };
    // The seeds: the apex and its neighbours that soil can reach from it;
    // the upper cone's height s lies between their heights less and more
    // their cone's drop.
    const int apex = radius * side + radius;
    if (place(apex) == kOff) continue;
    std::int32_t seeds[9];
    int n_seeds = 0;
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (int dr = -1; dr <= 1; ++dr)
      for (int dc = -1; dc <= 1; ++dc) {
        const int w = apex + dr * side + dc;
        if (place(w) == kOff || (w != apex && blocked(apex, w))) continue;
        seeds[n_seeds++] = w;
        const double hw = h[std::int64_t(wr0 + w / side) * cols_ + wc0 + w % side], d = ends_dist_[std::size_t(w)];
        lo = std::min(lo, hw + slope * d);
        hi = std::max(hi, hw - slope * d);
      }
    // A cell within the relaxation's tolerance of its cone passes soil on
    // (the passes would not move it, nor stop what comes through it): the
    // donors are those above the upper cone through s - tol, the
    // receivers those below the lower one through s + tol. (Held to the
    // cones themselves, the cells of the cone an earlier call built stood
    // on it to rounding and parted the seeds from the sets beyond them: at
    // a slant, where the apex moves on every step, the spill found an end
    // at rest, or its sets jumped between two heights and the last round's
    // could not balance (404 donors and no receiver), and the passes
    // carried the soil round the ends instead, about 150 passes a step;
    // docs/soil.md, "The spill round the ends at a slant, again".)
    const double tol = tolerance_m_;
    if (!(hi > lo - 2.0 * tol)) continue;  // the end stands at rest
    // Rounds: the donors (above the upper cone through s, s + slope d) and
    // the receivers (below the lower one, s - slope d), each connected to
    // the seeds through its own kind; then s balancing what they give and
    // take. The sets are found again for the new s until it settles.
    std::vector<std::pair<double, int>>& keys = ends_keys_;
    std::vector<std::int32_t>& queue = ends_queue_;
    // The search starts where this end's cone stood at the last call (the
    // tip moves a cell or less between calls), else halfway.
    double s = ends_s_[end] > lo && ends_s_[end] < hi ? ends_s_[end] : 0.5 * (lo + hi);
    // Only the cells of a round's sets carry a state: they are cleared.
    const auto clear_sets = [&] {
      for (const std::int32_t w : queue) ends_state_[std::size_t(w)] = 0;
      queue.clear();
    };
    // The root's bracket: a round whose sets balance above the s they were
    // found at puts the root above that s, one that balances below it,
    // below (the soil above the upper cone less the room under the lower
    // one falls as s rises, and the sets only grow the way that makes it
    // fall faster).
    double below = -std::numeric_limits<double>::infinity(), above = -below;
    // The heights the round's donors and receivers are found for: s, less
    // and more the tolerance; in the last round, the bracket's ends.
    double s_donor = 0.0, s_receiver = 0.0;
    bool last_round = false;
    for (int round = 0; round < kEndRounds || last_round; ++round) {
      if (!last_round) s_donor = s - tol, s_receiver = s + tol;
      clear_sets();
      keys.clear();
      // The round's visits (8 a cell of the sets: its neighbours) stay
      // within what the work cap leaves: past it the sets stop growing (the
      // balance over them still keeps the volume; the passes do the rest).
      const std::int64_t room = params_.max_pair_checks_per_step - ends_work_;
      // (kinds: the sets w may join, those of the cell it is reached from;
      // it joins each it belongs to. Both only where its two cones lie
      // closer than the two heights differ: the apex within the tolerance
      // of s, and in the last round the cells near it.)
      const auto admit = [&](int w, std::uint8_t kinds) {
        if (std::int64_t(queue.size() + 1) * 8 > room) return;
        const double hw = h[std::int64_t(wr0 + w / side) * cols_ + wc0 + w % side];
        const double d = ends_dist_[std::size_t(w)];
        std::uint8_t kind = 0;
        // (a donor inside the blade: held against it)
        if ((kinds & kDonor) && !(place(w) & kInside) && hw - slope * d > s_donor) kind |= kDonor;
        if ((kinds & kReceiver) && hw + slope * d < s_receiver) kind |= kReceiver;
        if (kind == 0) return;
        ends_state_[std::size_t(w)] = kind;
        if (kind & kDonor) keys.push_back({hw - slope * d, 1});
        if (kind & kReceiver) keys.push_back({hw + slope * d, -1});
        queue.push_back(w);
      };
      for (int q = 0; q < n_seeds; ++q) admit(seeds[q], kDonor | kReceiver);
      for (std::size_t q = 0; q < queue.size(); ++q) {
        const int w = queue[q];
        const std::uint8_t kind = ends_state_[std::size_t(w)];
        const int lc = w % side, lr = w / side;
        for (const Neighbour& nb : kNeighbours) {
          const int mc = lc + nb.dc, mr = lr + nb.dr;
          if (mc < 0 || mr < 0 || mc >= side || mr >= side) continue;
          const int v = mr * side + mc;
          if (ends_state_[std::size_t(v)] != 0 || place(v) == kOff || blocked(w, v)) continue;
          admit(v, kind);
        }
      }
      ends_work_ += std::int64_t(queue.size()) * 8;
      const double next = balance(keys);
      // Settled once the height moves by less than a twentieth of the
      // relaxation's tolerance (the cells it would still add or drop at the
      // sets' borders are that close to their cone: the passes see them).
      // A balance that goes back out of the bracket means the sets change
      // by a whole region between two heights (a cell at its cone's height
      // joins it to the seeds, or parts it from them), and further rounds
      // would only go back and forth between the two (they once went on to
      // kEndRounds: at 30 degrees, a 1 m blade on 5 mm cells spent 41 M of
      // its push's 50 M visits in the spill's rounds). Then one round more
      // finds the donors at the bracket's lower height and the receivers at
      // its upper one and balances them together: each cell's give and
      // take is continuous in s, so that balance has a root. A cell in both
      // (near the apex, where the two cones lie closer than the bracket is
      // wide) ends between its two cones: it passes soil through. (Ended at
      // the last round's own sets, the spill at a slant kept one with
      // donors and no receiver, and moved nothing.) The last round's sets
      // at its balance keep the volume either way; the passes do the rest.
      if (last_round) {
        s = next;
        break;
      }
      const bool back = !(next > below && next < above);
      if (next > s) below = s;
      else above = s;
      const bool settled = std::abs(next - s) <= 0.05 * tolerance_m_;
      s = next;
      if (ends_work_ + 8 * std::int64_t(queue.size()) > params_.max_pair_checks_per_step) break;
      if (back) {
        last_round = true;
        s_donor = below - tol;
        s_receiver = above + tol;
        continue;
      }
      if (settled) break;
    }
    ends_s_[end] = s;
    // The last round's sets at its balance: each donor comes down to the
    // upper cone, each receiver up to the lower one (quantized; the
    // rounding given back to the last cell written).
    // A receiver the ceiling holds under its cone takes less than the
    // balance gave it; the donors keep that much, each at most what it would
    // give, in the sets' order. (Given back on the last cell written, at the
    // ceiling itself, the ceiling's clamp deleted it: up to 3.6e-5 m^3 in a
    // push of a 1.33 m blade on 5 mm cells under a ceiling 0.1 m above a
    // 0.2 m layer; docs/soil.md, "Soil slides along a body's face".)
    double held = 0.0;
    for (const std::int32_t w : queue) {
      if (!std::isfinite(ceiling_m_)) break;  // (no ceiling: every run without bodies)
      if (ends_state_[std::size_t(w)] == kDonor) continue;
      const std::int64_t i = std::int64_t(wr0 + w / side) * cols_ + wc0 + w % side;
      const double want = quantized(s - slope * double(ends_dist_[std::size_t(w)]));
      if (want > double(h[i]) && want > double(ceiling_m_)) held += want - std::max(double(h[i]), double(ceiling_m_));
    }
    double gained = 0.0;
    std::int64_t last = -1;
    for (const std::int32_t w : queue) {
      const int c = wc0 + w % side, r = wr0 + w / side;
      const std::int64_t i = std::int64_t(r) * cols_ + c;
      const double d = ends_dist_[std::size_t(w)];
      const float old = h[i];
      const std::uint8_t state = ends_state_[std::size_t(w)];
      float now = old;
      if (state & kDonor) now = std::min(now, quantized(std::max(0.0, s + slope * d)));
      if (state & kReceiver) now = std::max(now, std::min(quantized(s - slope * d), ceiling_m_));
      if (held > 0.0 && now < old) {
        const float kept = std::min(old, quantized(double(now) + std::min(held, double(old) - double(now))));
        held -= double(kept) - double(now);
        now = kept;
      }
      if (now == old) continue;
      gained += double(now) - double(old);
      dirty(std::uint32_t(i));
      settle_exclude(i);
      h[i] = now;
      last = i;
      candidate(std::uint32_t(i), now < old);
      out.changed.include(c, r);
    }
    if (last >= 0 && gained != 0.0) give_back(h[last], -gained);
    clear_sets();
  }
  settle_candidates(h);
}

}  // namespace terracut
