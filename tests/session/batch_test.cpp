// A batch run of a scenario: determinism of every output file, conservation
// in the outputs, the CSV layout, progress lines, and failures that leave
// nothing behind.
#include "terracut/session/batch.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <fstream>
#include <iterator>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "../support/scenario_text.hpp"
#include "terracut/core/error.hpp"
#include "terracut/io/image.hpp"
#include "terracut/io/scenario.hpp"
#include "terracut/session/scenario.hpp"

namespace terracut::session {
namespace {

using io::apply_overrides;
using io::Image;
using io::parse_scenario;
using io::read_npy;
using io::read_png;

namespace fs = std::filesystem;

// A small mound cut twice (a rolling pass, then a level pass back), plus a
// repeat of the first: 3 cuts, 24 x 20 samples, 200 Hz.
const std::string kScenario = R"(name: small
terrain:
  generator: mound
  resolution: [24, 20]
  size_m: [1.2, 1.0]
  origin_m: [-0.6, 0.0, -0.5]
  full_scale_m: 0.3
  mound: {centre_m: [0.0, 0.0], radius_m: 0.45}
representation: surface
rate_hz: 200
blade: {length_m: 0.9}
cuts:
  - name: roll
    keyframes:
      - {t_s: 0.0, position_m: [0.0, 0.25, -0.6], rotation_deg: [0, 0, 0]}
      - {t_s: 1.0, position_m: [0.05, 0.18, 0.6], rotation_deg: [0, 15, 25]}
  - name: back
    keyframes:
      - {t_s: 0.0, position_m: [0.0, 0.12, 0.6]}
      - {t_s: 0.8, position_m: [0.0, 0.12, -0.6]}
sequence: [roll, back, roll]
)";

class RunTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("terracut_run_test_" + std::to_string(getpid()) + "_" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  Scenario scenario(Representation rep = Representation::kSurface) {
    Scenario sc;
    sc.base = parse_scenario(kScenario, dir_ / "small.yaml");
    apply_overrides(sc.base, std::nullopt, rep, std::nullopt);
    return sc;
  }

  RunResult run(const Scenario& sc, const fs::path& out, bool keep = false) {
    RunOptions options;
    options.out_dir = out;
    options.keep_records = keep;
    return run_scenario(sc, options);
  }

  fs::path dir_;
};

std::string read_bytes(const fs::path& path) {
  std::ifstream f(path, std::ios::binary);
  EXPECT_TRUE(f.good()) << path;
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::istringstream in(line);
  for (std::string cell; std::getline(in, cell, ',');) out.push_back(cell);
  return out;
}

TEST(SoilWarnings, NameAnUnsettledEndAndCellsTooFarFromSquare) {
  SoilFlowParams soil;
  soil.model = SoilModel::kFlow;
  soil.material.repose_deg = 34.0;
  const GridSpec square = grid_of_cells(10, 10, 0.01);
  EXPECT_TRUE(soil_warnings(soil, square, 0).empty());
  // Still active at the end: the count and the cap are named.
  const std::vector<std::string> unsettled = soil_warnings(soil, square, 17);
  ASSERT_EQ(unsettled.size(), 1u);
  EXPECT_NE(unsettled[0].find("a backlog of 17 cells"), std::string::npos) << unsettled[0];
  EXPECT_NE(unsettled[0].find("max_pair_checks_per_step = 50000"), std::string::npos) << unsettled[0];
  // Cells of 4:1: planes to 40.9 degrees stand, against 36.6 on square cells.
  GridSpec oblong = square;
  oblong.size_z_m = 0.4;
  const std::vector<std::string> rect = soil_warnings(soil, oblong, 0);
  ASSERT_EQ(rect.size(), 1u);
  EXPECT_NE(rect[0].find("40.9 degrees"), std::string::npos) << rect[0];
  EXPECT_NE(rect[0].find("36.6 on square"), std::string::npos) << rect[0];
  // Nearly square cells (5 %) stand within half a degree of square ones: no warning.
  GridSpec near = square;
  near.size_z_m = 0.105;
  EXPECT_TRUE(soil_warnings(soil, near, 0).empty());
  // The work cap reached: the steps are counted and the cap named.
  const std::vector<std::string> capped = soil_warnings(soil, square, 0, 3);
  ASSERT_EQ(capped.size(), 1u);
  EXPECT_NE(capped[0].find("stopped it in 3 steps"), std::string::npos) << capped[0];
  // With vanish there is no soil phase to warn about.
  soil.model = SoilModel::kVanish;
  EXPECT_TRUE(soil_warnings(soil, oblong, 17).empty());
}

// A cut whose blade never crosses the terrain (seen from above) is named;
// one that crosses it, even only at its last step or only by an end of the
// blade, is not. The terrain covers x in [-0.6, 0.6], z in [-0.5, 0.5].
TEST(CutWarnings, NameACutWhoseBladeNeverCrossesTheTerrain) {
  io::Scenario sc = parse_scenario(kScenario, "small.yaml");
  EXPECT_TRUE(cut_warnings(sc).empty());
  // "roll" moved 2 m along +X: its 0.9 m blade spans x in [1.55, 2.45] (the
  // tilt shortens it), past the terrain's edge at 0.6, at every step.
  for (Keyframe& k : sc.cuts[0].keyframes) k.pose.position_m.x += 2.0;
  std::vector<std::string> w = cut_warnings(sc);
  ASSERT_EQ(w.size(), 1u);  // once, though the sequence runs it twice
  EXPECT_NE(w[0].find("cut 'roll'"), std::string::npos) << w[0];
  EXPECT_NE(w[0].find("x in [-0.6, 0.6] m"), std::string::npos) << w[0];
  // Back to 1.0 m along X: the blade's -X end (at 1.0 - 0.45 = 0.55 at the
  // untilted start) is over the terrain once the path is in its z range.
  for (Keyframe& k : sc.cuts[0].keyframes) k.pose.position_m.x -= 1.0;
  EXPECT_TRUE(cut_warnings(sc).empty()) << cut_warnings(sc)[0];
  // A path that runs beside the terrain and enters it only at its last step.
  Motion& back = sc.cuts[1];
  back.keyframes[0].pose.position_m = {0.0, 0.12, 2.0};
  back.keyframes[1].pose.position_m = {0.0, 0.12, 0.5};
  EXPECT_TRUE(cut_warnings(sc).empty());
  back.keyframes[1].pose.position_m = {0.0, 0.12, 0.51};
  w = cut_warnings(sc);
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NE(w[0].find("cut 'back'"), std::string::npos) << w[0];
}

// The warning reaches the run's result (and summary.json's "warnings"), and
// the run goes on.
TEST_F(RunTest, ACutOutsideTheTerrainIsAWarningOfTheRun) {
  Scenario sc = scenario();
  for (Keyframe& k : sc.base.cuts[1].keyframes) k.pose.position_m.z += 5.0;
  const RunResult r = run(sc, dir_ / "out");
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find("cut 'back'"), std::string::npos) << r.warnings[0];
  const nlohmann::json summary = nlohmann::json::parse(read_bytes(dir_ / "out" / "summary.json"));
  ASSERT_EQ(summary["warnings"].size(), 1u);
  EXPECT_EQ(summary["warnings"][0], r.warnings[0]);
}

