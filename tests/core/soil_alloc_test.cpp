// The soil phase allocates nothing on the heap once built, even when every
// cell of the grid is queued: every global operator new in this test
// program is counted.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <numbers>
#include <vector>

#include "terracut/core/soil.hpp"

#include "../support/counting_new.hpp"

namespace terracut {
namespace {

TEST(SoilAllocation, ARampSteepEverywhereRelaxesWithoutAllocating) {
  // A 60-degree ramp: every cell starts active, so the lists fill to the
  // whole grid (reserved for exactly that on a small grid); the passes
  // queue cells already queued on every step.
  for (const int n : {8, 16, 32}) {
    const double cell = 0.01;
    std::vector<float> h(std::size_t(n) * n);
    for (int r = 0; r < n; ++r)
      for (int c = 0; c < n; ++c)
        h[std::size_t(r) * n + c] = float(0.5 + std::tan(60.0 * std::numbers::pi / 180.0) * (c + 0.5) * cell);
    HeightGrid grid(grid_of_cells(n, n, cell), h);
    SoilFlowParams p;
    p.model = SoilModel::kFlow;
    p.material.repose_deg = 34.0;
    p.max_pair_checks_per_step = 2000;  // passes spread over steps
    SoilFlow flow(p, grid);
    ASSERT_EQ(flow.active_cells(), std::int64_t(n) * n);
    const long before = g_allocations.load();
    int steps = 0;
    for (; steps < 100000 && flow.active_cells() > 0; ++steps) flow.relax(grid);
    EXPECT_EQ(g_allocations.load() - before, 0) << n << " x " << n;
    EXPECT_EQ(flow.active_cells(), 0) << "settled in " << steps << " steps";
  }
}

TEST(CellList, KeepsOnlyWhatItIsToldAndGrowsOnlyWhenAKeptCellFillsIt) {
  detail::CellList list;
  list.reserve(4);
  const std::size_t capacity = list.capacity();
  EXPECT_GE(capacity, 4u);
  for (std::uint32_t i = 0; i < capacity; ++i) list.push_if(i, true);
  const long before = g_allocations.load();
  // Full: cells not kept are written to the spare slot and dropped.
  for (std::uint32_t i = 0; i < 100; ++i) list.push_if(1000 + i, false);
  EXPECT_EQ(g_allocations.load() - before, 0);
  ASSERT_EQ(list.size(), capacity);
  for (std::uint32_t i = 0; i < capacity; ++i) EXPECT_EQ(list[i], i);
  // One more kept: it grows, and keeps what it held.
  list.push_if(77, true);
  EXPECT_EQ(list.size(), capacity + 1);
  EXPECT_GT(list.capacity(), capacity);
  EXPECT_EQ(list[capacity], 77u);
  for (std::uint32_t i = 0; i < capacity; ++i) EXPECT_EQ(list[i], i);
  // swap and clear.
  detail::CellList other;
  other.push_back(5);
  list.swap(other);
  ASSERT_EQ(list.size(), 1u);
  EXPECT_EQ(list[0], 5u);
  EXPECT_EQ(other.size(), capacity + 1);
  other.clear();
  EXPECT_TRUE(other.empty());
  EXPECT_EQ(std::vector<std::uint32_t>(list.begin(), list.end()), std::vector<std::uint32_t>{5});
}

}  // namespace
}  // namespace terracut
