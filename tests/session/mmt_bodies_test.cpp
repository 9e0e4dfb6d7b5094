// Model-mediated teleoperation with rigid bodies in the remote world: the
// sensed patches carry the tops of the bodies a depth camera would see (and
// not those of buried ones), a body's top under the hovering tool is never
// pushed into it, and the buried rock of scenarios/mmt_hidden_rock.yaml:
// held at the start, met by the remote's blade, then seen.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "terracut/core/error.hpp"
#include "terracut/session/mmt.hpp"
#include "terracut/session/scenario.hpp"
#include "terracut/session/world.hpp"
#include "../support/scenario_text.hpp"

#ifdef TERRACUT_HAVE_BULLET
#include "terracut/bullet/bodies_listener.hpp"
#endif

namespace terracut::session {
namespace {

namespace fs = std::filesystem;

const fs::path kScenarios = fs::path(TERRACUT_SOURCE_DIR) / "scenarios";

using test::read_text;

// The trench (operator: sand, no bodies) whose remote world is the same
// sand with a box of full size `size` resting on it, centred at (x, z).
Scenario trench_with_box(const std::string& name, double x, double z, Vec3 size) {
  const fs::path dir = fs::temp_directory_path() / ("terracut_mmt_bodies_" + name);
  fs::create_directories(dir);
  std::ostringstream box;
  box << "bodies:\n  - name: box\n    shape: box\n    size_m: [" << size.x << ", " << size.y
      << ", " << size.z << "]\n    mass_kg: 20\n    position_m: [" << x << ", "
      << 0.3 + 0.5 * size.y << ", " << z << "]\n\ncuts:";
  std::ofstream(dir / "remote.yaml")
      << test::replace(read_text(kScenarios / "mmt_trench_clay.yaml"), "cuts:", box.str());
  Scenario sc = load_scenario(kScenarios / "mmt_trench_clay.yaml");
  sc.mmt->remote_scenario = dir / "remote.yaml";
  sc.mmt->remote_soil.reset();
  return sc;
}

void run_for(MmtRun& run, double seconds) {
  const std::int64_t end = std::llround(seconds * run.operator_station().rate_hz());
  while (run.ticks_run() < end) run.tick();
}

TEST(MmtBodies, SensedPatchesCarryTheTopOfAnUncoveredBox) {
#ifndef TERRACUT_HAVE_BULLET
  GTEST_SKIP() << "built without Bullet";
#else
  // The operator's tool waits 5 cm above the sand at z = 0.75 for the first
  // second; the box (0.2 m square, 0.1 m high, top at y = 0.4) lies 0.35 m
  // ahead of it, inside the sensed square (half side 0.5 m here) and outside
  // the exclusion around the edge.
  Scenario sc = trench_with_box("top", 0.0, 0.4, {0.2, 0.1, 0.2});
  sc.mmt->sense_radius_m = 0.5;
  MmtRun run(sc);
  // A round trip (0.1 s), a sensing period (0.05 s) and the blend (0.1 s).
  run_for(run, 0.6);
  EXPECT_GT(run.operator_station().counters().patches, 0);
  const HeightGrid& g = run.operator_station().simulation().grid();
  const double cell = g.spec().cell_x_m();
  // The box's top rests at 0.4 within Bullet's settling (a fraction of a
  // millimetre) and the blend's last tick: a tenth of a cell.
  const double tol = 0.1 * cell;
  int on = 0, off = 0;
  for (int row = 0; row < g.rows(); ++row)
    for (int col = 0; col < g.cols(); ++col) {
      const double dx = std::fabs(g.sample_x(col)), dz = std::fabs(g.sample_z(row) - 0.4);
      const float h = g.height(col, row);
      if (dx < 0.1 - cell && dz < 0.1 - cell) {  // a cell inside the footprint
        EXPECT_NEAR(h, 0.4, tol) << "col " << col << " row " << row;
        ++on;
      } else if (dx > 0.1 + cell || dz > 0.1 + cell) {  // a cell outside: the soil
        EXPECT_NEAR(h, 0.3, 1e-5) << "col " << col << " row " << row;
        ++off;
      }
    }
  EXPECT_GE(on, 64);  // 8 x 8 samples
  EXPECT_GT(off, 9000);
#endif
}

TEST(MmtBodies, ABodyTopUnderTheHoveringToolIsNotPushedIntoIt) {
#ifndef TERRACUT_HAVE_BULLET
  GTEST_SKIP() << "built without Bullet";
#else
  // A 0.1 m cube right beside the end of the waiting tool (the blade spans
  // x in [-0.2, 0.2] at z = 0.75, its edge at y = 0.35; the cube x in
  // [0.23, 0.33]), its top 5 cm above the edge, within the exclusion around
  // the edge: blending it in would raise the terrain there above the edge.
  Scenario sc = trench_with_box("under", 0.28, 0.75, {0.1, 0.1, 0.1});
  MmtRun run(sc);
  run_for(run, 0.9);
  EXPECT_GT(run.operator_station().counters().patches, 0);
  for (const OperatorRecord& r : run.operator_station().records()) {
    ASSERT_EQ(r.contact_length_m, 0.0) << "t = " << r.t_s;
    ASSERT_EQ(length(r.force_device_n), 0.0) << "t = " << r.t_s;
  }
  // The samples near the edge wait below it (the whole cube is within the
  // exclusion); at the remote the cube has not moved (the plate is clear of it).
  const bullet::BodyState cube =
      run.remote_station().rig().world().bodies_listener()->world().body_state(0);
  EXPECT_NEAR(cube.position_m.x, 0.28, 1e-3);
  EXPECT_NEAR(cube.position_m.z, 0.75, 1e-3);
  const HeightGrid& g = run.operator_station().simulation().grid();
  for (int row = 0; row < g.rows(); ++row)
    for (int col = 0; col < g.cols(); ++col)
      ASSERT_LT(g.height(col, row), 0.35f) << "x " << g.sample_x(col) << " z " << g.sample_z(row);
#endif
}

TEST(MmtBodies, BuriedBodiesAreCheckedAgainstTheTerrainWithTheirLine) {
  const std::string text = read_text(kScenarios / "rock_buried.yaml");
  const fs::path file = kScenarios / "rock_buried.yaml";
  EXPECT_NO_THROW(parse_scenario(text, file));
  // Its top (0.28 + 0.03) above the sand at 0.3: not buried.
  const std::string high = test::replace(text, "position_m: [0.0, 0.18, -0.075]",
                                         "position_m: [0.0, 0.21, -0.075]");
  try {
    parse_scenario(high, file);
    FAIL() << "accepted a buried body above the soil";
  } catch (const InputError& e) {
    const std::string where =
        file.string() + ":" + std::to_string(test::line_of(high, "buried: true")) +
        ": bodies[0].buried: ";
    EXPECT_EQ(std::string(e.what()).rfind(where, 0), 0u) << e.what();
    EXPECT_NE(std::string(e.what()).find("is not under the soil"), std::string::npos) << e.what();
  }
  // Soil that flows is refused with a buried body, by the same line.
  const std::string flow = test::replace(text, "soil:\n", "soil:\n  model: flow\n");
  try {
    parse_scenario(flow, file);
    FAIL() << "accepted a buried body in flowing soil";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(":" + std::to_string(test::line_of(flow, "buried: true")) +
                                         ": bodies[0].buried: a buried body needs soil.model vanish"),
              std::string::npos)
        << e.what();
  }
  // Not a boolean.
  try {
    parse_scenario(test::replace(text, "buried: true", "buried: deep"), file);
    FAIL() << "accepted buried: deep";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bodies[0].buried"), std::string::npos) << e.what();
  }
}

#ifdef TERRACUT_HAVE_BULLET
// The rock of the remote world of mmt_hidden_rock.
bullet::BodyState remote_rock(MmtRun& run) {
  return run.remote_station().rig().world().bodies_listener()->world().body_state(0);
}
#endif

TEST(MmtBodies, HiddenRockIsHeldThenMetThenSeen) {
#ifndef TERRACUT_HAVE_BULLET
  GTEST_SKIP() << "built without Bullet";
#else
  // Without the scenario's arm limit: the plate shoves the rock up out of
  // its pit and it lies still on the sand, where the camera sees it (with
  // the limit it jams in its pit: TheRemoteArmStallsAgainstTheHiddenRock...).
  Scenario sc = load_scenario(kScenarios / "mmt_hidden_rock.yaml");
  sc.mmt->arm_force_limit_n = 1e7;
  MmtRun run(sc);
  const Vec3 start = remote_rock(run).position_m;
  // Held under the sand while the blade waits, plunges and cuts up to it:
  // the rock does not move at all (Bullet does not see it until it is reached).
  run_for(run, 2.5);
  EXPECT_TRUE(remote_rock(run).held);
  EXPECT_EQ(remote_rock(run).position_m.x, start.x);
  EXPECT_EQ(remote_rock(run).position_m.y, start.y);
  EXPECT_EQ(remote_rock(run).position_m.z, start.z);
  run.run();
  EXPECT_FALSE(remote_rock(run).held);
  const MmtSummary s = run.summary();

  // The remote's force, time-aligned with the operator's (the remote acts on
  // a command one delay later): up to the rock both cut the same sand; at the
  // rock the remote's force jumps and the local model's does not.
  const auto& op = run.operator_station().records();
  const auto& rm = run.remote_station().records();
  const std::size_t d = std::size_t(std::llround(sc.mmt->to_remote.delay_s * 1000.0));
  double before = 0.0, at = 0.0;
  for (std::size_t i = 0; i + d < rm.size() && i < op.size(); ++i) {
    const double err = length(op[i].force_world_n - rm[i + d].force_world_n);
    if (op[i].t_s > 1.8 && op[i].t_s < 2.5) before = std::max(before, err);
    if (op[i].t_s > 2.5 && op[i].t_s < 3.5) at = std::max(at, err);
  }
  EXPECT_GT(at, 5.0 * before) << "before " << before << " at " << at;
  EXPECT_GT(s.force_error_max_mmt_n, 5.0 * before);

  // The patches show the rock's top where it lies at the end, in the
  // operator's model: the samples a cell inside its footprint.
  const bullet::BodyState rock = remote_rock(run);
  const HeightGrid& g = run.operator_station().simulation().grid();
  const double cell = g.spec().cell_x_m();
  const double top = rock.position_m.y + 0.1;  // the block is 0.2 m high
  int seen = 0;
  for (int row = 0; row < g.rows(); ++row)
    for (int col = 0; col < g.cols(); ++col) {
      const double dx = std::fabs(g.sample_x(col) - rock.position_m.x);
      const double dz = std::fabs(g.sample_z(row) - rock.position_m.z);
      if (dx < 0.15 - cell && dz < 0.125 - cell) {
        EXPECT_NEAR(g.height(col, row), top, 0.1 * cell) << "col " << col << " row " << row;
        ++seen;
      }
    }
  EXPECT_GT(seen, 60);
#endif
}

TEST(MmtBodies, TheOperatorSeesTheRockWhereItLiesAfterTheArmLeftIt) {
#ifndef TERRACUT_HAVE_BULLET
  GTEST_SKIP() << "built without Bullet";
#else
  // With the scenario's 5 kN arm the rising plate tips the rock, which
  // settles after the arm has gone on: the remote's camera must report
  // where bodies moved, not only round the arm and where soil changed. At
  // the end the operator's model shows the rock's top as the remote's
  // camera sees it, within 1 mm (no deadband in this scenario; the rock may
  // still settle a fraction of a millimetre after the last 50 ms frame).
  Scenario sc = load_scenario(kScenarios / "mmt_hidden_rock.yaml");
  ASSERT_LT(sc.mmt->arm_force_limit_n, 1e7);
  MmtRun run(sc);
  run.run();
  EXPECT_FALSE(remote_rock(run).held);
  const HeightGrid& remote = run.remote_station().simulation().grid();
  const HeightGrid& local = run.operator_station().simulation().grid();
  const Rect all{0, 0, remote.cols(), remote.rows()};
  std::vector<float> camera(std::size_t(all.area()));
  run.remote_station().rig().world().sense_heights(all, camera);
  int rock_samples = 0;
  double worst = 0.0;
  for (std::int64_t i = 0; i < all.area(); ++i) {
    if (camera[std::size_t(i)] < remote.heights()[i] + 0.01f) continue;  // soil, not the rock
    ++rock_samples;
    worst = std::max(worst, double(std::fabs(local.heights()[i] - camera[std::size_t(i)])));
  }
  EXPECT_GT(rock_samples, 50);
  EXPECT_LT(worst, 1e-3) << "over " << rock_samples << " samples of the rock's top";
#endif
}

TEST(MmtBodies, TheRemoteArmStallsAgainstTheHiddenRockAtItsLimit) {
#ifndef TERRACUT_HAVE_BULLET
  GTEST_SKIP() << "built without Bullet";
#else
  // mmt_hidden_rock with a 3 kN arm: the plate breaks the rock out of the
  // sand (its break-out force, about 0.9 kN in this sand, is under the
  // limit), pushes it into the far wall of its pit and stalls there. The
  // remote's force (soil and rock) never exceeds the limit by more than
  // the plate's momentum over a step at the arm's top speed.
  Scenario sc = load_scenario(kScenarios / "mmt_hidden_rock.yaml");
  const double limit = 3000.0;
  sc.mmt->arm_force_limit_n = limit;  // the scenario's is 5 kN
  MmtRun run(sc);
  run.run();
  const bullet::TerrainWorld& w =
      run.remote_station().rig().world().bodies_listener()->world();
  ASSERT_TRUE(w.tool_limited());
  EXPECT_FALSE(remote_rock(run).held);
  const double margin =
      w.params().tool.mass_kg * sc.mmt->follower_speed_m_per_s * run.operator_station().rate_hz();
  double peak = 0.0;
  std::int64_t stalled = 0;
  double behind = 0.0;
  // Held still against the rock (stalled, the plate moving under 1 cm/s),
  // the plate has no momentum to spend: the force is the limit, give or
  // take what the block yields in a step (a few per mille).
  double steady_peak = 0.0;
  int steady_ticks = 0;
  const std::vector<RemoteRecord>& records = run.remote_station().records();
  for (std::size_t i = 0; i < records.size(); ++i) {
    const RemoteRecord& r = records[i];
    peak = std::max(peak, length(r.force_world_n));
    if (r.stalled) ++stalled;
    behind = std::max(behind, length(r.commanded_m - r.tool_m));
    if (i >= 2 && r.stalled && records[i - 1].stalled &&
        length(records[i - 1].tool_m - records[i - 2].tool_m) * run.operator_station().rate_hz() < 0.01 &&
        length(r.tool_m - records[i - 1].tool_m) * run.operator_station().rate_hz() < 0.01) {
      steady_peak = std::max(steady_peak, length(r.force_world_n));
      ++steady_ticks;
    }
  }
  EXPECT_LE(peak, limit + margin);
  EXPECT_GT(steady_ticks, 100);
  EXPECT_GT(steady_peak, 0.9 * limit);
  EXPECT_LE(steady_peak, 1.01 * limit);
  EXPECT_GT(peak, 0.5 * limit);  // it did push at its limit
  EXPECT_GT(stalled, 100);
  EXPECT_EQ(run.summary().stalled_ticks, stalled);
  // Stalled, the arm fell behind the command (0.5 m/s) by more than its
  // own servo's lag (1.5 m/s x 20 ms x ... : a few cm).
  EXPECT_GT(behind, 0.1);
#endif
}

}  // namespace
}  // namespace terracut::session
