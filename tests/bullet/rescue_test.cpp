// scenarios/rescue.yaml end to end: Simulation + TerrainWorld over the whole
// sequence, writing bodies.csv. The blocks drop and tip where the soil under
// them is cut, the debris is pushed by the plate, the other bodies stay put.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <filesystem>
#include <fstream>

#include "rescue_runner.hpp"

namespace terracut::test {
namespace {

// Angle between the body's local +Y axis and the world's +Y, degrees.
double tilt_deg(const Quat& q) {
  const Vec3 up = rotate(q, {0.0, 1.0, 0.0});
  return std::acos(std::clamp(up.y, -1.0, 1.0)) * 180.0 / std::numbers::pi;
}

int index_of(const BodiesRun& run, const std::string& name) {
  for (std::size_t i = 0; i < run.bodies.size(); ++i)
    if (run.bodies[i].name == name) return int(i);
  ADD_FAILURE() << "no body " << name;
  return 0;
}

// The run takes a few seconds, so it is done once and every check below
// reads it (one test: ctest runs each test in its own process).
class Rescue {
 public:
  Rescue()
      : file_(load_with_bodies(std::filesystem::path(TERRACUT_SOURCE_DIR) /
                               "scenarios/rescue.yaml")),
        input_(file_.base),
        dir_(std::filesystem::temp_directory_path() /
             ("terracut_rescue_" + std::to_string(::getpid()))),
        run_(run_with_bodies(file_, dir_)) {}
  ~Rescue() { std::filesystem::remove_all(dir_); }

  void writes_bodies_csv();
  void slab_drops_by_the_cut_depth_and_tips_on_the_way();
  void undercut_block_tips_into_the_trench();
  void plate_pushes_the_debris_and_feels_it();
  void bodies_away_from_the_cuts_stay_put();

 private:
  // The soil top and the lowest edge height of a cut, from the scenario itself.
  double soil_top() const { return input_.generator->plane.height_m; }
  double lowest_keyframe_y(const std::string& cut) const {
    const Motion& m = input_.cuts[std::size_t(input_.find_cut(cut))];
    double y = INFINITY;
    for (const Keyframe& k : m.keyframes) y = std::min(y, k.pose.position_m.y);
    return y;
  }
  // Resting tolerance: the bodies' collision margin (see terrain_world_test).
  static double tol() { return bullet::TerrainWorldParams{}.convex_margin_m; }

