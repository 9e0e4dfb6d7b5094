// After warm-up a step of the Simulation + TerrainWorld pair allocates
// nothing: every global operator new and every Bullet allocation (Bullet
// allocates through btAlignedAlloc, redirected here) of this program is
// counted.
#include <gtest/gtest.h>

#include <LinearMath/btAlignedAllocator.h>

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <new>
#include <string>

#include <unistd.h>

#include "terracut/bullet/bodies_csv.hpp"
#include "test_scene.hpp"

#include "../support/counting_bullet_alloc.hpp"

namespace terracut::bullet {
namespace {

TEST(WorldAllocation, BulletAllocationsAreCounted) {
  ASSERT_TRUE(g_installed);
  const long before = g_allocations.load();
  void* p = btAlignedAlloc(64, 16);
  EXPECT_EQ(g_allocations.load() - before, 1);
  btAlignedFree(p);
}

TEST(WorldAllocation, StepsAllocateNothingOnceWarm) {
  test::Scene scene;
  const std::filesystem::path csv_path = std::filesystem::temp_directory_path() /
                                         ("terracut_world_alloc_" + std::to_string(getpid()) + ".csv");
  BodiesCsvWriter csv(csv_path);
  // Warm-up: the first contacts grow Bullet's internal arrays (manifolds,
  // solver pools, island lists) to their working size; they are never
  // shrunk. The scene's first 0.2 s has the plate moving in the soil and
  // every body resting on the terrain.
  int i = 0;
  const long at_start = g_allocations.load();
  for (; i < 200; ++i) scene.step(i);
  EXPECT_GT(g_allocations.load() - at_start, 0);  // the warm-up did grow arrays

  // The rest: the soil cut under one body (it falls and lands), the plate
  // lifted, moved and pushing another body, rows of bodies.csv formatted.
  const long before = g_allocations.load();
  for (; i < 3000; ++i) {
    scene.step(i);
    csv.write_step(scene.world);
  }
  EXPECT_EQ(g_allocations.load() - before, 0);
  csv.close();
  EXPECT_EQ(csv.rows_written(), std::int64_t(2800) * scene.world.body_count());
  std::filesystem::remove(csv_path);
  EXPECT_GT(scene.sim.removed_volume_m3(), 0.0);
  EXPECT_LT(scene.world.body_state(0).position_m.y, 0.4 - 0.1);
  EXPECT_GT(scene.world.body_state(1).position_m.x, 0.75);
}

}  // namespace
}  // namespace terracut::bullet