TEST_F(RunTest, SameScenarioTwiceGivesBitwiseIdenticalOutputs) {
  for (Representation rep : {Representation::kSurface, Representation::kColumns}) {
    const Scenario sc = scenario(rep);
    const std::string tag(to_string(rep));
    run(sc, dir_ / (tag + "_one"));
    run(sc, dir_ / (tag + "_two"));
    for (const char* name : {"contact.csv", "height.npy", "removed.npy", "height.png",
                             "removed.png"}) {
      const std::string a = read_bytes(dir_ / (tag + "_one") / name);
      const std::string b = read_bytes(dir_ / (tag + "_two") / name);
      EXPECT_FALSE(a.empty()) << name;
      EXPECT_TRUE(a == b) << tag << " " << name << " differs between two runs";
    }
    // summary.json: identical except the "timing" object.
    auto summary = [&](const char* which) {
      nlohmann::json j = nlohmann::json::parse(read_bytes(dir_ / (tag + which) / "summary.json"));
      EXPECT_TRUE(j.contains("timing"));
      j.erase("timing");
      return j.dump();
    };
    EXPECT_EQ(summary("_one"), summary("_two")) << tag;
  }
}

TEST_F(RunTest, OutputsConserveMaterial) {
  const Scenario sc = scenario();
  const RunResult result = run(sc, dir_ / "out");
  const std::vector<float> initial = io::build_initial_heights(sc.base);
  int rows = 0;
  int cols = 0;
  const std::vector<float> height = read_npy(dir_ / "out" / "height.npy", &rows, &cols);
  const std::vector<float> removed = read_npy(dir_ / "out" / "removed.npy", &rows, &cols);
  ASSERT_EQ(rows, 20);
  ASSERT_EQ(cols, 24);
  ASSERT_EQ(height.size(), initial.size());
  // Per sample, to float rounding of the full scale (removed = initial - height in float).
  const double tol = 4.0 * 0.3 * 1.2e-7;
  double removed_sum = 0.0;
  int cut_samples = 0;
  for (std::size_t i = 0; i < initial.size(); ++i) {
    EXPECT_NEAR(double(height[i]) + removed[i], initial[i], tol) << "sample " << i;
    EXPECT_GE(height[i], 0.0f);
    EXPECT_GE(removed[i], 0.0f);
    removed_sum += removed[i];
    if (removed[i] > 0.0f) ++cut_samples;
  }
  EXPECT_GT(cut_samples, 10);  // the cuts did cut

  const double cell_area = (1.2 / 24) * (1.0 / 20);
  EXPECT_NEAR(removed_sum * cell_area, result.removed_volume_m3, initial.size() * tol * cell_area);
  EXPECT_NEAR(result.initial_volume_m3 - result.final_volume_m3, result.removed_volume_m3,
              initial.size() * tol * cell_area);
  EXPECT_LE(result.max_sample_error_m, tol);

  // The same numbers in summary.json, and the per-step volumes of contact.csv add up.
  const nlohmann::json j = nlohmann::json::parse(read_bytes(dir_ / "out" / "summary.json"));
  EXPECT_EQ(j["removed_volume_m3"].get<double>(), result.removed_volume_m3);
  EXPECT_LE(j["conservation"]["max_sample_error_m"].get<double>(), tol);
  EXPECT_NEAR(j["conservation"]["volume_error_m3"].get<double>(), 0.0,
              initial.size() * tol * cell_area);
  double csv_sum = 0.0;
  const std::vector<std::string> lines = lines_of(read_bytes(dir_ / "out" / "contact.csv"));
  for (std::size_t i = 1; i < lines.size(); ++i) csv_sum += std::stod(split(lines[i])[10]);
  EXPECT_NEAR(csv_sum, result.removed_volume_m3, 1e-8 * (1.0 + result.removed_volume_m3));
}

