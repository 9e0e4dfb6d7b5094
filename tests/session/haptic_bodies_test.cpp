// The rigid bodies in a haptic session (the world's Bullet listener)
// on scenarios/rock_push.yaml, with the script device on the fake clock
// (deterministic): the blade cuts a 4 cm trench along -Z and its plate runs
// into a 40 kg block resting on the sand. Checked against the same session
// without the block: before the plate reaches it, nothing differs; while the
// plate pushes it, the world force on the tool gains a component against the
// motion equal to the block's sliding friction (mu m g), and the device feels
// it scaled by force_scale; bodies.csv and summary.json follow the block; the
// viewer's frames carry its pose.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

#include "terracut/haptics/haptics_csv.hpp"
#include "terracut/session/haptic.hpp"

#ifdef TERRACUT_HAVE_BULLET
#include "terracut/bullet/terrain_world.hpp"
#endif

namespace terracut::session {
namespace {

namespace fs = std::filesystem;

#ifdef TERRACUT_HAVE_BULLET

const Scenario& rock_scenario() {
  static const Scenario s = load_scenario(
      fs::path(TERRACUT_SOURCE_DIR) / "scenarios/rock_push.yaml");
  return s;
}

std::string slurp(const fs::path& path) {
  std::ifstream f(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

// One session of the rock scenario (script device, fake clock), with or
// without its bodies, outputs in `dir`; with the scenario's soil (flow) or
// soil that vanishes.
struct RockRun {
  std::vector<haptics::LoopRecord> records;
  double max_body_force_n = 0.0;
  std::string summary;
  bool have_frame = false;
  haptics::ViewFrame frame;  // the newest published frame
};

RockRun run_rock(bool with_bodies, const fs::path& dir, bool vanish = false) {
  Scenario input = rock_scenario();
  if (!with_bodies) input.bodies.clear();
  if (vanish) input.base.soil.model = SoilModel::kVanish;
  fs::create_directories(dir);
  SessionOptions so;
  so.device = haptics::DeviceKind::kScript;
  so.clock = ClockMode::kFake;
  so.realtime = false;
  const io::Scenario& sc = input.base;
  HeightGrid grid(io::grid_spec(sc), io::build_initial_heights(sc));
  haptics::SnapshotExchange exchange(grid);
  so.snapshot = &exchange;
  if (with_bodies) so.bodies_csv = dir / "bodies.csv";
  RockRun out;
  {
    HapticSession session(input, so);
    session.run();
    session.write_outputs(dir);
    out.records = session.loop().records();
    out.max_body_force_n = session.loop().max_body_force_n();
  }
  out.summary = slurp(dir / "summary.json");
  if (const haptics::ViewFrame* f = exchange.acquire()) {
    out.have_frame = true;
    out.frame = *f;
  }
  return out;
}

class RockPush : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("terracut_rock_push_" + std::to_string(getpid()));
    fs::remove_all(dir_);
    with_ = new RockRun(run_rock(true, dir_ / "with"));
    without_ = new RockRun(run_rock(false, dir_ / "without"));
    vanish_with_ = new RockRun(run_rock(true, dir_ / "vanish_with", true));
    vanish_without_ = new RockRun(run_rock(false, dir_ / "vanish_without", true));
  }
  static void TearDownTestSuite() {
    delete with_;
    delete without_;
    delete vanish_with_;
    delete vanish_without_;
    fs::remove_all(dir_);
  }
  static fs::path dir_;
  static RockRun* with_;
  static RockRun* without_;
  // The same with soil that vanishes: there the rock leaves the terrain
  // alone (with soil that flows, the pile banks against it a cell from its
  // face, and the soil ahead of the blade, so the cutting force, differs
  // from a run without it before the plate arrives).
  static RockRun* vanish_with_;
  static RockRun* vanish_without_;
};
fs::path RockPush::dir_;
RockRun* RockPush::with_ = nullptr;
RockRun* RockPush::without_ = nullptr;
RockRun* RockPush::vanish_with_ = nullptr;
RockRun* RockPush::vanish_without_ = nullptr;

// The scenario's geometry.
struct Geometry {
  BodySpec rock;
  double touch_z;     // edge z where the plate's front face meets the rock's back face
  double cut_y;       // edge height while cutting, metres
  double push_end_z;  // edge z where the push ends
  double mu_m_g;      // the rock's sliding friction force on the sand, N
  Geometry() {
    const io::Scenario& sc = rock_scenario().base;
    rock = rock_scenario().bodies.at(0);
    const bullet::TerrainWorldParams world{};
    touch_z = rock.position_m.z + 0.5 * rock.size_m.z + 0.5 * world.tool.thickness_m;
    const Motion& cut = sc.cuts.at(0);
    cut_y = cut.keyframes.at(2).pose.position_m.y;
    push_end_z = cut.keyframes.at(3).pose.position_m.z;
    EXPECT_EQ(cut.keyframes.at(3).pose.position_m.y, cut_y);
    // Bullet multiplies the two friction coefficients.
    mu_m_g = rock.friction * world.terrain_friction * rock.mass_kg * world.gravity_m_s2;
  }
};

TEST_F(RockPush, TheRockIsFeltAgainstTheMotionOnlyWhileThePlatePushesIt) {
  const Geometry g;
  const double force_scale = rock_scenario().haptics.forces.force_scale;
  const std::vector<haptics::LoopRecord>& a = vanish_with_->records;
  const std::vector<haptics::LoopRecord>& b = vanish_without_->records;
  ASSERT_EQ(a.size(), b.size());
  ASSERT_GT(a.size(), 4000u);

  int before = 0, pushing = 0, against = 0, after = 0;
  double sum_fb_z = 0.0, sum_fb_x = 0.0, sum_fd_gain = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const haptics::LoopRecord& r = a[i];
    const haptics::LoopRecord& q = b[i];
    // The script gives both runs the same path, and the rock leaves the
    // terrain alone: the force models' part is the same.
    ASSERT_EQ(r.tool.position_m.z, q.tool.position_m.z) << i;
    ASSERT_EQ(r.contact_length_m, q.contact_length_m) << i;
    EXPECT_EQ(length(q.body_force_world_n), 0.0) << i;
    const Vec3 gain = r.force_world_n - q.force_world_n;
    const double tol = 1e-9 * (1.0 + length(r.force_world_n));
    EXPECT_NEAR(gain.x, r.body_force_world_n.x, tol) << i;
    EXPECT_NEAR(gain.y, r.body_force_world_n.y, tol) << i;
    EXPECT_NEAR(gain.z, r.body_force_world_n.z, tol) << i;

    const double z = r.tool.position_m.z;
    if (z > g.touch_z + 0.002) {
      // Before the plate reaches the rock (2 mm: four steps at 0.5 m/s): no
      // force from it at all, and the device gets exactly the same.
      ++before;
      EXPECT_EQ(length(r.body_force_world_n), 0.0) << "t = " << r.t_s << ", edge z = " << z;
      EXPECT_EQ(r.force_device_n.x, q.force_device_n.x) << i;
      EXPECT_EQ(r.force_device_n.y, q.force_device_n.y) << i;
      EXPECT_EQ(r.force_device_n.z, q.force_device_n.z) << i;
    } else if (std::abs(r.tool.position_m.y - g.cut_y) < 1e-9 && z < g.touch_z - 0.05 &&
               z > g.push_end_z) {
      // Steady pushing, 0.1 s after the first touch (its impact) and until
      // the blade backs off.
      ++pushing;
      sum_fb_z += r.body_force_world_n.z;
      sum_fb_x += r.body_force_world_n.x;
      if (dot(r.body_force_world_n, r.velocity_m_per_s) < 0.0) ++against;
      sum_fd_gain += length(r.force_device_n) - length(q.force_device_n);
    } else if (r.t_s > rock_scenario().base.cuts[0].duration_s() - 0.4) {
      // Backed off and rising, then holding: the plate has left the rock.
      ++after;
      EXPECT_EQ(length(r.body_force_world_n), 0.0) << "t = " << r.t_s;
    }
  }
  EXPECT_GT(before, 2000);
  // (touch_z - 0.05 - push_end_z) / 0.5 m/s = 0.82 s of steady pushing.
  EXPECT_GT(pushing, 800);
  EXPECT_GT(after, 600);
  // The blade moves along -Z: the rock resists along +Z, by its sliding
  // friction on the sand (Bullet's contact solver: within 10 %), with next
  // to nothing sideways.
  EXPECT_GE(against, int(0.97 * pushing));
  const double mean_z = sum_fb_z / pushing;
  EXPECT_NEAR(mean_z, g.mu_m_g, 0.10 * g.mu_m_g);
  EXPECT_LT(std::abs(sum_fb_x / pushing), 0.05 * g.mu_m_g);
  // The operator feels it: the device force grows by about mu m g x
  // force_scale (less than that exactly, as the vertical cutting force adds
  // in quadrature; the safety limiter does not bind here).
  const double fd_gain = sum_fd_gain / pushing;
  EXPECT_GT(fd_gain, 0.7 * g.mu_m_g * force_scale);
  EXPECT_LT(fd_gain, 1.1 * g.mu_m_g * force_scale);

