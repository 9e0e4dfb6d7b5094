// The viewer's loop driver (apps/viewer/loop_driver.*) with a drawing thread
// that does what the window does -- acquire frames, read the device's
// published state, post controls and targets -- while the loop runs on its
// own thread, paced and lock-step. Built and run under ThreadSanitizer by
// tests/tsan/tsan_test.sh: the exchange between the threads must be free
// of data races. (The viewer's own tests cover what the driver computes.)
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <thread>

#include "loop_driver.hpp"
#include "terracut/session/scenario.hpp"

namespace terracut::viewer {
namespace {

session::Scenario scenario() {
  return session::load_scenario(std::filesystem::path(TERRACUT_SOURCE_DIR) / "scenarios/trench_dry_sand.yaml");
}

// What the drawing thread does with each frame: read it, and turn the controls.
void draw(LoopDriver& driver, int round) {
  if (const haptics::ViewFrame* frame = driver.exchange().acquire()) {
    volatile float h = frame->heights.empty() ? 0.0f : frame->heights[frame->heights.size() / 2];
    (void)h;
  }
  ViewerDevice& device = driver.device();
  (void)device.script_time_s();
  (void)device.script_finished();
  device.set_speed(1.0 + 0.5 * (round % 3));
  if (round % 7 == 0) device.set_playing(!device.playing());
  if (round % 5 == 0) device.request_steps(3);
  BladePose target;
  target.position_m = {0.01 * (round % 10), 0.2, 0.0};
  device.set_target(target);
  if (round % 11 == 0) device.set_source(round % 2 ? ToolSource::kScript : ToolSource::kMouse);
}

TEST(LoopDriverThreads, PacedLoopAndDrawingThread) {
  const session::Scenario sc = scenario();
  DriverOptions options;
  options.paced = true;
  options.realtime = false;
  LoopTiming timing;
  LoopDriver driver(sc, viewer_settings(sc.haptics), options, &timing);
  driver.start();
  const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(600);
  for (int round = 0; std::chrono::steady_clock::now() < end; ++round) {
    draw(driver, round);
    (void)timing.snapshot();
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  driver.stop();
  EXPECT_GT(driver.loop().counters().ticks, 0);
}

TEST(LoopDriverThreads, LockStepLoopAndDrawingThread) {
  const session::Scenario sc = scenario();
  DriverOptions options;
  options.paced = false;
  options.realtime = false;
  LoopDriver driver(sc, viewer_settings(sc.haptics), options, nullptr);
  driver.start();
  for (int frame = 1; frame <= 40; ++frame) {
    driver.run_until_tick(frame * 10);
    while (driver.ticks_done() < frame * 10) {
      draw(driver, frame);
      std::this_thread::yield();
    }
  }
  driver.stop();
  EXPECT_GE(driver.ticks_done(), 400);
}

}  // namespace
}  // namespace terracut::viewer
