// Haptic sessions: scenario loading (the haptics section read by its own
// reader, line numbers kept), --device parsing, outputs.
#include "terracut/session/haptic.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "../support/input_error.hpp"
#include "../support/scenario_text.hpp"
#include "terracut/core/error.hpp"
#include "terracut/haptics/device_option.hpp"
#include "terracut/haptics/haptics_csv.hpp"

namespace terracut::session {
namespace {

namespace fs = std::filesystem;
using haptics::DeviceOption;
using haptics::parse_device_option;

namespace test {
fs::path trench_path() {
  return fs::path(TERRACUT_SOURCE_DIR) / "scenarios/trench_dry_sand.yaml";
}
const Scenario& trench() {
  static const Scenario s = load_scenario(trench_path());
  return s;
}
}  // namespace test

fs::path scratch(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("terracut_session_test_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

template <typename F>
std::string error_of(F&& f) {
  return terracut::test::input_error_of(std::forward<F>(f));
}

std::string read(const fs::path& p) { return terracut::test::read_text(p); }

TEST(Session, LoadsTheTrenchScenario) {
  const Scenario& s = test::trench();
  EXPECT_EQ(s.base.name, "trench_dry_sand");
  ASSERT_EQ(s.base.cuts.size(), 1u);
  EXPECT_EQ(s.base.cuts[0].name, "trench");
  EXPECT_EQ(s.haptics.device, haptics::DeviceKind::kSim);
  EXPECT_EQ(s.haptics.forces.cutting, CuttingModel::kEarthmoving);
}

TEST(Session, ScenarioErrorsAfterTheHapticsSectionKeepTheirLine) {
  const fs::path dir = scratch("lines");
  // An unknown top-level key after the haptics section (the file's last block).
  std::string text = read(test::trench_path()) + "blade_extra: 1\n";
  std::ofstream(dir / "broken.yaml") << text;
  const int line = int(std::count(text.begin(), text.end(), '\n'));
  const std::string e = error_of([&] { load_scenario(dir / "broken.yaml"); });
  EXPECT_NE(e.find("broken.yaml:" + std::to_string(line) + ":"), std::string::npos) << e;
  EXPECT_NE(e.find("blade_extra"), std::string::npos) << e;
  // An error inside the haptics section names it, at its line.
  std::string bad = read(test::trench_path());
  const std::size_t at = bad.find("    scale: 15");
  bad.replace(at, 13, "    scale: -1");
  std::ofstream(dir / "bad_scale.yaml") << bad;
  const int scale_line = int(std::count(bad.begin(), bad.begin() + std::ptrdiff_t(at), '\n')) + 1;
  const std::string e2 = error_of([&] { load_scenario(dir / "bad_scale.yaml"); });
  EXPECT_NE(e2.find("bad_scale.yaml:" + std::to_string(scale_line) + ": haptics.workspace.scale"),
            std::string::npos)
      << e2;
  fs::remove_all(dir);
}

TEST(Session, DeviceOption) {
  EXPECT_EQ(parse_device_option("script").kind, haptics::DeviceKind::kScript);
  EXPECT_EQ(parse_device_option("sim").kind, haptics::DeviceKind::kSim);
  const DeviceOption u = parse_device_option("udp");
  EXPECT_EQ(u.kind, haptics::DeviceKind::kUdp);
  EXPECT_FALSE(u.address && u.port);
  const DeviceOption a = parse_device_option("udp:127.0.0.1:47001");
  EXPECT_EQ(*a.address, "127.0.0.1");
  EXPECT_EQ(*a.port, 47001);
  const DeviceOption p = parse_device_option("udp:47002");
  EXPECT_FALSE(p.address);
  EXPECT_EQ(*p.port, 47002);
  const DeviceOption v6 = parse_device_option("udp:[::1]:9");
  EXPECT_EQ(*v6.address, "::1");
  EXPECT_EQ(*v6.port, 9);
  for (const char* bad : {"falcon", "sim:1", "udp:", "udp:1.2.3.4:", "udp:1.2.3.4:70000",
                          "udp:[::1]", "udp::5", "udp:host:x1"})
    EXPECT_NE(error_of([&] { parse_device_option(bad); }).find("--device"), std::string::npos)
        << bad;
}

TEST(Session, RefusesWhatCannotRun) {
  const Scenario& in = test::trench();
  SessionOptions o;
  o.device = haptics::DeviceKind::kUdp;
  o.clock = ClockMode::kFake;
  EXPECT_NE(error_of([&] { HapticSession s(in, o); }).find("--clock fake"), std::string::npos);
  Scenario other = in;
  other.haptics.cut = "no_such_cut";
  EXPECT_NE(error_of([&] { HapticSession s(other, SessionOptions{}); }).find("haptics.cut: no cut named"),
            std::string::npos);
  SessionOptions d;
  d.duration_s = -1.0;
  EXPECT_NE(error_of([&] { HapticSession s(in, d); }).find("--duration"), std::string::npos);
}

TEST(Session, ScriptSessionWritesConsistentOutputs) {
  SessionOptions o;
  o.device = haptics::DeviceKind::kScript;
  HapticSession session(test::trench(), o);
  EXPECT_EQ(session.clock(), ClockMode::kFake);
  session.run();
  const fs::path dir = scratch("outputs");
  session.write_outputs(dir);

  // haptics.csv: the documented header and one row per tick.
  std::ifstream csv(dir / "haptics.csv");
  std::string header, line;
  std::getline(csv, header);
  EXPECT_EQ(header, haptics::kHapticsCsvColumns);
  const int columns = int(std::count(header.begin(), header.end(), ',')) + 1;
  int rows = 0, clamped = 0, rate_limited = 0;
  while (std::getline(csv, line)) {
    ++rows;
    ASSERT_EQ(int(std::count(line.begin(), line.end(), ',')) + 1, columns) << line;
    // Columns 25 and 26 are clamped and rate_limited.
    std::stringstream ss(line);
    std::string cell;
    for (int c = 0; std::getline(ss, cell, ','); ++c) {
      if (c == 24) clamped += cell == "1";
      if (c == 25) rate_limited += cell == "1";
    }
  }
  const double duration =
      test::trench().base.cuts[0].duration_s() + test::trench().haptics.settle_s;
  EXPECT_EQ(rows, std::lround(duration * 1000.0));

  // summary.json agrees with the log and the loop.
  const nlohmann::json j = nlohmann::json::parse(read(dir / "summary.json"));
  EXPECT_EQ(j["device"], "script");
  EXPECT_EQ(j["clock"], "fake");
  EXPECT_EQ(j["ticks"].get<int>(), rows);
  EXPECT_EQ(j["safety"]["clamped"].get<int>(), clamped);
  EXPECT_EQ(j["safety"]["rate_limited"].get<int>(), rate_limited);
  EXPECT_EQ(j["rejected_packets"]["total"].get<int>(), 0);
  EXPECT_EQ(j["timing_us"]["missed_deadlines"].get<int>(), 0);
  EXPECT_NEAR(j["timing_us"]["period"]["p50"].get<double>(), 1000.0, 1e-9);
  EXPECT_GT(j["cutting"]["removed_volume_m3"].get<double>(), 0.0);
  EXPECT_LE(j["forces"]["max_device_force_n"].get<double>(), 8.0);
  EXPECT_GT(j["forces"]["max_device_force_n"].get<double>(), 0.5);
  EXPECT_TRUE(j["warnings"].is_array());
  fs::remove_all(dir);
}

TEST(Session, SimSessionReportsTheHand) {
  SessionOptions o;
  o.clock = ClockMode::kFake;
  HapticSession session(test::trench(), o);
  session.run();
  const nlohmann::json j = nlohmann::json::parse(session.summary_json());
  EXPECT_EQ(j["device"], "sim");
  EXPECT_LT(j["device_stats"]["hand_rendered_work_j"].get<double>(), 0.0);  // the soil took energy
  EXPECT_GT(j["device_stats"]["hand_max_tracking_error_m"].get<double>(), 0.0);
}

// The world force's magnitude in the horizontal plane, averaged over the
// records with t in [t0, t1).
double mean_push_force(const std::vector<haptics::LoopRecord>& records, double t0, double t1) {
  double sum = 0.0;
  int n = 0;
  for (const haptics::LoopRecord& r : records)
    if (r.t_s >= t0 && r.t_s < t1) {
      sum += std::hypot(r.force_world_n.x, r.force_world_n.z);
      ++n;
    }
  return n > 0 ? sum / n : 0.0;
}

TEST(Session, TheForceGrowsWithThePileTheBladePushes) {
  // scenarios/push_pile.yaml: a blade pushes a 5 cm cut 1 m through dry sand
  // that flows. The pile ahead weighs on the failure wedge (a surcharge), so
  // the force at the end of the push exceeds the force at its start; with
  // the soil vanishing (the paper's model) it stays as it was.
  const Scenario flow = load_scenario(fs::path(TERRACUT_SOURCE_DIR) / "scenarios/push_pile.yaml");
  ASSERT_EQ(flow.base.soil.model, SoilModel::kFlow);
  Scenario vanish = flow;
  vanish.base.soil.model = SoilModel::kVanish;
  SessionOptions o;
  o.clock = ClockMode::kFake;
  HapticSession a(flow, o), b(vanish, o);
  a.run();
  b.run();
  // The push runs from t = 1.4 s to 3.4 s at constant depth and speed.
  const std::vector<haptics::LoopRecord> ra = a.loop().records(), rb = b.loop().records();
  const double flow_start = mean_push_force(ra, 1.6, 2.0), flow_end = mean_push_force(ra, 3.0, 3.4);
  const double vanish_start = mean_push_force(rb, 1.6, 2.0), vanish_end = mean_push_force(rb, 3.0, 3.4);
  EXPECT_GT(flow_start, 0.0);
  EXPECT_GT(flow_end, 1.1 * flow_start);
  EXPECT_NEAR(vanish_end, vanish_start, 0.02 * vanish_start);
  EXPECT_GT(flow_end, 1.1 * vanish_end);
  // Nothing vanished in the flowing run.
  EXPECT_NEAR(a.loop().simulation().grid().volume_m3(), 2.0 * 2.0 * 0.3, 1e-5);
}

TEST(Session, TheOperatorFeelsTheWeightOfTheBucketsLoad) {
  // scenarios/bucket_cycle.yaml: the bucket scoops, lifts out and carries
  // its load sideways (1.9-3.4 s: out of the sand, no cutting force), then
  // dumps it (4.0 s on). While it carries, the force is the load's weight,
  // straight down: unit weight x volume.
  const Scenario sc = load_scenario(fs::path(TERRACUT_SOURCE_DIR) / "scenarios/bucket_cycle.yaml");
  ASSERT_TRUE(sc.base.blade.bucket.enabled());
  SessionOptions o;
  o.clock = ClockMode::kFake;
  HapticSession s(sc, o);
  s.run();
  const Simulation& sim = s.loop().simulation();
  const double unit_weight = sim.params().soil.material.unit_weight_n_per_m3;
  const double initial_m3 = 2.0 * 2.0 * 0.3;
  double carry_y = 0.0, carry_xz = 0.0;
  int n = 0;
  double after_dump_y = 0.0;
  for (const haptics::LoopRecord& r : s.loop().records()) {
    if (r.t_s > 2.6 && r.t_s < 3.3) {
      carry_y += r.force_world_n.y;
      carry_xz = std::max(carry_xz, std::hypot(r.force_world_n.x, r.force_world_n.z));
      ++n;
    }
    if (r.t_s > 4.8) after_dump_y = r.force_world_n.y;
  }
  ASSERT_GT(n, 100);
  // All of it poured by the end, and nothing lost.
  EXPECT_EQ(sim.last().soil.bucket_load_m3, 0.0);
  EXPECT_NEAR(sim.grid().volume_m3(), initial_m3, 1e-5);
  // 0.4 m x 3.5 cm x 0.6 m of full depth scooped (half the plunge's ramp in it), at most the struck 0.0090 m^3.
  const double weight = -carry_y / n;
  EXPECT_GT(weight, unit_weight * 0.0084 * 0.98);
  EXPECT_LT(weight, unit_weight * 0.0090 * 1.02);
  EXPECT_LT(carry_xz, 0.01 * weight);  // straight down
  EXPECT_NEAR(after_dump_y, 0.0, 1e-9);  // empty, out of the sand: nothing
}

TEST(Session, TheBucketsLoadResistsItsAcceleration) {
  // scenarios/bucket_cycle.yaml: out of the sand, the bucket's lift (0.67 m/s
  // up, 1.9-2.4 s) turns into its carry (0.6 m/s along +X, 2.4-3.4 s). The
  // load's inertia is all the horizontal force there, and its impulse over
  // the turn is the load's mass x its change of velocity, whatever the
  // filters: -m (0.6, -0.67, 0) N s, m = weight / g.
  const Scenario sc = load_scenario(fs::path(TERRACUT_SOURCE_DIR) / "scenarios/bucket_cycle.yaml");
  SessionOptions o;
  o.clock = ClockMode::kFake;
  HapticSession s(sc, o);
  s.run();
  double weight = 0.0, impulse_x = 0.0, impulse_y = 0.0, impulse_z = 0.0, peak_x = 0.0;
  int n = 0;
  for (const haptics::LoopRecord& r : s.loop().records()) {
    if (r.t_s > 2.6 && r.t_s < 3.3) weight -= r.force_world_n.y, ++n;
  }
  ASSERT_GT(n, 100);
  weight /= n;
  const double dt = 1.0 / sc.base.rate_hz;
  for (const haptics::LoopRecord& r : s.loop().records()) {
    if (!(r.t_s > 2.3 && r.t_s < 3.3)) continue;
    impulse_x += r.force_world_n.x * dt;
    impulse_y += (r.force_world_n.y + weight) * dt;
    impulse_z += r.force_world_n.z * dt;
    peak_x = std::min(peak_x, r.force_world_n.x);
  }
  const double mass = weight / haptics::HapticLoop::kGravityM_s2;
  EXPECT_GT(mass, 10.0);  // about 0.0084 m^3 of dry sand
  EXPECT_NEAR(impulse_x, -mass * 0.6, 1e-3 * mass * 0.6);
  EXPECT_NEAR(impulse_y, mass * (0.6 - 0.265) / 0.5, 1e-3 * mass);
  EXPECT_NEAR(impulse_z, 0.0, 1e-9);
  // Spread over the filter's time constant, not a single tick.
  EXPECT_LT(-peak_x, mass * 0.6 * 2.0 * std::numbers::pi * haptics::HapticLoop::kAccelerationCutoffHz * 1.01);
}

}  // namespace
}  // namespace terracut::session