TEST_F(RunTest, FlowingSoilIsConservedAndWrittenAsTakenAndDeposited) {
  // The same cuts with soil that flows: nothing vanishes.
  Scenario sc;
  sc.base = parse_scenario(kScenario + "soil: {model: flow, repose_deg: 34}\n", dir_ / "small.yaml");
  ASSERT_EQ(sc.base.soil.model, SoilModel::kFlow);
  const RunResult result = run(sc, dir_ / "out");
  ASSERT_TRUE(result.soil);
  EXPECT_GT(result.removed_volume_m3, 0.0);  // the blade cut ...
  EXPECT_NEAR(result.soil->displaced_volume_m3, result.removed_volume_m3,
              1e-6 * result.removed_volume_m3);  // ... and moved all of it
  EXPECT_NEAR(result.final_volume_m3, result.initial_volume_m3, 1e-6 * result.initial_volume_m3);
  int rows = 0, cols = 0;
  const std::vector<float> initial = io::build_initial_heights(sc.base);
  const std::vector<float> height = read_npy(dir_ / "out" / "height.npy", &rows, &cols);
  const std::vector<float> removed = read_npy(dir_ / "out" / "removed.npy", &rows, &cols);
  const std::vector<float> deposited = read_npy(dir_ / "out" / "deposited.npy", &rows, &cols);
  ASSERT_EQ(deposited.size(), initial.size());
  // height = initial - removed + deposited, each part never negative.
  int put = 0;
  for (std::size_t i = 0; i < initial.size(); ++i) {
    EXPECT_GE(removed[i], 0.0f);
    EXPECT_GE(deposited[i], 0.0f);
    EXPECT_TRUE(removed[i] == 0.0f || deposited[i] == 0.0f) << i;
    EXPECT_NEAR(double(height[i]), double(initial[i]) - removed[i] + deposited[i], 1e-6) << i;
    if (deposited[i] > 0.0f) ++put;
  }
  EXPECT_GT(put, 5);
  // The net soil moved is what the removed layer holds; the ground the blade
  // cut is at least that (soil that slid back and was cut again counts
  // again) and at most every step's cut (which counts the pushed soil again).
  double removed_sum = 0.0;
  for (const float r : removed) removed_sum += double(r);
  const double cell_area = sc.base.size_x_m / cols * (sc.base.size_z_m / rows);
  EXPECT_NEAR(result.soil->net_moved_m3, removed_sum * cell_area, 1e-6 * result.initial_volume_m3);
  EXPECT_GE(result.soil->cut_from_ground_m3, result.soil->net_moved_m3 - 1e-9);
  EXPECT_LE(result.soil->cut_from_ground_m3, result.removed_volume_m3 + 1e-9);
  EXPECT_GT(result.soil->net_moved_m3, 0.0);
  EXPECT_TRUE(fs::exists(dir_ / "out" / "deposited.png"));
  const nlohmann::json j = nlohmann::json::parse(read_bytes(dir_ / "out" / "summary.json"));
  EXPECT_EQ(j["soil"]["model"], "flow");
  EXPECT_EQ(j["soil"]["cut_from_ground_m3"].get<double>(), result.soil->cut_from_ground_m3);
  EXPECT_EQ(j["soil"]["net_moved_m3"].get<double>(), result.soil->net_moved_m3);
  EXPECT_EQ(j["soil"]["displaced_volume_m3"].get<double>(), result.soil->displaced_volume_m3);
  EXPECT_NEAR(j["soil"]["volume_m3"]["error"].get<double>(), 0.0, 1e-6 * result.initial_volume_m3);
  EXPECT_NEAR(j["conservation"]["volume_error_m3"].get<double>(), 0.0,
              1e-6 * result.initial_volume_m3);
  // The same scenario twice: the same bits.
  const RunResult again = run(sc, dir_ / "again");
  EXPECT_EQ(read_bytes(dir_ / "out" / "height.npy"), read_bytes(dir_ / "again" / "height.npy"));
  EXPECT_EQ(again.soil->pair_checks, result.soil->pair_checks);
}

