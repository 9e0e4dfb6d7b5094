// The viewer's teleoperation mode (LoopDriver with DriverOptions::mmt): the
// viewer's device drives the operator station, the remote runs in-process,
// and the remote's patches reach the frames the viewer draws. The remote
// world's sand lies 2 cm lower than the operator's model: before the blade
// touches anything, the sensed square around the remote tool comes back and
// the drawn local model sinks there to the remote's heights, and nowhere else.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "loop_driver.hpp"
#include "terracut/core/error.hpp"
#include "terracut/session/scenario.hpp"
#include "../support/scenario_text.hpp"

namespace {

using namespace terracut;
using namespace terracut::viewer;
namespace fs = std::filesystem;

const fs::path kTrench = fs::path(TERRACUT_SOURCE_DIR) / "scenarios" / "mmt_trench_clay.yaml";

session::Scenario trench_with_lower_remote() {
  std::ifstream in(kTrench);
  std::ostringstream text;
  text << in.rdbuf();
  const fs::path dir = fs::temp_directory_path() / "terracut_viewer_mmt";
  fs::create_directories(dir);
  std::ofstream(dir / "remote.yaml") << test::replace(text.str(), "height_m: 0.3", "height_m: 0.28");
  session::Scenario sc = session::load_scenario(kTrench);
  sc.mmt->remote_scenario = dir / "remote.yaml";
  return sc;
}

TEST(ViewerMmt, RemotePatchesReachTheDrawnLocalModel) {
  const session::Scenario sc = trench_with_lower_remote();
  DriverOptions o;
  o.paced = false;
  o.source = ToolSource::kScript;
  o.mmt = true;
  LoopDriver d(sc, viewer_settings(sc.haptics), o, nullptr);
  ASSERT_TRUE(d.mmt());
  d.start();
  // 0.6 s: the tool holds 5 cm above the sand at (0, 0.75) for the first
  // second; a round trip (0.1 s), a sensing period (0.05 s) and the blend
  // (0.1 s) later the first patch has landed.
  const std::int64_t ticks = std::llround(0.6 * d.rate_hz());
  d.run_until_tick(ticks);
  while (d.ticks_done() < ticks) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  d.stop();
  const haptics::ViewFrame* f = d.exchange().acquire();
  ASSERT_NE(f, nullptr);

  const GridSpec& g = d.spec();
  const double sense_r = sc.mmt->sense_radius_m;
  int inside = 0, outside = 0;
  for (int row = 0; row < g.rows; ++row)
    for (int col = 0; col < g.cols; ++col) {
      const double x = g.origin_m.x + (col + 0.5) * g.cell_x_m();
      const double z = g.origin_m.z + (row + 0.5) * g.cell_z_m();
      const float h = f->heights[std::size_t(row) * std::size_t(g.cols) + std::size_t(col)];
      // Well inside the sensed square around (0, 0.75), by a cell: the
      // remote's, within 1/20 of the 2 cm difference (the newest patches'
      // blends are still finishing their last fraction).
      if (std::fabs(x) < sense_r - g.cell_x_m() && std::fabs(z - 0.75) < sense_r - g.cell_z_m()) {
        EXPECT_NEAR(h, 0.28, 0.001) << "col " << col << " row " << row;
        ++inside;
      } else if (std::fabs(x) > sense_r + g.cell_x_m() || std::fabs(z - 0.75) > sense_r + g.cell_z_m()) {
        EXPECT_NEAR(h, 0.30, 1e-5) << "col " << col << " row " << row;
        ++outside;
      }
    }
  EXPECT_GT(inside, 100);
  EXPECT_GT(outside, 1000);
  const MmtLive& m = d.mmt_live();
  EXPECT_GT(m.patches.load(), 0);
  // The measured round trip is the emulated one, within the jitter both ways
  // and a tick of each station.
  EXPECT_NEAR(m.rtt_s.load(), m.emulated_rtt_s.load(),
              sc.mmt->to_remote.jitter_s + sc.mmt->to_operator.jitter_s + 2.0 / d.rate_hz());
}

TEST(ViewerMmt, AScenarioWithoutAnMmtSectionIsRefusedByName) {
  const session::Scenario sc =
      session::load_scenario(fs::path(TERRACUT_SOURCE_DIR) / "scenarios" / "trench_dry_sand.yaml");
  DriverOptions o;
  o.paced = false;
  o.mmt = true;
  try {
    LoopDriver d(sc, viewer_settings(sc.haptics), o, nullptr);
    FAIL() << "accepted --mmt without an mmt: section";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("mmt"), std::string::npos) << e.what();
  }
}

}  // namespace