  // The peak (the first touch, an impact) is reported.
  double peak = 0.0;
  for (const haptics::LoopRecord& r : a) peak = std::max(peak, length(r.body_force_world_n));
  EXPECT_EQ(vanish_with_->max_body_force_n, peak);
  EXPECT_GT(peak, g.mu_m_g);
  EXPECT_EQ(vanish_without_->max_body_force_n, 0.0);
}

TEST_F(RockPush, WithSoilThatFlowsThePileNeitherPushesNorLiftsTheRockBeforeThePlate) {
  // The shipped scenario (soil: flow): the pile reaches the rock before the
  // plate, but its earth pressure (a few newtons) is far below the rock's
  // sliding friction, and no heightfield ramp lifts it: until the plate's
  // face meets the rock's back face the rock stays where it is, upright
  // and at its height (Bullet's resting jitter: well under the collision
  // margin).
  const Geometry g;
  const double margin = bullet::TerrainWorldParams{}.convex_margin_m;
  ASSERT_FALSE(with_->records.empty());
  std::ifstream csv(dir_ / "with" / "bodies.csv");
  std::string line;
  std::getline(csv, line);
  std::size_t k = 0;
  int rows_before = 0;
  while (std::getline(csv, line) && k < with_->records.size()) {
    double t, x, y, z, qw, qx, qy, qz;
    int body;
    char name[32];
    ASSERT_EQ(std::sscanf(line.c_str(), "%lf,%d,%31[^,],%lf,%lf,%lf,%lf,%lf,%lf,%lf", &t, &body, name,
                          &x, &y, &z, &qw, &qx, &qy, &qz),
              10);
    // Row 0 is the state before the first tick; row k + 1 after tick k.
    if (t > 0.0 && with_->records[k++].tool.position_m.z <= g.touch_z + 0.002) continue;
    ++rows_before;
    EXPECT_NEAR(z, g.rock.position_m.z, 0.2 * margin) << "t = " << t;
    EXPECT_NEAR(y, g.rock.position_m.y, 0.2 * margin) << "t = " << t;
    // Tilt: the body's Y axis from the world's, cos = 1 - 2 (qx^2 + qz^2).
    EXPECT_GT(1.0 - 2.0 * (qx * qx + qz * qz), std::cos(1.0 * std::numbers::pi / 180.0)) << "t = " << t;
  }
  EXPECT_GT(rows_before, 2000);
}

TEST_F(RockPush, BodiesCsvAndSummaryFollowTheRock) {
  const Geometry g;
  std::ifstream csv(dir_ / "with" / "bodies.csv");
  ASSERT_TRUE(csv) << "bodies.csv was not written";
  EXPECT_FALSE(fs::exists(dir_ / "without" / "bodies.csv"));
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, "t,body,name,x,y,z,qw,qx,qy,qz,vx,vy,vz");
  std::size_t rows = 0;
  double first[3] = {NAN, NAN, NAN}, last[3] = {NAN, NAN, NAN}, last_t = NAN;
  while (std::getline(csv, line)) {
    double t, x, y, z;
    int body;
    char name[32];
    ASSERT_EQ(std::sscanf(line.c_str(), "%lf,%d,%31[^,],%lf,%lf,%lf", &t, &body, name, &x, &y, &z), 6)
        << line;
    EXPECT_EQ(body, 0);
    EXPECT_EQ(std::string(name), "rock");
    if (rows == 0) {
      first[0] = x, first[1] = y, first[2] = z;
      EXPECT_EQ(t, 0.0);
    }
    last[0] = x, last[1] = y, last[2] = z;
    last_t = t;
    ++rows;
  }
  // The state before the first step, then one row per tick (every tick was stepped).
  EXPECT_EQ(rows, with_->records.size() + 1);
  EXPECT_NEAR(last_t, double(with_->records.size()) / rock_scenario().base.rate_hz, 1e-9);
  EXPECT_NEAR(first[0], g.rock.position_m.x, 1e-6);
  EXPECT_NEAR(first[1], g.rock.position_m.y, 1e-6);
  EXPECT_NEAR(first[2], g.rock.position_m.z, 1e-6);
  // Pushed along -Z by the plate's travel after the touch (plus a short
  // slide once released: v^2 / (2 mu g) = 2.7 cm at 0.5 m/s), on the sand
  // (upright, at the same height), not sideways.
  const double push = g.touch_z - g.push_end_z;
  EXPECT_LT(last[2], first[2] - push + 0.005);
  EXPECT_GT(last[2], first[2] - push - 0.05);
  EXPECT_NEAR(last[1], first[1], 0.005);
  EXPECT_NEAR(last[0], first[0], 0.02);

