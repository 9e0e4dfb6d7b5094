// Soil that flows, the blade's ends (soil.hpp, docs/soil.md "The spill round
// the blade's ends"): what stands above the repose cone through an end of
// the blade slides round it, down to what lies below the cone, in one
// construction per step rather than hundreds of relaxation passes.
#include "terracut/core/soil.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "soil_internal.hpp"

namespace terracut {

using namespace soil_internal;

namespace {

/// The root t of sum over donors of (a - t)+ = sum over receivers of
/// (t - b)+ (the soil above the upper cone through t against the room
/// under the lower one): the function is continuous and decreasing in t,
/// piecewise linear between the keys. `keys` holds (key, +1 donor / -1
/// receiver) and is sorted here.
double balance(std::vector<std::pair<double, int>>& keys) {
  std::sort(keys.begin(), keys.end());
  // Above every key: only receivers count (f < 0 unless none). Walk from
  // the top down: f(t) = sumA - nA t - (nB t - sumB) with the donors whose
  // key is above t and the receivers whose key is below it.
  double sum_a = 0.0, sum_b = 0.0;
  std::int64_t n_a = 0, n_b = 0;
  for (const auto& [key, kind] : keys)
    if (kind < 0) sum_b += key, ++n_b;
  // f just above the highest key: donors none.
  for (std::size_t i = keys.size(); i-- > 0;) {
    const double t = keys[i].first;
    // On [keys[i], keys[i+1]) the sets are: donors with key > t, receivers with key < t...
    // f at t with the current sets (donors above, receivers at or below: a
    // receiver whose key is t adds 0).
    const double f = (sum_a - double(n_a) * t) - (double(n_b) * t - sum_b);
    if (f >= 0.0) {
      // The root lies in [t, next key above): solve the linear piece.
      const double slope = double(n_a + n_b);
      return slope > 0.0 ? (sum_a + sum_b) / slope : t;
    }
    // Cross the key downward: a donor starts counting, a receiver stops.
    if (keys[i].second > 0) {
      sum_a += t;
      ++n_a;
    } else {
      sum_b -= t;
      --n_b;
    }
  }
  const double slope = double(n_a + n_b);
  return slope > 0.0 ? (sum_a + sum_b) / slope : (keys.empty() ? 0.0 : keys.front().first);
}

}  // namespace

void SoilFlow::spill_round_ends(HeightGrid& grid, const Segment& to, SoilStepResult& out) {
  const GridSpec& spec = grid.spec();
  const double ex = to.b.x - to.a.x, ez = to.b.z - to.a.z;
  const double len2 = ex * ex + ez * ez;
  if (!(len2 > 0.0)) return;
  const double len = std::sqrt(len2);
  const double half = 0.5 * (std::abs(ez) * dx_ + std::abs(ex) * dz_) / len;
  const double slope = std::tan(params_.material.repose_deg * std::numbers::pi / 180.0);
  const double diag = std::hypot(dx_, dz_);
  const HeightGrid::EditLayers layers = grid.edit_layers();
  float* h = layers.height_m;
  const int radius = kEndWindowCells;
  const int side = 2 * radius + 1;
  for (int end = 0; end < 2; ++end) {
    const Vec3& tip = end == 0 ? to.a : to.b;
    const double tu = to_cells(tip.x, spec.origin_m.x, dx_), tv = to_cells(tip.z, spec.origin_m.z, dz_);
    const int wc0 = int(std::floor(tu)) - radius, wr0 = int(std::floor(tv)) - radius;
    ends_state_.assign(std::size_t(side) * side, 0);
    ends_key_.resize(std::size_t(side) * side);
    // A window cell's place: -1 outside the grid, the blade, a body or the
    // other end's half; else its index.
    const auto cell_of = [&](int lc, int lr, double& d, bool& inside) -> std::int64_t {
      const int c = wc0 + lc, r = wr0 + lr;
      if (lc < 0 || lr < 0 || lc >= side || lr >= side || c < 0 || r < 0 || c >= cols_ || r >= rows_) return -1;
      const std::int64_t i = std::int64_t(r) * cols_ + c;
      if (obstacle_[i] != 0) return -1;
      const double x = spec.origin_m.x + (c + 0.5) * dx_ - to.a.x, z = spec.origin_m.z + (r + 0.5) * dz_ - to.a.z;
      const double t = (x * ex + z * ez) / len2;
      if (end == 0 ? !(t < 0.5) : !(t > 0.5)) return -1;
      const double n = (ex * z - ez * x) / len;
      inside = std::abs(n) < half && t >= 0.0 && t <= 1.0;
      if (inside) return -1;
      // The distance to the tip along the 8-neighbour stencil's octagonal
      // norm (the cone it spans stands at the repose limit of every pair).
      const double ux = std::abs(spec.origin_m.x + (c + 0.5) * dx_ - tip.x) / dx_;
      const double uz = std::abs(spec.origin_m.z + (r + 0.5) * dz_ - tip.z) / dz_;
      d = ux >= uz ? (ux - uz) * dx_ + uz * diag : (uz - ux) * dz_ + ux * diag;
      return i;
    };
    // Whether the pair's centres lie on two sides of the edge within its span.
    const auto crosses = [&](std::int64_t i, std::int64_t j) {
      const double xa = spec.origin_m.x + (double(col_of(std::uint32_t(i))) + 0.5) * dx_ - to.a.x;
      const double za = spec.origin_m.z + (double(row_of(std::uint32_t(i))) + 0.5) * dz_ - to.a.z;
      const double xb = spec.origin_m.x + (double(col_of(std::uint32_t(j))) + 0.5) * dx_ - to.a.x;
      const double zb = spec.origin_m.z + (double(row_of(std::uint32_t(j))) + 0.5) * dz_ - to.a.z;
      const double na = ex * za - ez * xa, nb = ex * zb - ez * xb;
      if ((na > 0.0) == (nb > 0.0)) return false;
      const double w = na / (na - nb);
      const double t = ((xa + (xb - xa) * w) * ex + (za + (zb - za) * w) * ez) / len2;
      return t >= 0.0 && t <= 1.0;
    };
    // Seeds: the cells within a cell and a half of the tip.
    // Donors (kind 1) stand above the upper cone through s, receivers (kind
    // 2) below the lower one, each set connected to the tip through its own.
    double s = 0.0;
    {
      double lo = 1e300, hi = -1e300;
      bool any = false;
      for (int lr = radius - 2; lr <= radius + 2; ++lr)
        for (int lc = radius - 2; lc <= radius + 2; ++lc) {
          double d = 0.0;
          bool inside = false;
          const std::int64_t i = cell_of(lc, lr, d, inside);
          if (i < 0 || d > 1.5 * std::max(dx_, dz_)) continue;
          any = true;
          lo = std::min(lo, double(h[i]) + slope * d);
          hi = std::max(hi, double(h[i]) - slope * d);
        }
      if (!any || !(hi > lo)) continue;  // the tip stands at rest
      s = 0.5 * (lo + hi);
    }
    {
      // Soil goes round the tip only if the cells round it are one piece
      // (a grid's edge or a body at the tip closes the way round).
      std::int32_t seeds[25];
      int n = 0;
      for (int lr = radius - 2; lr <= radius + 2; ++lr)
        for (int lc = radius - 2; lc <= radius + 2; ++lc) {
          double d = 0.0;
          bool inside = false;
          const std::int64_t i = cell_of(lc, lr, d, inside);
          if (i >= 0 && d <= 1.5 * std::max(dx_, dz_)) seeds[n++] = lr * side + lc;
        }
      std::uint32_t reached = 1;  // bit per seed
      for (bool grew = true; grew;) {
        grew = false;
        for (int p = 0; p < n; ++p)
          for (int q = 0; q < n; ++q) {
            if (!(reached >> p & 1u) || (reached >> q & 1u)) continue;
            const int pc = seeds[p] % side, pr = seeds[p] / side, qc = seeds[q] % side, qr = seeds[q] / side;
            if (std::abs(pc - qc) > 1 || std::abs(pr - qr) > 1) continue;
            if (crosses(std::int64_t(wr0 + pr) * cols_ + wc0 + pc, std::int64_t(wr0 + qr) * cols_ + wc0 + qc)) continue;
            reached |= 1u << q;
            grew = true;
          }
      }
      if (reached != (n >= 32 ? ~0u : (1u << n) - 1u)) continue;
    }
    std::vector<std::pair<double, int>>& keys = ends_keys_;
    std::vector<std::int32_t>& queue = ends_queue_;
    double t_root = s;
    int donors = 0, receivers = 0;
    for (int round = 0; round < kEndRounds; ++round) {
      std::fill(ends_state_.begin(), ends_state_.end(), 0);
      queue.clear();
      keys.clear();
      const auto visit = [&](int lc, int lr) {
        const std::int32_t w = lr * side + lc;
        if (lc < 0 || lr < 0 || lc >= side || lr >= side || ends_state_[std::size_t(w)] != 0) return;
        double d = 0.0;
        bool inside = false;
        const std::int64_t i = cell_of(lc, lr, d, inside);
        if (i < 0) {
          ends_state_[std::size_t(w)] = 3;
          return;
        }
        const double a = double(h[i]) - slope * d, b = double(h[i]) + slope * d;
        ends_key_[std::size_t(w)] = float(d);
        if (a > s) {
          ends_state_[std::size_t(w)] = 1;
          keys.push_back({a, 1});
          queue.push_back(w);
        } else if (b < s) {
          ends_state_[std::size_t(w)] = 2;
          keys.push_back({b, -1});
          queue.push_back(w);
        } else {
          ends_state_[std::size_t(w)] = 3;
        }
      };
      for (int lr = radius - 2; lr <= radius + 2; ++lr)
        for (int lc = radius - 2; lc <= radius + 2; ++lc) {
          double d = 0.0;
          bool inside = false;
          const std::int64_t i = cell_of(lc, lr, d, inside);
          if (i < 0 || d > 1.5 * std::max(dx_, dz_)) continue;
          visit(lc, lr);
        }
      for (std::size_t q = 0; q < queue.size(); ++q) {
        const std::int32_t w = queue[q];
        const int lc = w % side, lr = w / side;
        const std::uint8_t kind = ends_state_[std::size_t(w)];
        const std::int64_t i = std::int64_t(wr0 + lr) * cols_ + (wc0 + lc);
        for (const Neighbour& nb : kNeighbours) {
          const int mc = lc + nb.dc, mr = lr + nb.dr;
          if (mc < 0 || mr < 0 || mc >= side || mr >= side) continue;
          const std::int32_t v = mr * side + mc;
          if (ends_state_[std::size_t(v)] != 0 && ends_state_[std::size_t(v)] != 3) continue;
          if (ends_state_[std::size_t(v)] == 3) continue;
          const int c = wc0 + mc, r = wr0 + mr;
          if (c < 0 || r < 0 || c >= cols_ || r >= rows_) continue;
          if (crosses(i, std::int64_t(r) * cols_ + c)) continue;
          double d = 0.0;
          bool inside = false;
          const std::int64_t j = cell_of(mc, mr, d, inside);
          if (j < 0) {
            ends_state_[std::size_t(v)] = 3;
            continue;
          }
          const double a = double(h[j]) - slope * d, b = double(h[j]) + slope * d;
          if (kind == 1 && a > s) {
            ends_state_[std::size_t(v)] = 1;
            ends_key_[std::size_t(v)] = float(d);
            keys.push_back({a, 1});
            queue.push_back(v);
          } else if (kind == 2 && b < s) {
            ends_state_[std::size_t(v)] = 2;
            ends_key_[std::size_t(v)] = float(d);
            keys.push_back({b, -1});
            queue.push_back(v);
          }
        }
      }
      out.pair_checks += std::int64_t(queue.size()) * 8;
      const double next = balance(keys);
      const bool settled = std::abs(next - s) <= quantum_m_;
      t_root = next;
      s = next;
      if (settled) break;
    }
    // Apply with the last round's sets and its root.
    double gained = 0.0;
    std::int64_t last = -1;
    for (const std::int32_t w : queue) {
      const int lc = w % side, lr = w / side;
      const int c = wc0 + lc, r = wr0 + lr;
      const std::int64_t i = std::int64_t(r) * cols_ + c;
      const double d = ends_key_[std::size_t(w)];
      const float old = h[i];
      float now = old;
      if (ends_state_[std::size_t(w)] == 1) {
        const float cap = quantized(std::max(0.0, t_root + slope * d));
        if (cap < old) now = cap, ++donors;
      } else {
        const float fill = std::min(quantized(t_root - slope * d), ceiling_m_);
        if (fill > old) now = fill, ++receivers;
      }
      if (now == old) continue;
      gained += double(now) - double(old);
      dirty(std::uint32_t(i));
      h[i] = now;
      last = i;
      candidate(std::uint32_t(i), now < old);
      out.changed.include(c, r);
    }
    if (last >= 0 && gained != 0.0) give_back(h[last], -gained);
  }
  settle_candidates(h);
}

}  // namespace terracut
