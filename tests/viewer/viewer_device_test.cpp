// The viewer's virtual device (apps/viewer/viewer_device.hpp): the Tour that
// plays a scenario's cut sequence, and the device as the haptic loop reads
// it (script time, pause, single steps, speed, the mouse's lag, the transit
// back to the script). No OpenGL needed.
#include <gtest/gtest.h>

#include <cmath>

#include "terracut/haptics/workspace.hpp"
#include "terracut/io/scenario.hpp"
#include "viewer_device.hpp"

namespace {

using namespace terracut;
using namespace terracut::viewer;

// Two cuts through a box in the same direction (as the paper's experiment 2's
// A and B, but B also along +Z), so the tool must travel back between them.
const char* kTwoCuts = R"(
name: two_cuts
terrain:
  generator: box
  resolution: 20
  size_m: [1.0, 1.0]
  full_scale_m: 1.0
blade: {length_m: 1.2}
cuts:
  - name: A
    keyframes:
      - {t_s: 0.0, position_m: [0.5, 0.75, -0.1]}
      - {t_s: 2.0, position_m: [0.5, 0.70, 1.1], rotation_deg: [0, 0, 45]}
  - name: B
    keyframes:
      - {t_s: 0.0, position_m: [0.5, 0.5, -0.1]}
      - {t_s: 2.0, position_m: [0.5, 0.5, 1.1]}
)";

constexpr double kClearance = 2.0;
constexpr double kSpeed = 1.0;  // transit speed, m/s

double distance(Vec3 a, Vec3 b) { return length(a - b); }

TEST(ViewerTour, PlaysEachCutThenRisesOverTheTerrainToTheNext) {
  io::Scenario sc = io::parse_scenario(kTwoCuts, "two_cuts.yaml");
  Tour tour(sc, kClearance, kSpeed);
  const Motion& a = sc.cuts[0];
  const Motion& b = sc.cuts[1];
  // Transit: up from A's end (y 0.70 -> 2.0), across back to B's start
  // (1.2 m along Z), down to it (2.0 -> 0.5), at 1 m/s.
  const double up = kClearance - 0.70, across = 1.2, down = kClearance - 0.5;
  EXPECT_NEAR(tour.duration_s(), 2.0 + up + across + down + 2.0, 1e-9);

  // Cut A plays as its motion from t = 0.
  for (double t : {0.0, 0.5, 1.3, 2.0}) {
    EXPECT_LT(distance(tour.sample(t).position_m, a.sample(t).position_m), 1e-12) << t;
  }
  // Cut B plays as its motion after the transit.
  const double b0 = 2.0 + up + across + down;
  for (double t : {0.0, 0.7, 2.0}) {
    EXPECT_LT(distance(tour.sample(b0 + t).position_m, b.sample(t).position_m), 1e-9) << t;
  }
  // The across leg is at the clearance height: it cuts nothing.
  for (double f : {0.01, 0.5, 0.99}) {
    EXPECT_NEAR(tour.sample(2.0 + up + f * across).position_m.y, kClearance, 1e-9);
  }
  // The path is continuous: no jump larger than the fastest speed allows.
  const double dt = 1e-3;
  double max_step = 0.0;
  for (double t = 0.0; t < tour.duration_s(); t += dt)
    max_step = std::max(max_step, distance(tour.sample(t).position_m, tour.sample(t + dt).position_m));
  EXPECT_LT(max_step, 1.3 * dt);  // the cuts move at 0.6 m/s, the transit at 1 m/s
  const PoseLeg* leg = tour.leg_at(b0 + 0.5);
  ASSERT_NE(leg, nullptr);
  EXPECT_EQ(leg->cut, 1);
  EXPECT_EQ(leg->sequence_index, 1);
}

struct ViewerDeviceTest : ::testing::Test {
  io::Scenario sc = io::parse_scenario(kTwoCuts, "two_cuts.yaml");
  Tour tour{sc, kClearance, kSpeed};
  haptics::WorkspaceMapping mapping{12.0, {0.5, 0.3, 0.5}, 30.0};
  haptics::Workspace ws{mapping};
  static constexpr double kRate = 1000.0;

  // The world position the loop maps the device's sample to.
  Vec3 world(const haptics::DeviceSample& s) const { return ws.to_world(s.position_m); }
};

