// The viewer's input and panel logic without a window (viewer_controls.hpp,
// and the pause, step and reset behaviour of the virtual device and the
// session options): what the tool readout says, which key does what, when a
// paused viewer takes frames, when the window redraws, where the tool's
// label goes, and what a Reset keeps.
#include <GLFW/glfw3.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <ctime>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <thread>
#include <vector>

#include "loop_driver.hpp"
#include "terracut/session/scenario.hpp"
#include "terracut/haptics/workspace.hpp"
#include "terracut/io/scenario.hpp"
#include "viewer_controls.hpp"
#include "viewer_device.hpp"

namespace {

using namespace terracut;
using namespace terracut::viewer;

constexpr int kSide = 100;
constexpr double kCell = 0.01;  // metres

// The blade tilted about its own Z (its +X end up), then turned about world +Y.
BladePose pose_at(Vec3 p, double yaw_deg, double tilt_deg) {
  constexpr double kRad = 3.14159265358979323846 / 180.0;
  return {p, quat_from_axis_angle({0, 1, 0}, yaw_deg * kRad) *
                 quat_from_axis_angle({0, 0, 1}, tilt_deg * kRad)};
}

TEST(ToolReadout, HeightDepthYawAndTiltOfTheBlade) {
  // A 0.2 m layer on ground at y = 0.1.
  GridSpec spec = grid_of_cells(kSide, kSide, kCell);
  spec.origin_m.y = 0.1;
  const std::vector<float> h(kSide * kSide, 0.2f);
  for (Representation rep : {Representation::kSurface, Representation::kColumns}) {
    const ToolReadout r = tool_readout(pose_at({0.5, 0.25, 0.5}, 30.0, 10.0), spec, h.data(), rep);
    EXPECT_NEAR(r.height_m, 0.15, 1e-12);
    EXPECT_NEAR(r.depth_m, 0.3 - 0.25, 1e-6);  // 5 cm into the soil
    EXPECT_NEAR(r.yaw_deg, 30.0, 1e-9);
    EXPECT_NEAR(r.tilt_deg, 10.0, 1e-9);
    // Above the soil: a negative depth is the clearance.
    const ToolReadout up = tool_readout(pose_at({0.5, 0.42, 0.5}, 0.0, 0.0), spec, h.data(), rep);
    EXPECT_NEAR(up.depth_m, -(0.42 - 0.3), 1e-6);
    EXPECT_NEAR(up.yaw_deg, 0.0, 1e-12);
    EXPECT_NEAR(up.tilt_deg, 0.0, 1e-12);
  }
  // The Q key turns the blade positively about +Y: +X toward -Z is +yaw.
  EXPECT_NEAR(tool_readout(pose_at({0.5, 0.3, 0.5}, -120.0, 0.0), spec, h.data(),
                           Representation::kSurface)
                  .yaw_deg,
              -120.0, 1e-9);
}

TEST(ToolReadout, DepthIsReadBesideTheBladesOwnTrench) {
  // The blade (along X) sits at the bottom of the one-row trench it cut.
  GridSpec spec = grid_of_cells(kSide, kSide, kCell);
  std::vector<float> h(kSide * kSide, 0.2f);
  for (int c = 0; c < kSide; ++c) h[std::size_t(50) * kSide + c] = 0.12f;
  const ToolReadout r =
      tool_readout(pose_at({0.5, 0.12, 0.505}, 0.0, 0.0), spec, h.data(), Representation::kColumns);
  EXPECT_NEAR(r.depth_m, 0.08, 1e-6);
}

TEST(KeyCommands, EscAndCtrlQQuitAPlainQTurns) {
  EXPECT_EQ(key_command(GLFW_KEY_ESCAPE, 0), KeyCommand::kQuit);
  EXPECT_EQ(key_command(GLFW_KEY_Q, GLFW_MOD_CONTROL), KeyCommand::kQuit);
  EXPECT_EQ(key_command(GLFW_KEY_Q, 0), KeyCommand::kNone);  // held: turn about Y
  EXPECT_EQ(key_command(GLFW_KEY_SPACE, 0), KeyCommand::kPlayPause);
  EXPECT_EQ(key_command(GLFW_KEY_N, 0), KeyCommand::kStep);
  EXPECT_EQ(key_command(GLFW_KEY_BACKSPACE, 0), KeyCommand::kReset);
  EXPECT_EQ(key_command(GLFW_KEY_T, 0), KeyCommand::kTopView);
  EXPECT_EQ(key_command(GLFW_KEY_C, 0), KeyCommand::kColour);
  EXPECT_EQ(key_command(GLFW_KEY_E, 0), KeyCommand::kNone);
}

TEST(FrameGate, PausedFreezesWhatIsShownAndAStepIsSeen) {
  FrameGate gate;
  // Playing: every frame.
  for (int i = 0; i < 5; ++i) EXPECT_TRUE(gate.take(true, 0.001 * i));
  // Paused with the clock still: a few frames for the ticks in flight, then none.
  int taken = 0;
  for (int i = 0; i < 20; ++i) taken += gate.take(false, 0.004) ? 1 : 0;
  EXPECT_GT(taken, 0);
  EXPECT_LE(taken, 4);
  EXPECT_FALSE(gate.take(false, 0.004));
  // A step moves the device clock: its frames are taken, and the ones that
  // settle after it, then none again.
  EXPECT_TRUE(gate.take(false, 0.010));
  EXPECT_TRUE(gate.take(false, 0.024));
  taken = 0;
  for (int i = 0; i < 20; ++i) taken += gate.take(false, 0.024) ? 1 : 0;
  EXPECT_LE(taken, 4);
  EXPECT_FALSE(gate.take(false, 0.024));
  // A new session takes its first frame.
  gate.reset();
  EXPECT_TRUE(gate.take(false, 0.0));
}

TEST(RedrawGate, DrawsOnlyAfterAChange) {
  RedrawGate gate;
  int drawn = 0;
  for (int i = 0; i < 10; ++i) drawn += gate.draw() ? 1 : 0;
  EXPECT_EQ(drawn, RedrawGate::kSettleFrames);  // the first frames, then idle
  EXPECT_FALSE(gate.draw());
  gate.changed();
  drawn = 0;
  for (int i = 0; i < 10; ++i) drawn += gate.draw() ? 1 : 0;
  EXPECT_EQ(drawn, RedrawGate::kSettleFrames);
}

// Whether the rectangle (x, y, w, h) contains the point.
bool covers(float x, float y, float w, float h, float px, float py) {
  return px >= x && px <= x + w && py >= y && py <= y + h;
}

TEST(LabelPosition, BesideTheToolClearOfTheBladeAndInsideTheView) {
  const ScreenRect view{390.0f, 0.0f, 890.0f, 800.0f};
  const float w = 180.0f, h = 40.0f, gap = 22.0f;
  // Directions of the blade on the screen: level, steep, diagonal both ways.
  const float dirs[4][2] = {{1.0f, 0.0f}, {0.0f, 1.0f}, {1.0f, -1.0f}, {1.0f, 1.0f}};
  const float tools[3][2] = {{800.0f, 400.0f}, {1270.0f, 5.0f}, {395.0f, 790.0f}};
  for (const auto& t : tools)
    for (const auto& d : dirs) {
      float x = 0.0f, y = 0.0f;
      label_position(t[0], t[1], d[0], d[1], w, h, view, gap, x, y);
      // Inside the scene viewport (never clipped).
      EXPECT_GE(x, view.x);
      EXPECT_GE(y, view.y);
      EXPECT_LE(x + w, view.x + view.w + 1e-3f);
      EXPECT_LE(y + h, view.y + view.h + 1e-3f);
      // Never over the tool point.
      EXPECT_FALSE(covers(x, y, w, h, t[0], t[1])) << t[0] << "," << t[1];
      // In the middle of the view, clear of the blade's line too: no point
      // of the blade within 150 px of the tool is under the label.
      if (t[0] == 800.0f) {
        const float n = std::hypot(d[0], d[1]);
        for (float s = -150.0f; s <= 150.0f; s += 5.0f)
          EXPECT_FALSE(covers(x, y, w, h, t[0] + s * d[0] / n, t[1] + s * d[1] / n))
              << d[0] << "," << d[1] << " s " << s;
      }
    }
  // A view resized smaller than the label: it starts at the view's corner.
  float x = 0.0f, y = 0.0f;
  label_position(100.0f, 50.0f, 1.0f, 0.0f, w, h, ScreenRect{0.0f, 0.0f, 120.0f, 30.0f}, gap, x, y);
  EXPECT_EQ(x, 0.0f);
  EXPECT_EQ(y, 0.0f);
}

// A straight cut along +Z at 1 m/s, for the device's pause and step.
const char* kLine = R"(
name: line
terrain: {generator: plane, resolution: 10, size_m: [1.0, 1.0], full_scale_m: 0.2}
blade: {length_m: 0.5}
cuts:
  - name: A
    keyframes:
      - {t_s: 0.0, position_m: [0.5, 0.1, 0.0]}
      - {t_s: 1.0, position_m: [0.5, 0.1, 1.0]}
)";

