// A blade's top (validation/top.hpp): pushed square to the grid, turned,
// rolled, slow and fast, on 1 cm and 5 mm cells, no cell against a blade of
// finite height stands above its top unless the blade is buried, the pile
// reaches the top and what goes over lies in the trench behind, and the
// volume is kept.
#include "terracut/validation/top.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <stdexcept>

namespace terracut::validation {
namespace {

TEST(SoilTop, APushedPileNeverStandsAboveTheBladesTop) {
  for (const TopCase& c : validation_top_cases()) {
    const TopMeasure m = measure_top(c);
    EXPECT_LE(m.worst_unburied_m, kTopSlack_m) << describe(c);
    EXPECT_GE(m.reach_m, -1e-3) << describe(c) << ": the pile never reached the top";
    EXPECT_GT(m.over_top_m3, 0.01) << describe(c);
    EXPECT_GE(m.behind_m3, m.over_top_m3 * (1.0 - 1e-3)) << describe(c);
    EXPECT_LE(std::abs(m.volume_error_m3), m.volume_slack_m3) << describe(c);
    EXPECT_TRUE(m.holds()) << describe(c);
  }
}

// Level and not rolled, the blade is never buried in these pushes: the
// trench behind it takes all that falls over, and nothing stands above
// the top at all.
TEST(SoilTop, ALevelBladeIsNeverBuriedInItsOpenTrench) {
  for (const double yaw : {0.0, 30.0, 90.0}) {
    const TopCase c{0.1, yaw, 0.0, 1.0, 0.01};
    EXPECT_LE(measure_top(c).reach_m, kTopSlack_m) << describe(c);
  }
}

TEST(SoilTop, ABadCaseIsRefusedByName) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const TopCase c : {TopCase{0.0}, TopCase{nan}, TopCase{0.1, nan}, TopCase{0.1, 0.0, 6.0},
                          TopCase{0.1, 0.0, 0.0, 3.0}, TopCase{0.1, 0.0, 0.0, 1.0, 0.001}}) {
    EXPECT_THROW(measure_top(c), std::invalid_argument) << describe(c);
  }
}

}  // namespace
}  // namespace terracut::validation
