// A step allocates nothing on the heap after start-up: every global operator
// new in this test program is counted.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>

#include "terracut/core/simulation.hpp"
#include "test_terrains.hpp"

#include "../support/counting_new.hpp"

namespace terracut {
namespace {

TEST(SimulationAllocation, StepAllocatesNothing) {
  for (Representation rep : {Representation::kColumns, Representation::kSurface}) {
    SimParams p;
    p.grid = test::square_spec(256, 256, 1.0, 0.2);
    p.representation = rep;
    p.blade.length_m = 0.8;
    Simulation sim(p, test::dome(p.grid, 0.5, 0.5, 0.4, 0.2));
    long before = g_allocations.load();
    for (int i = 0; i <= 2000; ++i) {
      double t = i / 2000.0;
      // Translation, rotation (with sub-steps) and a lift midway.
      if (i == 1000) sim.lift();
      sim.step({{0.5, 0.1, -0.1 + 1.2 * t}, quat_from_euler_deg({0, 90.0 * t, 20.0 * t})});
    }
    EXPECT_EQ(g_allocations.load() - before, 0) << to_string(rep);
    EXPECT_GT(sim.removed_volume_m3(), 0.0);
  }
}

}  // namespace
}  // namespace terracut