TEST(ViewerControls, AStepPlaysItsStatedTimeThenHolds) {
  const io::Scenario sc = io::parse_scenario(kLine, "line.yaml");
  const Tour tour(sc, 1.0, 1.0);
  const haptics::Workspace ws{haptics::WorkspaceMapping{}};
  constexpr double kRate = 1000.0;
  ViewerDevice dev(ws, tour, tour.sample(0.0), kRate, 1.0, 1.0, nullptr);
  dev.start(0.0);
  haptics::DeviceSample s;
  int i = 0;
  for (; i <= 100; ++i) dev.read(i / kRate, s);
  EXPECT_NEAR(dev.clock_s(), 0.1, 1e-9);
  // Paused: the clock, the script and the tool stand still.
  dev.set_playing(false);
  for (int k = 0; k < 50; ++k, ++i) dev.read(i / kRate, s);
  EXPECT_NEAR(dev.clock_s(), 0.1, 1e-9);
  EXPECT_NEAR(dev.script_time_s(), 0.1, 1e-9);
  // A Step: kStepTime_s of device time over as many ticks, then holding again.
  dev.request_step_s(kStepTime_s);
  EXPECT_TRUE(dev.stepping());
  int ticks = 0;
  while (dev.stepping() && ticks < 1000) {
    dev.read(i++ / kRate, s);  // one loop period per tick
    ++ticks;
  }
  EXPECT_EQ(ticks, int(std::lround(kStepTime_s * kRate)));
  EXPECT_NEAR(dev.clock_s(), 0.1 + kStepTime_s, 1e-9);
  EXPECT_NEAR(dev.script_time_s(), 0.1 + kStepTime_s, 1e-9);
  EXPECT_NEAR(ws.to_world(s.position_m).z, 0.1 + kStepTime_s, 1e-9);  // 20 mm at 1 m/s
  EXPECT_FALSE(dev.playing());
  for (int k = 0; k < 50; ++k) dev.read(i++ / kRate, s);
  EXPECT_NEAR(dev.clock_s(), 0.1 + kStepTime_s, 1e-9);
  // Bad requests are ignored.
  dev.request_step_s(-1.0);
  dev.request_step_s(std::nan(""));
  EXPECT_FALSE(dev.stepping());
}

