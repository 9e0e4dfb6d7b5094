// HeightGrid's storage: the layers' placement (staggered within their
// pages, so that a traversal across the rows does not evict its own lines)
// and deep copies.
#include "terracut/core/grid.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <utility>
#include <vector>

namespace terracut {
namespace {

std::vector<float> ramp(int cols, int rows) {
  std::vector<float> h(size_t(cols) * size_t(rows));
  for (size_t i = 0; i < h.size(); ++i) h[i] = 0.001f * float(i % 997);
  return h;
}

std::uintptr_t page_offset(const float* p) { return reinterpret_cast<std::uintptr_t>(p) % 4096; }

// On a 4096-wide grid (rows 16 KiB apart) the three layers' samples must not
// share their offset within a page, for small grids and for huge-page ones.
TEST(GridStorage, LayersStartAtDifferentPageOffsets) {
  for (int side : {16, 1024}) {
    HeightGrid g(grid_of_cells(side, side, 1e-3), ramp(side, side));
    std::uintptr_t h = page_offset(g.heights()), r = page_offset(g.removed()), i = page_offset(g.initial());
    EXPECT_NE(h, r) << side;
    EXPECT_NE(h, i) << side;
    EXPECT_NE(r, i) << side;
    // Cache-line aligned, so a line holds 16 whole samples of one layer.
    EXPECT_EQ(h % 64, 0u);
    EXPECT_EQ(r % 64, 0u);
    EXPECT_EQ(i % 64, 0u);
    // The layers do not overlap.
    const std::int64_t n = g.spec().sample_count();
    EXPECT_GE(g.removed() - g.heights(), n);
    EXPECT_GE(g.initial() - g.removed(), n);
  }
}

TEST(GridStorage, LayersHoldTheirValues) {
  const int cols = 37, rows = 23;
  std::vector<float> h = ramp(cols, rows);
  HeightGrid g(grid_of_cells(cols, rows, 0.01), h);
  for (std::int64_t i = 0; i < g.spec().sample_count(); ++i) {
    ASSERT_EQ(g.heights()[i], h[size_t(i)]);
    ASSERT_EQ(g.initial()[i], h[size_t(i)]);
    ASSERT_EQ(g.removed()[i], 0.0f);
  }
  g.lower(g.index(5, 7), 0.0f);
  g.reset();
  EXPECT_EQ(g.height(5, 7), h[size_t(g.index(5, 7))]);
  EXPECT_EQ(g.removed()[g.index(5, 7)], 0.0f);
}

TEST(GridStorage, CopiesAreDeepAndMovesKeepTheLayers) {
  const int cols = 40, rows = 30;
  HeightGrid a(grid_of_cells(cols, rows, 0.01), ramp(cols, rows));
  a.lower(a.index(3, 4), 0.0f);
  HeightGrid b = a;
  EXPECT_EQ(b.state_hash(), a.state_hash());
  EXPECT_NE(b.heights(), a.heights());
  b.lower(b.index(10, 11), 0.0f);
  EXPECT_NE(b.state_hash(), a.state_hash());
  EXPECT_NE(a.height(10, 11), 0.0f);
  // Assignment over a grid of another size takes the other's size.
  HeightGrid c(grid_of_cells(3, 2, 0.01), ramp(3, 2));
  c = b;
  EXPECT_EQ(c.state_hash(), b.state_hash());
  EXPECT_EQ(c.conservation_error_m(), 0.0);
  const float* layer = c.heights();
  HeightGrid d = std::move(c);
  EXPECT_EQ(d.heights(), layer);  // a move keeps the stable array
  EXPECT_EQ(d.state_hash(), b.state_hash());
}

}  // namespace
}  // namespace terracut
