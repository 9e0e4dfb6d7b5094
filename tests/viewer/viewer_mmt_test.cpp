// The viewer's teleoperation mode (LoopDriver with DriverOptions::mmt): the
// viewer's device drives the operator station, the remote runs in-process,
// and the remote's patches reach the frames the viewer draws. The remote
// world's sand lies 2 cm lower than the operator's model: before the blade
// touches anything, the sensed square around the remote tool comes back and
// the drawn local model sinks there to the remote's heights, and nowhere else.
// The same against a remote station in another process (`terracut mmt
// --role remote`, the viewer's --remote), and the viewer's refusals of a bad
// --remote.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>
#include <vector>

#include "loop_driver.hpp"
#include "terracut/core/error.hpp"
#include "terracut/session/scenario.hpp"
#include "../support/scenario_text.hpp"
#include "../support/spawn.hpp"

namespace {

using namespace terracut;
using namespace terracut::viewer;
namespace fs = std::filesystem;

const fs::path kTrench = fs::path(TERRACUT_SOURCE_DIR) / "scenarios" / "mmt_trench_clay.yaml";

session::Scenario trench_with_lower_remote() {
  const fs::path dir = fs::temp_directory_path() / "terracut_viewer_mmt";
  fs::create_directories(dir);
  std::ofstream(dir / "remote.yaml") << test::replace(test::read_text(kTrench), "height_m: 0.3", "height_m: 0.28");
  session::Scenario sc = session::load_scenario(kTrench);
  sc.mmt->remote_scenario = dir / "remote.yaml";
  return sc;
}

// The first 0.6 s of the trench in the viewer's driver with the remote
// station in-process (remote empty) or at that address; checks that the
// remote's patches reached the drawn model, only inside the sensed square.
void expect_patches_drawn(const session::Scenario& sc, const std::string& remote,
                          double rtt_slack_s, const net::LinkKey& key = {}) {
  DriverOptions o;
  o.paced = false;
  o.source = ToolSource::kScript;
  o.mmt = true;
  o.remote = remote;
  o.key = key;
  LoopDriver d(sc, viewer_settings(sc.haptics), o, nullptr);
  ASSERT_TRUE(d.mmt());
  EXPECT_EQ(d.remote_station() == nullptr, !remote.empty());
  d.start();
  // 0.6 s: the tool holds 5 cm above the sand at (0, 0.75) for the first
  // second; a round trip (0.1 s), a sensing period (0.05 s) and the blend
  // (0.1 s) later the first patch has landed.
  const std::int64_t ticks = std::llround(0.6 * d.rate_hz());
  d.run_until_tick(ticks);
  while (d.ticks_done() < ticks) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  d.stop();
  d.end_session();
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
  // and a tick of each station; over real UDP never shorter than the
  // emulated delays less the jitter (the station's clock is the wall clock's).
  EXPECT_NEAR(m.rtt_s.load(), m.emulated_rtt_s.load(),
              sc.mmt->to_remote.jitter_s + sc.mmt->to_operator.jitter_s + 2.0 / d.rate_hz() +
                  rtt_slack_s);
  EXPECT_GE(m.rtt_s.load(), m.emulated_rtt_s.load() - sc.mmt->to_remote.jitter_s - sc.mmt->to_operator.jitter_s);
}

TEST(ViewerMmt, RemotePatchesReachTheDrawnLocalModel) {
  expect_patches_drawn(trench_with_lower_remote(), "", 0.0);
}


// The window prints how the loop is scheduled: in MMT the stations tick on
// the driver's own thread, and that is said (it printed an empty line).
TEST(ViewerMmt, TheRealTimeLineSaysHowTheStationsAreScheduled) {
  const session::Scenario sc = session::load_scenario(kTrench);
  DriverOptions o;
  o.paced = false;
  o.mmt = true;
  LoopDriver d(sc, viewer_settings(sc.haptics), o, nullptr);
  EXPECT_EQ(d.realtime_line().rfind("real-time: ", 0), 0u) << d.realtime_line();
  EXPECT_NE(d.realtime_line().find("stations"), std::string::npos) << d.realtime_line();
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


// The trench's operator scenario with its remote world written next to it
// (the sand 2 cm lower), as files: another process reads them.
fs::path trench_files_with_lower_remote(const fs::path& dir) {
  std::ifstream in(kTrench);
  std::ostringstream text;
  text << in.rdbuf();
  fs::create_directories(dir);
  std::ofstream(dir / "remote.yaml") << test::replace(text.str(), "height_m: 0.3", "height_m: 0.28");
  std::ofstream(dir / "operator.yaml")
      << test::replace(text.str(), "# scenario: omitted:", "scenario: remote.yaml  #");
  return dir / "operator.yaml";
}

std::string slurp(const fs::path& p) {
  std::ifstream f(p);
  std::ostringstream s;
  s << f.rdbuf();
  return s.str();
}

TEST(ViewerMmt, TheViewerIsTheOperatorOfARemoteInAnotherProcess) {
  const fs::path dir =
      fs::temp_directory_path() / ("terracut_viewer_mmt_remote_" + std::to_string(getpid()));
  fs::remove_all(dir);
  const fs::path scenario = trench_files_with_lower_remote(dir);
  const fs::path key_file = dir / "mmt.key";
  const net::LinkKey link_key = net::write_new_key_file(key_file);
  // The remote station binds any free port and says which.
  const fs::path log = dir / "remote.log";
  const pid_t remote = test::spawn({TERRACUT_BIN, "mmt", scenario.string(), "--role", "remote",
                                    "--listen", "127.0.0.1:0", "--key", key_file.string(), "--out",
                                    (dir / "remote").string()},
                                   log, dir / "remote.err");
  ASSERT_GT(remote, 0);
  const std::string key = "remote listening on 127.0.0.1:";
  std::string port;
  for (int i = 0; i < 400 && port.empty(); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(25));
    const std::string text = slurp(log);
    if (const std::size_t at = text.find(key); at != std::string::npos)
      port = std::to_string(std::atoi(text.c_str() + at + key.size()));
  }
  ASSERT_FALSE(port.empty()) << "the remote station did not say its port: " << slurp(dir / "remote.err");
  // Real UDP on a shared machine: the measured round trip may also carry a
  // few milliseconds of scheduling.
  expect_patches_drawn(session::load_scenario(scenario), "127.0.0.1:" + port, 0.01, link_key);
  // The viewer ended the session: the remote ends, having heard the viewer's commands.
  EXPECT_EQ(test::wait_exit(remote, 30.0), 0) << slurp(dir / "remote.err");
  const std::string summary = slurp(dir / "remote" / "summary.json");
  EXPECT_NE(summary.find("\"role\": \"remote\""), std::string::npos) << summary;
  EXPECT_NE(summary.find("\"accepted\": "), std::string::npos) << summary;
  EXPECT_EQ(summary.find("\"accepted\": 0,"), std::string::npos) << summary;
  EXPECT_NE(summary.find("\"how\": \"operator_ended\""), std::string::npos) << summary;
  fs::remove_all(dir);
}

TEST(ViewerMmt, NoRemoteStationAtTheAddressIsRefusedByName) {
  const session::Scenario sc = session::load_scenario(kTrench);
  DriverOptions o;
  o.paced = false;
  o.mmt = true;
  o.remote = "127.0.0.1:1";  // nothing listens there
  o.key = net::insecure_key();
  o.connect_timeout_s = 0.3;
  try {
    LoopDriver d(sc, viewer_settings(sc.haptics), o, nullptr);
    FAIL() << "connected to nobody";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--remote: no remote station answered at 127.0.0.1:1"),
              std::string::npos)
        << e.what();
  }
}