// The device says paused only while neither playing nor stepping: that is
// when the paced loop holds (haptics::Device::paused).
TEST(ViewerControls, TheDeviceIsPausedOnlyWithNothingToPlay) {
  const io::Scenario sc = io::parse_scenario(kLine, "line.yaml");
  const Tour tour(sc, 1.0, 1.0);
  const haptics::Workspace ws{haptics::WorkspaceMapping{}};
  ViewerDevice dev(ws, tour, tour.sample(0.0), 1000.0, 1.0, 1.0, nullptr);
  EXPECT_FALSE(dev.paused());
  dev.set_playing(false);
  EXPECT_TRUE(dev.paused());
  dev.request_step_s(kStepTime_s);
  EXPECT_FALSE(dev.paused());
  dev.request_step_s(-1.0);  // ignored
  EXPECT_FALSE(dev.paused());
  dev.start(0.0);
  haptics::DeviceSample s;
  for (int i = 0; dev.stepping() && i < 1000; ++i) dev.read(i / 1000.0, s);
  EXPECT_TRUE(dev.paused());
  dev.request_steps(1);
  EXPECT_FALSE(dev.paused());
}

// CPU time of this process, seconds.
double process_cpu_s() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

// Pause pauses the paced haptic loop: while paused the loop ticks nothing
// and the process spends almost no CPU (the loop at 1 kHz spends a tenth of
// a core spinning to its deadlines); Play starts it again, and the pause is
// no period in the device's timing.
TEST(ViewerControls, PauseHoldsThePacedHapticLoop) {
  const session::Scenario sc = session::load_scenario(
      std::filesystem::path(TERRACUT_SOURCE_DIR) / "scenarios/trench_dry_sand.yaml");
  LoopTiming timing;
  DriverOptions o;
  o.paced = true;
  o.realtime = false;
  o.source = ToolSource::kScript;
  LoopDriver d(sc, viewer_settings(sc.haptics), o, &timing);
  d.start();
  using namespace std::chrono_literals;
  std::this_thread::sleep_for(200ms);
  const std::int64_t playing = timing.snapshot().ticks;
  EXPECT_GT(playing, 50);
  d.device().set_playing(false);
  std::this_thread::sleep_for(50ms);  // the tick in flight ends, the loop holds
  const std::int64_t held_from = timing.snapshot().ticks;
  const double cpu0 = process_cpu_s();
  const auto wall0 = std::chrono::steady_clock::now();
  std::this_thread::sleep_for(400ms);
  const double cpu_s = process_cpu_s() - cpu0;
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  EXPECT_EQ(timing.snapshot().ticks, held_from) << "the loop ticked while paused";
  EXPECT_LT(cpu_s, 0.02 * wall_s) << "CPU while paused: " << cpu_s << " s in " << wall_s << " s";
  std::printf("paused: %.4f s of CPU in %.3f s (%.2f %% of a core)\n", cpu_s, wall_s, 100.0 * cpu_s / wall_s);
  d.device().set_playing(true);
  std::this_thread::sleep_for(200ms);
  EXPECT_GT(timing.snapshot().ticks - held_from, 50);
  // The 400 ms hold is not a period of the loop.
  EXPECT_LT(timing.snapshot().period_max_us, 300e3);
  d.stop();
}