// A blade given a top (blade.height_m) lets what stands higher fall over it:
// the run reports it (over_top_m3, and the height among the inputs), keeps
// the volume, and the same cuts with an unbounded blade report none.
TEST_F(RunTest, SoilOverTheBladesTopIsReportedAndKept) {
  const std::string flow = "soil: {model: flow, repose_deg: 34}\n";
  Scenario topped;
  topped.base = parse_scenario(test::replace(kScenario, "blade: {length_m: 0.9}", "blade: {length_m: 0.9, height_m: 0.02}") + flow,
                               dir_ / "topped.yaml");
  ASSERT_EQ(topped.base.blade.height_m, 0.02);
  const RunResult result = run(topped, dir_ / "topped");
  ASSERT_TRUE(result.soil);
  EXPECT_GT(result.soil->over_top_m3, 0.0);
  EXPECT_NEAR(result.final_volume_m3, result.initial_volume_m3, 1e-6 * result.initial_volume_m3);
  const nlohmann::json j = nlohmann::json::parse(read_bytes(dir_ / "topped" / "summary.json"));
  EXPECT_EQ(j["soil"]["over_top_m3"].get<double>(), result.soil->over_top_m3);
  EXPECT_EQ(j["inputs"]["blade_height_m"].get<double>(), 0.02);
  Scenario unbounded;
  unbounded.base = parse_scenario(kScenario + flow, dir_ / "small.yaml");
  const RunResult plain = run(unbounded, dir_ / "plain");
  EXPECT_EQ(plain.soil->over_top_m3, 0.0);
  const nlohmann::json k = nlohmann::json::parse(read_bytes(dir_ / "plain" / "summary.json"));
  EXPECT_EQ(k["soil"]["over_top_m3"].get<double>(), 0.0);
  EXPECT_FALSE(k["inputs"].contains("blade_height_m"));
}

