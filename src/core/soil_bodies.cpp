// Soil that flows, rigid bodies (soil.hpp): their footprints as obstacles
// the soil does not enter, and where soil pushed against one goes round it.
#include "terracut/core/soil.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "soil_internal.hpp"

namespace terracut {

using namespace soil_internal;

void SoilFlow::set_obstacles(std::span<const SoilObstacle> obstacles) noexcept {
  // Bodies at rest give the same list step after step: nothing to do.
  const auto clipped = [this](const SoilObstacle& o) {
    return SoilObstacle{{std::max(o.cells.c0, 0), std::max(o.cells.r0, 0), std::min(o.cells.c1, cols_),
                         std::min(o.cells.r1, rows_)},
                        o.bottom_m};
  };
  {
    std::size_t k = 0;
    bool same = true;
    for (const SoilObstacle& given : obstacles) {
      if (k == std::size_t(kMaxObstacles)) break;
      const SoilObstacle o = clipped(given);
      if (o.cells.empty() || !(o.bottom_m == o.bottom_m)) continue;
      same = same && k < obstacles_.size() && obstacles_[k].cells == o.cells && obstacles_[k].bottom_m == o.bottom_m;
      ++k;
    }
    if (same && k == obstacles_.size()) return;
  }
  // Clear the old ones; the soil banked against them may now slide on, so
  // the cells along their sides (inside and out) are examined again.
  // A settle under way leaves the cells under the old and the new bodies
  // alone (its walls were found with the old ones).
  for (const SoilObstacle& o : obstacles_) {
    settle_exclude(o.cells);
    for (int r = o.cells.r0; r < o.cells.r1; ++r)
      std::fill_n(obstacle_.begin() + std::int64_t(r) * cols_ + o.cells.c0, o.cells.c1 - o.cells.c0, 0);
    const int c0 = std::max(o.cells.c0 - 1, 0), c1 = std::min(o.cells.c1, cols_ - 1);
    const int r0 = std::max(o.cells.r0 - 1, 0), r1 = std::min(o.cells.r1, rows_ - 1);
    for (int r = r0; r <= r1; ++r)
      for (int c = c0; c <= c1; ++c)
        if (r <= r0 + 1 || r >= r1 - 1 || c <= c0 + 1 || c >= c1 - 1)
          activate(std::uint32_t(std::int64_t(r) * cols_ + c));
  }
  obstacles_.clear();
  for (const SoilObstacle& given : obstacles) {
    if (int(obstacles_.size()) == kMaxObstacles) break;
    const SoilObstacle o = clipped(given);
    if (o.cells.empty() || !(o.bottom_m == o.bottom_m)) continue;  // off the grid, or NaN
    obstacles_.push_back(o);
    settle_exclude(o.cells);
    const auto id = std::uint8_t(obstacles_.size());
    for (int r = o.cells.r0; r < o.cells.r1; ++r)
      for (int c = o.cells.c0; c < o.cells.c1; ++c) {
        std::uint8_t& mark = obstacle_[std::size_t(std::int64_t(r) * cols_ + c)];
        // Where two overlap, the lower underside counts.
        if (mark == 0 || o.bottom_m < obstacles_[mark - 1u].bottom_m) mark = id;
      }
  }
}

void SoilFlow::beside_body(const HeightGrid& grid, double x, double z, double tx, double tz,
                           std::int64_t& first, std::int64_t& second) const {
  // Walk from the point (x, z) both ways along the unit (tx, tz), a cell at
  // a time, to the first sample on each side that no body stands over.
  const GridSpec& spec = grid.spec();
  const double step = std::min(dx_ / std::max(std::abs(tx), 1e-9), dz_ / std::max(std::abs(tz), 1e-9));
  const auto at = [&](double along) -> std::int64_t {
    const double u = to_cells(x + tx * along, spec.origin_m.x, dx_);
    const double v = to_cells(z + tz * along, spec.origin_m.z, dz_);
    if (u < 0.0 || v < 0.0 || u >= cols_ || v >= rows_) return -1;
    return std::int64_t(std::floor(v)) * cols_ + std::int64_t(std::floor(u));
  };
  for (int j = 1; j <= kMaxPushCells; ++j) {
    const std::int64_t a = at(j * step), b = at(-j * step);
    const bool fa = a >= 0 && obstacle_[a] == 0, fb = b >= 0 && obstacle_[b] == 0;
    if (!fa && !fb) {
      if (a < 0 && b < 0) return;  // off the grid both ways: stays where it was
      continue;
    }
    first = fa ? a : b;
    second = fa && fb ? b : -1;
    return;
  }
}

}  // namespace terracut