TEST(ViewerControls, AResetKeepsThePauseTheSourceAndTheSpeed) {
  const io::Scenario sc = io::parse_scenario(kLine, "line.yaml");
  const Tour tour(sc, 1.0, 1.0);
  const haptics::Workspace ws{haptics::WorkspaceMapping{}};
  ViewerDevice dev(ws, tour, tour.sample(0.0), 1000.0, 1.0, 1.0, nullptr);
  DriverOptions before;
  before.playing = true;
  before.source = ToolSource::kScript;
  dev.set_playing(false);
  dev.set_source(ToolSource::kMouse);
  dev.set_speed(0.25);
  const DriverOptions after = reset_options(before, dev);
  EXPECT_FALSE(after.playing);  // paused stays paused
  EXPECT_EQ(after.source, ToolSource::kMouse);
  EXPECT_EQ(after.speed, 0.25);
  dev.set_playing(true);
  EXPECT_TRUE(reset_options(before, dev).playing);
}

TEST(ViewerControls, TheMouseToolIsPutDownJustAboveTheSoil) {
  const GridSpec spec = grid_of_cells(kSide, kSide, kCell);
  EXPECT_NEAR(mouse_clearance_m(spec, 0.2), 0.005, 1e-12);  // half a 1 cm cell
  EXPECT_NEAR(mouse_clearance_m(spec, 2.0), 0.04, 1e-12);   // 2 % of a tall terrain
}