  BodiesScenario file_;
  const io::Scenario& input_;
  std::filesystem::path dir_;
  BodiesRun run_;
};

void Rescue::writes_bodies_csv() {
  const BodiesRun& run = run_;
  EXPECT_EQ(run.bodies.size(), 5u);
  EXPECT_EQ(run.csv_rows, (run.steps + 1) * std::int64_t(run.bodies.size()));
  std::ifstream in(dir_ / "bodies.csv");
  std::string header;
  std::getline(in, header);
  EXPECT_EQ(header, bullet::kBodiesCsvColumns);
  EXPECT_EQ(run.bounds.clamped_total, 0);
}

void Rescue::slab_drops_by_the_cut_depth_and_tips_on_the_way() {
  const BodiesRun& run = run_;
  const int slab = index_of(run, "slab_a");
  const double depth = soil_top() - lowest_keyframe_y("undercut_a");
  const bullet::BodyState& start = run.state(0, slab);
  const bullet::BodyState& end = run.state(run.steps, slab);
  EXPECT_NEAR(end.position_m.y, start.position_m.y - depth, tol());
  double lowest = INFINITY, most_tilt = 0.0;
  for (std::int64_t k = 0; k <= run.steps; ++k) {
    lowest = std::min(lowest, run.state(k, slab).position_m.y);
    most_tilt = std::max(most_tilt, tilt_deg(run.state(k, slab).orientation));
  }
  EXPECT_GT(lowest, start.position_m.y - depth - tol());  // never through the new floor
  EXPECT_GT(most_tilt, 10.0);                               // it tipped as the edge passed
  EXPECT_LT(tilt_deg(end.orientation), 2.0);                // and lies flat at the end
}

void Rescue::undercut_block_tips_into_the_trench() {
  const BodiesRun& run = run_;
  const int block = index_of(run, "block_b");
  const bullet::BodyState& end = run.state(run.steps, block);
  // Resting on what is under it: the trench's floor, and with soil that
  // flows the sand that slid back into the trench. Its lowest point lies
  // between the lowest and the highest soil under its box, to the margin.
  const Vec3 half = half_extents_m(run.bodies[std::size_t(block)]);
  Vec3 reach{};  // the world half extents of its box
  for (const Vec3 axis : {Vec3{1, 0, 0}, Vec3{0, 1, 0}, Vec3{0, 0, 1}}) {
    const Vec3 a = rotate(end.orientation, axis);
    const double e = dot(axis, Vec3{half.x, half.y, half.z});
    reach = reach + Vec3{std::fabs(a.x) * e, std::fabs(a.y) * e, std::fabs(a.z) * e};
  }
  const double lowest = end.position_m.y - reach.y - input_.origin_m.y;
  const auto [soil_lo, soil_hi] =
      run.heights_under(end.position_m.x - reach.x, end.position_m.x + reach.x,
                        end.position_m.z - reach.z, end.position_m.z + reach.z);
  const double floor = lowest_keyframe_y("trench_b");
  EXPECT_GE(soil_lo, floor - tol());  // the cut reached the trench's floor, not below
  EXPECT_GT(lowest, soil_lo - tol());
  EXPECT_LT(lowest, soil_hi + tol());
  if (input_.soil.model == SoilModel::kVanish) {
    EXPECT_NEAR(lowest, floor, tol());  // the trench's floor, bare
  }
  // On its side in the trench: its 0.2 m X edge is now vertical, to 5
  // degrees on a level floor, and further by the slope of what it rests on.
  // On the bare floor (vanish) that is the soil's mean slope across its box;
  // where the soil flows the sand that slid back in lines the trench as a
  // channel whose walls stand at up to the angle of repose, and the block
  // may lie on one wall: its mean slope across the box understates it.
  const double slope_deg =
      input_.soil.model == SoilModel::kFlow
          ? input_.soil.material.repose_deg
          : std::atan((soil_hi - soil_lo) / (2.0 * std::max(reach.x, reach.z))) * 180.0 / std::numbers::pi;
  EXPECT_NEAR(tilt_deg(end.orientation), 90.0, 5.0 + slope_deg);
  EXPECT_LT(end.position_m.x, run.state(0, block).position_m.x);  // towards the trench (-X)
}

void Rescue::plate_pushes_the_debris_and_feels_it() {
  const BodiesRun& run = run_;
  const int debris = index_of(run, "debris_d");
  const BodySpec& spec = run.bodies[std::size_t(debris)];
  // The plate's front face ends at z = 1.8 + thickness / 2; the debris ahead
  // of it, then sliding on by at most v^2 / (2 mu g) at the push speed.
  const double thickness = bullet::TerrainWorldParams{}.tool.thickness_m;
  const double face = 1.8 + 0.5 * thickness;
  const double speed = 0.6 / 2.0;
  const double mu = spec.friction * bullet::TerrainWorldParams{}.terrain_friction;
  const double slide = speed * speed / (2.0 * mu * 9.81);
  const double z_end = run.state(run.steps, debris).position_m.z;
  EXPECT_GT(z_end, face + 0.5 * spec.size_m.z - tol());
  EXPECT_LT(z_end, face + 0.5 * spec.size_m.z + slide + tol());
  // While pushing, the force on the plate points back (-Z).
  const int push = [&] {
    for (std::size_t k = 0; k < input_.sequence.size(); ++k)
      if (input_.cuts[std::size_t(input_.sequence[k])].name == "push_d")
        return int(k);
    return -1;
  }();
  double fz = 0.0;
  int touching = 0;
  for (std::int64_t k = 0; k <= run.steps; ++k) {
    if (run.sequence_index[std::size_t(k)] != push) continue;
    if (run.tool_force_n[std::size_t(k)].z != 0.0) {
      fz += run.tool_force_n[std::size_t(k)].z;
      ++touching;
    }
  }
  ASSERT_GT(touching, 500);  // (returns from this check only)
  EXPECT_LT(fz / touching, 0.0);
}

void Rescue::bodies_away_from_the_cuts_stay_put() {
  const BodiesRun& run = run_;
  for (const char* name : {"rock_c", "post_e"}) {
    const int b = index_of(run, name);
    const Vec3 d = run.state(run.steps, b).position_m - run.state(0, b).position_m;
    // Bullet's resting jitter before the body sleeps is well under a fifth of the margin.
    EXPECT_LT(length(d), 0.2 * tol()) << name;
    EXPECT_LT(tilt_deg(run.state(run.steps, b).orientation), 0.5) << name;
    EXPECT_FALSE(run.state(run.steps, b).active) << name << " should be asleep";
  }
}

TEST(Rescue, EndToEnd) {
  Rescue rescue;
  {
    SCOPED_TRACE("bodies.csv");
    rescue.writes_bodies_csv();
  }
  {
    SCOPED_TRACE("slab_a drops by the cut depth and tips on the way");
    rescue.slab_drops_by_the_cut_depth_and_tips_on_the_way();
  }
  {
    SCOPED_TRACE("block_b tips into the trench");
    rescue.undercut_block_tips_into_the_trench();
  }
  {
    SCOPED_TRACE("the plate pushes debris_d and feels it");
    rescue.plate_pushes_the_debris_and_feels_it();
  }
  {
    SCOPED_TRACE("bodies away from the cuts stay put");
    rescue.bodies_away_from_the_cuts_stay_put();
  }
}

}  // namespace
}  // namespace terracut::test