  // summary.json: the bodies entry with the peak force on the blade.
  const std::string& s = with_->summary;
  EXPECT_NE(s.find("\"bodies\": {"), std::string::npos) << s;
  EXPECT_NE(s.find("\"peak_tool_force_n\""), std::string::npos) << s;
  EXPECT_NE(s.find("\"csv\": \"bodies.csv\""), std::string::npos) << s;
  EXPECT_EQ(without_->summary.find("\"bodies\""), std::string::npos);
  // haptics.csv: the bodies' force columns.
  const std::string hcsv = slurp(dir_ / "with" / "haptics.csv");
  EXPECT_EQ(hcsv.rfind(haptics::kHapticsCsvColumns, 0), 0u);
  EXPECT_NE(std::string(haptics::kHapticsCsvColumns).find("fb_x,fb_y,fb_z"), std::string::npos);
}

TEST_F(RockPush, ViewerFramesCarryTheRockPose) {
  const Geometry g;
  ASSERT_TRUE(with_->have_frame);
  const haptics::ViewFrame& f = with_->frame;
  ASSERT_EQ(f.body_count, 1);
  EXPECT_EQ(f.body_total, 1);
  const haptics::ViewBody& b = f.bodies[0];
  EXPECT_EQ(b.shape, BodyShape::kBox);
  EXPECT_EQ(b.half_extents_m.x, 0.5 * g.rock.size_m.x);
  EXPECT_EQ(b.half_extents_m.y, 0.5 * g.rock.size_m.y);
  EXPECT_EQ(b.half_extents_m.z, 0.5 * g.rock.size_m.z);
  // Where bodies.csv leaves it (its last row: the same last step).
  std::ifstream csv(dir_ / "with" / "bodies.csv");
  std::string line, last;
  while (std::getline(csv, line)) last = line;
  double t, x, y, z, qw;
  int body;
  char name[32];
  ASSERT_EQ(std::sscanf(last.c_str(), "%lf,%d,%31[^,],%lf,%lf,%lf,%lf", &t, &body, name, &x, &y,
                        &z, &qw),
            7);
  EXPECT_NEAR(b.position_m.x, x, 1e-6);
  EXPECT_NEAR(b.position_m.y, y, 1e-6);
  EXPECT_NEAR(b.position_m.z, z, 1e-6);
  EXPECT_NEAR(std::abs(b.orientation.w), std::abs(qw), 1e-6);
  EXPECT_EQ(without_->frame.body_count, 0);
}