TEST_F(ViewerDeviceTest, ScriptTimeFollowsTheLoopClockAndPauseHolds) {
  ViewerDevice dev(ws, tour, tour.sample(0.0), kRate, kClearance, kSpeed, nullptr);
  dev.set_pause_at_end(false);
  dev.start(0.0);
  haptics::DeviceSample s;
  for (int i = 0; i <= 500; ++i) ASSERT_TRUE(dev.read(i / kRate, s));
  EXPECT_NEAR(dev.script_time_s(), 0.5, 1e-9);
  EXPECT_LT(distance(world(s), tour.sample(0.5).position_m), 1e-9);
  EXPECT_TRUE(s.has_orientation);

  // Paused: the handle holds still while the loop's time goes on.
  dev.set_playing(false);
  const Vec3 held = world(s);
  for (int i = 501; i <= 700; ++i) dev.read(i / kRate, s);
  EXPECT_LT(distance(world(s), held), 1e-12);
  // A single step advances one loop period.
  dev.request_steps(1);
  dev.read(701 / kRate, s);
  EXPECT_NEAR(dev.script_time_s(), 0.5 + 1.0 / kRate, 1e-9);

  // Half speed: 200 ticks play 0.1 s of script.
  dev.set_playing(true);
  dev.set_speed(0.5);
  for (int i = 702; i < 902; ++i) dev.read(i / kRate, s);
  EXPECT_NEAR(dev.script_time_s(), 0.5 + 1.0 / kRate + 0.1, 1e-9);
}

TEST_F(ViewerDeviceTest, ScriptEndPausesWhenAsked) {
  ViewerDevice dev(ws, tour, tour.sample(0.0), kRate, kClearance, kSpeed, nullptr);
  dev.set_speed(16.0);
  dev.start(0.0);
  haptics::DeviceSample s;
  int i = 0;
  while (!dev.script_finished() && i < 100000) dev.read(++i / kRate, s);
  EXPECT_TRUE(dev.script_finished());
  EXPECT_FALSE(dev.playing());
  EXPECT_NEAR(dev.script_time_s(), tour.duration_s(), 1e-12);
  EXPECT_LT(distance(world(s), tour.sample(tour.duration_s()).position_m), 1e-9);
}

TEST_F(ViewerDeviceTest, MouseTargetIsFollowedWithAFirstOrderLag) {
  const BladePose start = tour.sample(0.0);
  ViewerDevice dev(ws, tour, start, kRate, kClearance, kSpeed, nullptr);
  dev.set_source(ToolSource::kMouse);
  dev.start(0.0);
  haptics::DeviceSample s;
  dev.read(0.0, s);
  BladePose target = start;
  target.position_m = start.position_m + Vec3{0.3, -0.2, 0.1};
  dev.set_target(target);
  // After T seconds the remaining distance is d0 * exp(-T / lag).
  const int ticks = 60;
  for (int i = 1; i <= ticks; ++i) dev.read(i / kRate, s);
  const double d0 = length(Vec3{0.3, -0.2, 0.1});
  const double expected = d0 * std::exp(-(ticks / kRate) / kVirtualDeviceLag_s);
  EXPECT_NEAR(distance(world(s), target.position_m), expected, 1e-6);
}

TEST_F(ViewerDeviceTest, BackToTheScriptTheToolTravelsOverTheTerrain) {
  const BladePose start = tour.sample(0.0);
  ViewerDevice dev(ws, tour, start, kRate, kClearance, kSpeed, nullptr);
  dev.set_pause_at_end(false);
  dev.start(0.0);
  haptics::DeviceSample s;
  int i = 0;
  for (; i <= 300; ++i) dev.read(i / kRate, s);  // script time 0.3 s
  const double script_t = dev.script_time_s();
  // The mouse drags the tool somewhere else.
  dev.set_source(ToolSource::kMouse);
  BladePose away = start;
  away.position_m = {0.2, 0.4, 0.8};
  dev.set_target(away);
  for (int k = 0; k < 1000; ++k, ++i) dev.read(i / kRate, s);
  EXPECT_LT(distance(world(s), away.position_m), 1e-6);
  // Back to the script: up to the clearance, over, down to where it left off.
  dev.set_source(ToolSource::kScript);
  double highest = -1e9;
  for (int k = 0; k < 10000; ++k, ++i) {
    dev.read(i / kRate, s);
    highest = std::max(highest, world(s).y);
    if (dev.script_time_s() > script_t + 0.05) break;
  }
  EXPECT_NEAR(highest, kClearance, 1e-6);
  EXPECT_GT(dev.script_time_s(), script_t);
  EXPECT_LT(distance(world(s), tour.sample(dev.script_time_s()).position_m), 1e-9);
}

}  // namespace