#ifdef TERRACUT_HAVE_BULLET
TEST_F(RunTest, SoilPushedIntoAPocketStaysUnderTheBodiesHeightfieldsBound) {
  // A 1.25 m blade cutting 5 cm of a 0.2 m layer on 5 mm cells is driven at
  // 26.6 degrees through a static wall 0.1 m thick (mass 0), pushing soil
  // into the pocket between itself and the wall. The soil model's writers
  // keep it under the bodies' heightfield's upper bound (2 x full_scale_m =
  // 0.4 m): nothing is lowered to the bound, no soil deleted, no warning,
  // and the volume is kept to one float rounding of the bound a step.
  // Before, the relaxation's passes raised cells past the bound and the
  // heightfield deleted 9.6e-6 m^3 in 9 samples (before that change, the
  // run reported such soil, without a word, as its volume error).
  const std::string text = R"(name: pocket
terrain:
  generator: plane
  resolution: 320
  size_m: [1.6, 1.6]
  origin_m: [-0.8, 0.0, -0.8]
  full_scale_m: 0.2
  plane: {height_m: 0.2}
soil: {model: flow, repose_deg: 34}
blade: {length_m: 1.25}
bodies:
  - {name: wall, shape: box, size_m: [0.1, 0.4, 0.4], mass_kg: 0, position_m: [-0.08, 0.4, 0.3], friction: 0.6}
cuts:
  - name: sweep
    keyframes:
      - {t_s: 0.0, position_m: [0.1565, 0.21, -0.3130], rotation_deg: [0, -26.5651, 0]}
      - {t_s: 0.2, position_m: [0.0939, 0.15, -0.1878], rotation_deg: [0, -26.5651, 0]}
      - {t_s: 1.0, position_m: [-0.1565, 0.15, 0.3130], rotation_deg: [0, -26.5651, 0]}
      - {t_s: 1.5, position_m: [-0.1565, 0.15, 0.3130], rotation_deg: [0, -26.5651, 0]}
)";
  const Scenario sc = session::parse_scenario(text, dir_ / "pocket.yaml");
  const RunResult result = run(sc, dir_ / "out");
  const nlohmann::json j = nlohmann::json::parse(read_bytes(dir_ / "out" / "summary.json"));
  ASSERT_TRUE(j.contains("bodies"));
  EXPECT_EQ(j["bodies"]["samples_clamped_to_bounds"].get<int>(), 0);
  EXPECT_EQ(j["bodies"]["soil_clamped_m3"].get<double>(), 0.0);
  for (const std::string& w : result.warnings) EXPECT_EQ(w.find("deleting"), std::string::npos) << w;
  const double cell = 1.6 / 320, bound = 0.4;
  EXPECT_NEAR(result.volume_error_m3, 0.0,
              double(result.steps) * double(std::numeric_limits<float>::epsilon()) * bound * cell * cell);
}
#endif

TEST(BoundsWarnings, SoilTheBodiesHeightfieldDeletedIsOneLineWithTheVolumeAndTheBound) {
  EXPECT_TRUE(bounds_warnings(0, 0.0, 0.4).empty());
  const std::vector<std::string> w = bounds_warnings(13, 6.4e-6, 0.4);
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NE(w[0].find("13 times"), std::string::npos) << w[0];
  EXPECT_NE(w[0].find("deleting 6.4e-06 m^3"), std::string::npos) << w[0];
  EXPECT_NE(w[0].find("upper bound (0.4 m"), std::string::npos) << w[0];
  EXPECT_NE(w[0].find("terrain.full_scale_m"), std::string::npos) << w[0];
}

TEST_F(RunTest, ContactCsvHasOneRowPerStepInSequenceOrder) {
  const Scenario sc = scenario();
  const RunResult result = run(sc, dir_ / "out", true);
  const std::vector<std::string> lines = lines_of(read_bytes(dir_ / "out" / "contact.csv"));
  ASSERT_FALSE(lines.empty());
  EXPECT_EQ(lines[0],
            "t,cut,x,y,z,qw,qx,qy,qz,contact_length,removed_volume,section_area,max_depth,"
            "cells_visited");
  // roll: round(1.0*200)+1 = 201 steps, back: 161, roll again: 201.
  const std::int64_t expected_steps = 201 + 161 + 201;
  EXPECT_EQ(result.steps, expected_steps);
  ASSERT_EQ(std::int64_t(lines.size()) - 1, expected_steps);
  ASSERT_EQ(std::int64_t(result.records.size()), expected_steps);
  for (std::int64_t i = 0; i < expected_steps; ++i) {
    const std::vector<std::string> cells = split(lines[std::size_t(i + 1)]);
    ASSERT_EQ(cells.size(), 14u) << lines[std::size_t(i + 1)];
    // Global time advances one step of 1/rate per row.
    EXPECT_NEAR(std::stod(cells[0]), double(i) / 200.0, 1e-9);
    const char* want = i < 201 ? "roll" : (i < 362 ? "back" : "roll");
    EXPECT_EQ(cells[1], want) << i;
    EXPECT_NEAR(std::stod(cells[9]), result.records[std::size_t(i)].contact.length_m,
                1e-8 * (1.0 + result.records[std::size_t(i)].contact.length_m));
  }
  // A cut starts at its first keyframe and ends at its last.
  EXPECT_EQ(split(lines[1])[4], "-0.6");
  EXPECT_EQ(split(lines[201])[4], "0.6");
  EXPECT_EQ(split(lines[202])[3], "0.12");
  // Per-cut statistics agree with the records.
  ASSERT_EQ(result.cuts.size(), 3u);
  std::int64_t first = 0;
  for (const CutStats& c : result.cuts) {
    double peak = 0.0;
    double volume = 0.0;
    for (std::int64_t i = first; i < first + c.steps; ++i) {
      peak = std::max(peak, result.records[std::size_t(i)].contact.length_m);
      volume += result.records[std::size_t(i)].removed_volume_m3;
    }
    EXPECT_EQ(c.peak_contact_m, peak) << c.name;
    EXPECT_NEAR(c.removed_volume_m3, volume, 1e-15) << c.name;
    EXPECT_NEAR(c.start_t_s, double(first) / 200.0, 1e-12) << c.name;
    // cut_steps (what the Python module samples a cut by) says the same.
    EXPECT_EQ(c.steps, cut_steps(sc.base.cuts[std::size_t(sc.base.find_cut(c.name))], 200.0))
        << c.name;
    first += c.steps;
  }
  EXPECT_GT(result.cuts[0].peak_contact_m, 0.0);
  // The repeated pass meets only what the others left: less than the first time.
  EXPECT_LT(result.cuts[2].removed_volume_m3, result.cuts[0].removed_volume_m3);
}