TEST_F(RockPush, TheSameSessionTwiceIsIdentical) {
  const RockRun again = run_rock(true, dir_ / "again");
  ASSERT_EQ(again.records.size(), with_->records.size());
  for (std::size_t i = 0; i < again.records.size(); ++i) {
    const haptics::LoopRecord& r = again.records[i];
    const haptics::LoopRecord& q = with_->records[i];
    ASSERT_EQ(r.body_force_world_n.x, q.body_force_world_n.x) << i;
    ASSERT_EQ(r.body_force_world_n.y, q.body_force_world_n.y) << i;
    ASSERT_EQ(r.body_force_world_n.z, q.body_force_world_n.z) << i;
    ASSERT_EQ(r.force_device_n.x, q.force_device_n.x) << i;
  }
  EXPECT_EQ(slurp(dir_ / "again" / "bodies.csv"), slurp(dir_ / "with" / "bodies.csv"));
}

TEST(BodiesEngine, IsAvailableWithBullet) { EXPECT_TRUE(bodies_available()); }

#else

TEST(BodiesEngine, NeedsBullet) {
  EXPECT_FALSE(bodies_available());
  GTEST_SKIP() << "built without Bullet: the rock-push session is not run ("
               << bodies_unavailable_message() << ")";
}

#endif

}  // namespace
}  // namespace terracut::session