// The command line: --remote needs --mmt, and an address it can read. Both
// are bad option values, checked after parsing: exit 1 (bad input) as in
// every terracut program (apps/exit_codes.hpp), naming the option.
TEST(ViewerMmt, BadRemoteOptionsExitOneNamingTheOption) {
  const fs::path dir =
      fs::temp_directory_path() / ("terracut_viewer_mmt_cli_" + std::to_string(getpid()));
  fs::create_directories(dir);
  const auto refused = [&](std::vector<std::string> args, const std::string& expect) {
    args.insert(args.begin(), {TERRACUT_VIEWER_BIN, kTrench.string()});
    const pid_t pid = test::spawn(args, dir / "out.txt", dir / "err.txt");
    ASSERT_GT(pid, 0);
    EXPECT_EQ(test::wait_exit(pid, 30.0), 1) << args[2];
    const std::string err = slurp(dir / "err.txt");
    EXPECT_NE(err.find(expect), std::string::npos) << err;
  };
  refused({"--remote", "127.0.0.1:47100", "--headless"}, "--remote: needs --mmt");
  refused({"--mmt", "--remote", "nowhere", "--headless"}, "--remote");
  refused({"--mmt", "--remote", "127.0.0.1:99999", "--headless"}, "--remote");
  fs::remove_all(dir);
}

}  // namespace
