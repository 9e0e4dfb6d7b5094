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

// On a 4096-wide grid (rows 16 KiB apart) the two layers' samples must not
// share their offset within a page, for small grids and for huge-page ones.
TEST(GridStorage, LayersStartAtDifferentPageOffsets) {
  for (int side : {16, 1024}) {
    HeightGrid g(grid_of_cells(side, side, 1e-3), ramp(side, side));
    std::uintptr_t h = page_offset(g.heights()), i = page_offset(g.initial());
    EXPECT_NE(h, i) << side;
    // Cache-line aligned, so a line holds 16 whole samples of one layer.
    EXPECT_EQ(h % 64, 0u);
    EXPECT_EQ(i % 64, 0u);
    // The layers do not overlap.
    const std::int64_t n = g.spec().sample_count();
    EXPECT_GE(g.initial() - g.heights(), n);
  }
}

TEST(GridStorage, LayersHoldTheirValues) {
  const int cols = 37, rows = 23;
  std::vector<float> h = ramp(cols, rows);
  HeightGrid g(grid_of_cells(cols, rows, 0.01), h);
  for (std::int64_t i = 0; i < g.spec().sample_count(); ++i) {
    ASSERT_EQ(g.heights()[i], h[size_t(i)]);
    ASSERT_EQ(g.initial()[i], h[size_t(i)]);
    ASSERT_EQ(g.removed_at(i), 0.0f);
  }
  g.lower(g.index(5, 7), 0.0f);
  g.reset();
  EXPECT_EQ(g.height(5, 7), h[size_t(g.index(5, 7))]);
  EXPECT_EQ(g.removed_at(g.index(5, 7)), 0.0f);
}

// The removed layer is derived: after a cut and a deposit it is initial -
// height at every sample, the removed height where cut, negative where
// material was put down, zero elsewhere; copy_removed writes the same.
TEST(GridStorage, RemovedIsInitialLessHeight) {
  const int cols = 19, rows = 11;
  std::vector<float> h = ramp(cols, rows);
  HeightGrid g(grid_of_cells(cols, rows, 0.01), h);
  const std::int64_t cut = g.index(4, 3), raised = g.index(9, 8);
  const float cut_to = 0.25f * h[size_t(cut)];
  EXPECT_EQ(g.lower(cut, cut_to), h[size_t(cut)] - cut_to);
  const float up = h[size_t(raised)] + 0.5f;
  g.set_heights(Rect{9, 8, 10, 9}, &up);
  std::vector<float> copy(size_t(g.spec().sample_count()), -1.0f);
  g.copy_removed(copy.data());
  for (std::int64_t i = 0; i < g.spec().sample_count(); ++i) {
    const float expected = i == cut ? h[size_t(i)] - cut_to : i == raised ? h[size_t(i)] - up : 0.0f;
    ASSERT_EQ(g.removed_at(i), expected) << i;
    ASSERT_EQ(copy[size_t(i)], expected) << i;
  }
  EXPECT_GT(g.removed_at(cut), 0.0f);
  EXPECT_LT(g.removed_at(raised), 0.0f);
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