TEST_F(RunTest, PngOutputsAreTheLayersOverFullScale) {
  const Scenario sc = scenario();
  run(sc, dir_ / "out");
  int rows = 0;
  int cols = 0;
  const std::vector<float> height = read_npy(dir_ / "out" / "height.npy", &rows, &cols);
  const Image png = read_png(dir_ / "out" / "height.png");
  ASSERT_EQ(png.cols, 24);
  ASSERT_EQ(png.rows, 20);
  EXPECT_EQ(png.bit_depth, 16);
  for (std::size_t i = 0; i < height.size(); ++i)
    EXPECT_NEAR(png.values[i] * 0.3, height[i], 0.3 / 65535.0) << i;
}

TEST_F(RunTest, ProgressLinesOnlyForLongRuns) {
  const Scenario sc = scenario();
  std::ostringstream quiet;
  RunOptions options;
  options.out_dir = dir_ / "a";
  options.progress = &quiet;
  options.progress_after_s = 1e9;  // never reached
  run_scenario(sc, options);
  EXPECT_EQ(quiet.str(), "");

  std::ostringstream loud;
  options.out_dir = dir_ / "b";
  options.progress = &loud;
  options.progress_after_s = 0.0;  // every run is "long"
  options.progress_label = "label";
  run_scenario(sc, options);
  EXPECT_NE(loud.str().find("label: "), std::string::npos) << loud.str();
  EXPECT_NE(loud.str().find("steps/s"), std::string::npos) << loud.str();
  EXPECT_NE(loud.str().find("%"), std::string::npos) << loud.str();
}

TEST_F(RunTest, UnwritableOutputNamesTheFileAndLeavesNothingBehind) {
  const Scenario sc = scenario();
  // A folder where height.npy should go: writing it fails after contact.csv.
  const fs::path out = dir_ / "out";
  fs::create_directories(out / "height.npy" / "blocker");
  std::ofstream(out / "summary.json") << "stale";  // from an older run
  try {
    run(sc, out);
    FAIL() << "the run did not report the unwritable file";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("height.npy"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(out / "contact.csv"));
  EXPECT_FALSE(fs::exists(out / "summary.json"));
  EXPECT_FALSE(fs::exists(out / "removed.npy"));
}

TEST_F(RunTest, OutputFolderThatIsAFileIsNamed) {
  const Scenario sc = scenario();
  std::ofstream(dir_ / "plainfile") << "x";
  try {
    run(sc, dir_ / "plainfile" / "sub");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("plainfile"), std::string::npos) << e.what();
  }
}

TEST_F(RunTest, MissingFoldersAreCreated) {
  const Scenario sc = scenario();
  run(sc, dir_ / "deep" / "er" / "out");
  for (const char* name : kRunOutputFiles) EXPECT_TRUE(fs::exists(dir_ / "deep/er/out" / name)) << name;
}

}  // namespace
}  // namespace terracut::session
