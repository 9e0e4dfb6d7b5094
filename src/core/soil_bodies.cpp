// Soil that flows, rigid bodies (soil.hpp): their footprints as obstacles
// the soil does not enter (where soil pushed against one goes round it:
// soil_displace.cpp).
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

}  // namespace terracut
