// A loop tick allocates nothing on the heap, whatever the device (script,
// simulated hand, UDP with traffic) and with the viewer feed: every global
// operator new in this test program is counted.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <functional>
#include <new>

#include "haptics_fixture.hpp"
#include "terracut/haptics/loop.hpp"
#include "terracut/haptics/script_device.hpp"
#include "terracut/haptics/sim_hand.hpp"
#include "terracut/haptics/udp_device.hpp"
#include "terracut/io/scenario.hpp"

#include "../support/counting_new.hpp"

namespace terracut::haptics {
namespace {

// Runs the trench's ticks [0, ticks) by hand and counts allocations during
// all but the first (the first tick starts the device).
long allocations_per_run(Device& device, std::int64_t ticks, SnapshotExchange* snapshot,
                         const std::function<void(std::int64_t)>& before_tick = nullptr,
                         const test::HapticScenario& in = test::trench()) {
  LoopOptions o;
  o.ticks = ticks;
  o.record_capacity = std::size_t(ticks);
  o.realtime = false;
  o.snapshot = snapshot;
  const test::LoopRig rig = test::make_loop_rig(in.haptics, in.scenario, Quat{}, device, o);
  HapticLoop& loop = *rig;
  loop.step1(0.0);
  loop.step2(0.0, 0.0, false);
  const long before = g_allocations.load();
  for (std::int64_t i = 1; i < ticks; ++i) {
    if (before_tick) before_tick(i);
    loop.step1(double(i) / in.scenario.rate_hz);
    loop.step2(1.0 / in.scenario.rate_hz, 0.0, false);
  }
  const long during = g_allocations.load() - before;
  EXPECT_GT(loop.simulation().removed_volume_m3(), 0.0);
  return during;
}

TEST(LoopAllocation, ScriptAndSimTicksAllocateNothing) {
  const HapticSettings& s = test::trench().haptics;
  const DevicePath path(test::trench().scenario.cuts[0], Workspace(s.workspace));
  {
    ScriptDevice device(path);
    EXPECT_EQ(allocations_per_run(device, 3000, nullptr), 0);
  }
  {
    SimHandDevice device(
        SimHand(s.hand, s.forces.device.inherent_damping_n_s_per_m, path,
                test::trench().scenario.rate_hz));
    const io::Scenario& sc = test::trench().scenario;
    const Simulation probe(io::sim_params(sc), io::build_initial_heights(sc));
    SnapshotExchange exchange(probe.grid());
    EXPECT_EQ(allocations_per_run(device, 3000, &exchange), 0);
  }
}

TEST(LoopAllocation, TicksOnSoilThatFlowsAllocateNothing) {
  // The trench with soil that flows: the cut is pushed into a pile and the
  // pile relaxes every tick; its scratch is sized when the loop is built.
  test::HapticScenario flow = test::trench();
  flow.scenario.soil.model = SoilModel::kFlow;
  const DevicePath path(flow.scenario.cuts[0], Workspace(flow.haptics.workspace));
  ScriptDevice device(path);
  EXPECT_EQ(allocations_per_run(device, 3000, nullptr, nullptr, flow), 0);
}

TEST(LoopAllocation, UdpTicksAllocateNothing) {
  const HapticSettings& s = test::trench().haptics;
  const DevicePath path(test::trench().scenario.cuts[0], Workspace(s.workspace));
  UdpDevice device("127.0.0.1", 0);
  BridgeClient client("127.0.0.1", device.port(), 9);
  // A pose before every tick (the client's own sends allocate nothing
  // either), plus a malformed datagram now and then.
  std::uint8_t junk[10] = {1, 2, 3};
  const long n = allocations_per_run(device, 3000, nullptr, [&](std::int64_t i) {
    PosePayload p;
    p.position_m = path.position_m(1.6 + double(i) * 1e-3);
    client.send_pose(p, std::uint64_t(i));
    if (i % 100 == 0) client.send_raw(junk, sizeof junk);
  });
  EXPECT_EQ(n, 0);
  EXPECT_GT(device.bridge_stats().accepted, 0);
}

}  // namespace
}  // namespace terracut::haptics
