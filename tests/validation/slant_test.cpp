// A push at a slant (validation/slant.hpp): the pile at the default work cap
// is the converged one (the cap lifted). Tolerances: 5 % of the soil ahead
// of the blade (issue 31's bound) and one cell's repose rise at the peak
// (tan(repose) x the cell).
#include "terracut/validation/slant.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace terracut::validation {
namespace {

TEST(SlantPush, AtThirtyDegreesTheCappedPileIsTheConvergedOne) {
  // A 1 m blade cutting 5 cm, pushed 1 m at 1 m/s turned 30 degrees, on
  // 1 cm cells. The edge passes cell centres somewhere along it in every
  // step, and the spill round its ends runs every step. Its rounds went
  // back and forth between two heights to their limit: the capped pile held
  // 6.5 % more than the converged one (docs/soil.md, "The spill round the
  // ends at a slant").
  SlantPush push;
  push.yaw_deg = 30.0;
  push.depth_m = 0.05;
  push.travel_m = 1.0;
  push.cell_m = 0.01;
  const SlantPile capped = measure_slant(push);
  push.cap = 1000000000;
  const SlantPile converged = measure_slant(push);
  ASSERT_GT(converged.ahead_m3, 0.0);
  EXPECT_NEAR(capped.ahead_m3, converged.ahead_m3, 0.05 * converged.ahead_m3)
      << capped.capped_steps << " steps at the cap";
  EXPECT_NEAR(capped.peak_m, converged.peak_m, std::tan(34.0 * std::numbers::pi / 180.0) * push.cell_m);
}

// With this settle, the push turned 10 degrees leaves the pile it leaves
// square to the grid (cap lifted: within 5 % of the soil ahead, and a
// cell's rise at the peak), and at the default cap the converged one.
void expect_the_turned_pile_is_the_square_one(SoilSettle settle, double cell_m) {
  SlantPush push;
  push.cell_m = cell_m;
  push.settle = settle;
  push.cap = 1000000000;
  const SlantPile turned = measure_slant(push);
  push.yaw_deg = 0.0;
  const SlantPile square = measure_slant(push);
  const double rise = std::tan(34.0 * std::numbers::pi / 180.0) * push.cell_m;
  ASSERT_GT(square.ahead_m3, 0.0);
  EXPECT_NEAR(turned.ahead_m3, square.ahead_m3, 0.05 * square.ahead_m3);
  EXPECT_NEAR(turned.peak_m, square.peak_m, rise);
  push.yaw_deg = 10.0;
  push.cap = SoilFlowParams{}.max_pair_checks_per_step;
  const SlantPile capped = measure_slant(push);
  EXPECT_NEAR(capped.ahead_m3, turned.ahead_m3, 0.05 * turned.ahead_m3) << capped.capped_steps << " steps at the cap";
  EXPECT_NEAR(capped.peak_m, turned.peak_m, rise);
}

TEST(SlantPush, WithThePassesAloneATurnedPileIsTheSquareOne) {
  // soil.settle: passes. A 1 m blade cutting 4 cm, pushed 0.8 m at 1 m/s
  // on 1 cm cells and held 0.2 s. (With the settle's patches, the default
  // until 2026-12-07, the turned pile holds 21 % less: 0.01823 against
  // 0.02316 m^3; docs/soil.md, "The fans by default".)
  expect_the_turned_pile_is_the_square_one(SoilSettle::kPasses, 0.01);
}

TEST(SlantPush, WithTheDefaultSettleATurnedPileIsTheSquareOne) {
  // The default settle, the fans. The same push on 5 mm cells. (With the
  // patches, the default until 2026-12-07, the turned pile holds 52 %
  // less: 0.01064 against 0.02215 m^3, and the capped one twice the
  // converged; docs/soil.md, "The fans by default".)
  ASSERT_EQ(SoilFlowParams{}.settle, SoilSettle::kFans);
  expect_the_turned_pile_is_the_square_one(SoilFlowParams{}.settle, 0.005);
}

TEST(SlantPush, TheDefaultSettlesPileIsThePassesOwn) {
  // A settle is a shortcut to the state the relaxation's passes reach on
  // their own (soil.settle: passes): converged, it must leave the pile they
  // leave, within the bounds (5 % of the soil ahead, a cell's rise
  // at the peak), square to the grid and turned. Measured with the fans:
  // +0.1 % and -1.8 %; with the patches, the default until 2026-12-07,
  // -5.6 % and -55.5 % (docs/soil.md, "The fans by default").
  for (const double yaw : {0.0, 10.0}) {
    SlantPush push;
    push.cell_m = 0.005;
    push.yaw_deg = yaw;
    push.cap = 1000000000;
    push.settle = SoilSettle::kPasses;
    const SlantPile passes = measure_slant(push);
    push.settle = SoilFlowParams{}.settle;
    const SlantPile settled = measure_slant(push);
    const double rise = std::tan(34.0 * std::numbers::pi / 180.0) * push.cell_m;
    ASSERT_GT(passes.ahead_m3, 0.0);
    EXPECT_NEAR(settled.ahead_m3, passes.ahead_m3, 0.05 * passes.ahead_m3) << "yaw " << yaw;
    EXPECT_NEAR(settled.peak_m, passes.peak_m, rise) << "yaw " << yaw;
  }
}

TEST(SlantPush, APushItCannotSetUpIsRefused) {
  const auto refused = [](SlantPush p, const std::string& field) {
    try {
      measure_slant(p);
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
      return;
    }
    ADD_FAILURE() << field << " accepted";
  };
  SlantPush p;
  p.yaw_deg = std::nan("");
  refused(p, "yaw_deg");
  p = {};
  p.width_m = 0.0;
  refused(p, "width_m");
  p = {};
  p.depth_m = 0.2;
  refused(p, "depth_m");
  p = {};
  p.travel_m = -1.0;
  refused(p, "travel_m");
  p = {};
  p.speed_m_per_s = 0.0;
  refused(p, "speed_m_per_s");
  p = {};
  p.hold_s = -0.1;
  refused(p, "hold_s");
  p = {};
  p.cell_m = 0.1;
  refused(p, "cell_m");
  p = {};
  p.cap = 10;
  refused(p, "cap");
}

}  // namespace
}  // namespace terracut::validation