// The mouse-driven cut through the trench's sand, as the window drives it:
// targets posted once a frame (25 frames/s, as a slow software renderer
// draws) moving steadily along -Z at 0.3 m/s with the blade 6 cm deep; the
// haptic loop steps in lock-step. Returns |horizontal world force| per tick
// over the steady part of the cut.
std::vector<double> mouse_cut_force(bool ramp) {
  const session::Scenario sc = session::load_scenario(
      std::filesystem::path(TERRACUT_SOURCE_DIR) / "scenarios/trench_dry_sand.yaml");
  DriverOptions o;
  o.paced = false;
  o.source = ToolSource::kMouse;
  o.record_capacity = 4000;
  LoopDriver d(sc, viewer_settings(sc.haptics), o, nullptr);
  ViewerDevice& dev = d.device();
  constexpr int kFrameTicks = 40;  // 25 frames/s at 1 kHz
  const double frame_s = kFrameTicks / d.rate_hz();
  if (ramp) {
    dev.set_frame_interval_s(frame_s);
  } else {
    dev.set_lag_s(1.5 * frame_s);  // the viewer's behaviour before: a lag alone
  }
  d.start();
  BladePose target{{0.0, 0.24, 0.6}, {}};
  std::int64_t tick = 0;
  auto frame = [&] {
    dev.set_target(target);
    tick += kFrameTicks;
    d.run_until_tick(tick);
    while (d.ticks_done() < tick) std::this_thread::sleep_for(std::chrono::microseconds(50));
  };
  for (int k = 0; k < 25; ++k) frame();  // into the sand, 1 s
  const double speed = 0.3;
  for (int k = 0; k < 75; ++k) {  // 3 s along -Z
    target.position_m.z -= speed * frame_s;
    frame();
  }
  d.stop();
  std::vector<double> out;
  for (const haptics::LoopRecord& r : d.loop().records())
    if (r.t_s > 2.0 && r.t_s < 3.9) out.push_back(std::hypot(r.force_world_n.x, r.force_world_n.z));
  return out;
}

double relative_ripple(const std::vector<double>& f) {
  double mean = 0.0;
  for (double x : f) mean += x;
  mean /= double(f.size());
  double var = 0.0;
  for (double x : f) var += (x - mean) * (x - mean);
  return std::sqrt(var / double(f.size())) / mean;
}

TEST(ViewerControls, AMouseDrivenCutDoesNotBuzzAtTheFrameRate) {
  // With a lag alone the tool's speed decays within every frame, and the
  // cutting force (below its saturation speed, beta |v|) follows it: a
  // saw-tooth at the frame rate. Ramping to each target over one frame
  // keeps the speed, and the force, steady.
  const std::vector<double> before = mouse_cut_force(false);
  const std::vector<double> after = mouse_cut_force(true);
  ASSERT_GT(before.size(), 1000u);
  ASSERT_EQ(before.size(), after.size());
  const double mean_after = [&] {
    double m = 0.0;
    for (double x : after) m += x;
    return m / double(after.size());
  }();
  EXPECT_GT(mean_after, 50.0);  // cutting: about 500 N s/m x 0.3 m/s
  EXPECT_GT(relative_ripple(before), 0.15);
  EXPECT_LT(relative_ripple(after), 0.02);
  // For docs/viewer.md's spectrum: both series, when asked for.
  if (const char* path = std::getenv("TERRACUT_MOUSE_CUT_CSV")) {
    std::ofstream csv(path);
    csv << "t,before_n,after_n\n";
    for (std::size_t i = 0; i < before.size(); ++i)
      csv << 2.0 + 1e-3 * double(i + 1) << "," << before[i] << "," << after[i] << "\n";
  }
}

}  // namespace
