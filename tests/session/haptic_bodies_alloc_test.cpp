// The haptic loop with the rigid bodies' listener (Bullet world, bodies.csv and
// the viewer feed) allocates nothing per tick once Bullet is warm: every
// global operator new and every Bullet allocation (btAlignedAlloc,
// redirected here) of this program is counted over the rock session's ticks
// after the plate's first touch (Bullet's contact arrays grow to their
// working size on the first contacts of each kind).
#include <gtest/gtest.h>
#include <unistd.h>

#include <LinearMath/btAlignedAllocator.h>

#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <new>

#include "terracut/haptics/script_device.hpp"
#include "terracut/session/haptic.hpp"

#include "../support/counting_bullet_alloc.hpp"

namespace terracut::session {
namespace {

namespace fs = std::filesystem;

// The rock session with the given soil model: allocations are counted after
// the plate's first touch, to the end.
void expect_no_allocation_once_warm(SoilModel model) {
  ASSERT_TRUE(g_installed);
  Scenario in = load_scenario(fs::path(TERRACUT_SOURCE_DIR) / "scenarios/rock_push.yaml");
  in.base.soil.model = model;
  const fs::path dir = fs::temp_directory_path() / ("terracut_bodies_alloc_" + std::to_string(getpid()));
  fs::create_directories(dir);
  const io::Scenario& sc = in.base;
  const Motion& cut = sc.cuts.at(0);
  const double rate = sc.rate_hz;
  const std::int64_t ticks = std::llround((cut.duration_s() + in.haptics.settle_s) * rate);
  // The plate's first touch: its front face (edge + half the plate's 2 cm)
  // reaches the rock's back face at t = 2.58 s (scenarios/rock_push.yaml).
  const std::int64_t warm = std::llround(2.7 * rate);

  haptics::ScriptDevice device(haptics::DevicePath(cut, haptics::Workspace(in.haptics.workspace)));
  HeightGrid grid(io::grid_spec(sc), io::build_initial_heights(sc));
  haptics::SnapshotExchange exchange(grid);
  haptics::LoopOptions o;
  o.ticks = ticks;
  o.record_capacity = std::size_t(ticks);
  o.realtime = false;
  o.snapshot = &exchange;
  RigOptions ro;
  ro.loop = o;
  ro.bodies_csv = dir / "bodies.csv";
  long during = -1;
  double peak = 0.0;
  const long at_start = g_allocations.load();
  {
    const haptics::LoopParams params(in.haptics, sc.blade, sc.rate_hz);
    HapticRig rig(in, params, cut.keyframes[0].pose.orientation, device, ro);
    haptics::HapticLoop& loop = rig.loop();
    // Until the rock is first pushed (by the plate, or on flowing soil by
    // the pile ahead of it) and at least to the plate's touch.
    std::int64_t i = 0;
    for (; i < ticks && (i < warm || loop.max_body_force_n() <= 0.0); ++i) {
      loop.step1(double(i) / rate);
      loop.step2(i == 0 ? 0.0 : 1.0 / rate, 0.0, false);
    }
    ASSERT_GT(loop.max_body_force_n(), 0.0) << "the rock was never pushed";
    ASSERT_LT(i, ticks - std::int64_t(rate)) << "the rock was first pushed in the last second";
    const long before = g_allocations.load();
    // Building the world and Bullet's first contacts did allocate: the
    // counter sees them.
    EXPECT_GT(before - at_start, 10);
    for (; i < ticks; ++i) {
      loop.step1(double(i) / rate);
      loop.step2(1.0 / rate, 0.0, false);
      exchange.acquire();  // a reader taking frames, as the viewer does
    }
    during = g_allocations.load() - before;
    peak = loop.max_body_force_n();
    rig.world().finish();
  }
  EXPECT_EQ(during, 0) << "allocations in the ticks of pushing the rock and leaving it";
  EXPECT_GT(peak, 0.0);
  fs::remove_all(dir);
}

TEST(BodiesEngineAllocation, TicksAllocateNothingOnceBulletIsWarm) {
  expect_no_allocation_once_warm(SoilModel::kVanish);
}

// Soil that flows, banking against the rock (its obstacle set every step
// by the bodies' listener) and sliding from under it: no allocation either.
TEST(BodiesEngineAllocation, TicksWithFlowingSoilAllocateNothingOnceBulletIsWarm) {
  expect_no_allocation_once_warm(SoilModel::kFlow);
}

}  // namespace
}  // namespace terracut::session
