// Calibration of a soil material (calibrate.hpp): material tests on an exact
// Mohr-Coulomb line give back its angle and intercept, noisy ones within
// their stated uncertainty; a force record that terracut made itself with a
// known material gives that material back from a wrong start, and with noise
// on the force the truth lies within the stated uncertainty; a field the
// force does not depend on is named, not invented; bad files are refused
// naming the file, the line and the field.
#include "terracut/validation/calibrate.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "terracut/core/error.hpp"
#include "../support/input_error.hpp"
#include "terracut/core/simulation.hpp"

namespace terracut::validation {
namespace {

namespace fs = std::filesystem;
using terracut::test::input_error_of;
constexpr double kDeg = std::numbers::pi / 180.0;

const FittedField& field(const Calibration& c, const std::string& name) {
  for (const FittedField& f : c.fields)
    if (f.name == name) return f;
  ADD_FAILURE() << "no field " << name;
  static const FittedField none;
  return none;
}

// ---- Material tests -----------------------------------------------------------

TEST(CalibrateTests, AnExactMohrCoulombLineGivesItsAngleAndIntercept) {
  MaterialTests t;
  const double phi = 33.0, c = 450.0, delta = 24.0;
  for (double sigma : {1000.0, 2500.0, 4000.0, 8000.0}) {
    t.shear.push_back({sigma, c + sigma * std::tan(phi * kDeg)});
    t.plate.push_back({sigma, sigma * std::tan(delta * kDeg)});
  }
  t.bulk_density_kg_per_m3 = {1500.0, 1510.0, 1490.0};
  t.repose_deg = {30.0, 32.0};
  const Calibration cal = calibrate_from_tests(t);
  // Exact data: the least-squares line is the line, to rounding.
  EXPECT_NEAR(cal.material.internal_friction_deg, phi, 1e-9);
  EXPECT_NEAR(cal.material.cohesion_pa, c, 1e-8);
  EXPECT_NEAR(cal.material.soil_tool_friction_deg, delta, 1e-9);
  EXPECT_NEAR(field(cal, "internal_friction_deg").uncertainty, 0.0, 1e-9);
  EXPECT_NEAR(cal.material.unit_weight_n_per_m3, 1500.0 * kStandardGravity_m_per_s2, 1e-9);
  // The standard error of the mean of 1500, 1510, 1490: s = 10, s / sqrt(3).
  EXPECT_NEAR(field(cal, "unit_weight_n_per_m3").uncertainty, 10.0 / std::sqrt(3.0) * kStandardGravity_m_per_s2,
              1e-9);
  EXPECT_NEAR(cal.material.repose_deg, 31.0, 1e-12);
  EXPECT_NEAR(field(cal, "repose_deg").uncertainty, std::sqrt(2.0) / std::sqrt(2.0), 1e-12);
}

// Noisy shear tests: over many trials the truth lies within two standard
// uncertainties about 95 % of the time (a normal error; the t distribution
// with 10 degrees of freedom gives 92.7 %): at least 88 % of 400 trials
// (the binomial's 3-sigma low end), and the uncertainty is not inflated
// (at most 99 %).
TEST(CalibrateTests, NoisyShearTestsCoverTheTruthAtTheirStatedUncertainty) {
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 150.0);  // Pa
  const double phi = 30.0, c = 300.0;
  int phi_in = 0, c_in = 0;
  const int trials = 400;
  for (int k = 0; k < trials; ++k) {
    MaterialTests t;
    for (int i = 0; i < 12; ++i) {
      const double sigma = 1000.0 + 600.0 * i;
      t.shear.push_back({sigma, std::max(0.0, c + sigma * std::tan(phi * kDeg) + noise(rng))});
    }
    const Calibration cal = calibrate_from_tests(t);
    const FittedField& f = field(cal, "internal_friction_deg");
    const FittedField& g = field(cal, "cohesion_pa");
    phi_in += std::abs(f.value - phi) <= 2.0 * f.uncertainty;
    c_in += std::abs(g.value - c) <= 2.0 * g.uncertainty;
  }
  EXPECT_GE(phi_in, int(0.88 * trials));
  EXPECT_LE(phi_in, int(0.99 * trials));
  EXPECT_GE(c_in, int(0.88 * trials));
  EXPECT_LE(c_in, int(0.99 * trials));
}

TEST(CalibrateTests, ALineNeedsTwoNormalStresses) {
  MaterialTests t;
  t.shear = {{1000.0, 700.0}, {1000.0, 720.0}};
  EXPECT_THROW(calibrate_from_tests(t), InputError);
  t.shear = {{1000.0, 700.0}};
  EXPECT_THROW(calibrate_from_tests(t), InputError);
}

// Two tests fix a line exactly, one value a mean: no degree of freedom is
// left to estimate the scatter, and the uncertainty says so (infinite, and
// a note), never zero.
TEST(CalibrateTests, AnUndeterminedUncertaintyIsInfiniteNotZero) {
  MaterialTests t;
  t.shear = {{1000.0, 900.0}, {3000.0, 2300.0}};
  t.plate = {{2000.0, 900.0}};
  t.repose_deg = {31.0};
  const Calibration cal = calibrate_from_tests(t);
  EXPECT_NEAR(cal.material.internal_friction_deg, std::atan(0.7) / kDeg, 1e-9);
  for (const char* f : {"internal_friction_deg", "cohesion_pa", "soil_tool_friction_deg", "repose_deg"})
    EXPECT_TRUE(std::isinf(field(cal, f).uncertainty)) << f;
  EXPECT_GE(cal.notes.size(), 3u);
  // The unit weight and the adhesion came from no test: said.
  bool kept = false;
  for (const std::string& n : cal.notes) kept |= n.find("no test gives unit_weight_n_per_m3, adhesion_pa") == 0;
  EXPECT_TRUE(kept);
}

TEST(CalibrateTests, ALineBelowZeroStressGivesNoCohesionAndSaysSo) {
  MaterialTests t;
  t.shear = {{1000.0, 500.0}, {2000.0, 1200.0}};  // intercept -200 Pa
  const Calibration cal = calibrate_from_tests(t);
  EXPECT_EQ(cal.material.cohesion_pa, 0.0);
  bool said = false;
  for (const std::string& n : cal.notes) said |= n.find("cohesion set to 0") != std::string::npos;
  EXPECT_TRUE(said);
}

class TempDir : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("terracut_calibrate_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path write(const std::string& name, const std::string& text) {
    const fs::path p = dir_ / name;
    std::ofstream(p) << text;
    return p;
  }
  fs::path dir_;
};

using MaterialTestsFile = TempDir;

TEST_F(MaterialTestsFile, TheGeneralFormIsRead) {
  const fs::path p = write("t.json",
                           R"({"bulk_density_kg_per_m3": [1600], "repose_deg": [31, 33],
                               "shear": [{"sigma_pa": 1000, "tau_pa": 900}, {"sigma_pa": 3000, "tau_pa": 2300}],
                               "plate": [{"sigma_pa": 1000, "tau_pa": 450}]})");
  const MaterialTests t = read_material_tests(p);
  EXPECT_EQ(t.bulk_density_kg_per_m3.size(), 1u);
  EXPECT_EQ(t.repose_deg.size(), 2u);
  ASSERT_EQ(t.shear.size(), 2u);
  EXPECT_EQ(t.shear[1].tau_pa, 2300.0);
  const Calibration cal = calibrate_from_tests(t);
  EXPECT_NEAR(cal.material.internal_friction_deg, std::atan(0.7) / kDeg, 1e-9);
  EXPECT_NEAR(cal.material.cohesion_pa, 200.0, 1e-9);
}

TEST_F(MaterialTestsFile, TheDemReferencesOwnFileIsRead) {
  const fs::path p = fs::path(TERRACUT_SOURCE_DIR) / "validation/dem/results/material.json";
  const MaterialTests t = read_material_tests(p);
  EXPECT_GE(t.shear.size(), 4u);
  EXPECT_GE(t.plate.size(), 1u);
  EXPECT_FALSE(t.repose_deg.empty());
  EXPECT_FALSE(t.bulk_density_kg_per_m3.empty());
  const Calibration cal = calibrate_from_tests(t);
  EXPECT_TRUE(validate(cal.material).empty());
}

TEST_F(MaterialTestsFile, BadFilesAreRefusedNamingWhatIsWrong) {
  EXPECT_NE(input_error_of([&] { read_material_tests(dir_ / "absent.json"); }).find("cannot be read"), std::string::npos);
  EXPECT_NE(input_error_of([&] { read_material_tests(write("a.json", "{ not json")); }).find("not valid JSON"),
            std::string::npos);
  EXPECT_NE(input_error_of([&] { read_material_tests(write("b.json", R"({"shaer": []})")); }).find("shaer: unknown test"),
            std::string::npos);
  EXPECT_NE(input_error_of([&] { read_material_tests(write("c.json", R"({"repose_deg": [30, "x"]})")); })
                .find("repose_deg"),
            std::string::npos);
  EXPECT_NE(input_error_of([&] {
              read_material_tests(write("d.json", R"({"shear": [{"sigma_pa": -5, "tau_pa": 1}]})"));
            }).find("shear[0]"),
            std::string::npos);
  EXPECT_NE(input_error_of([&] { read_material_tests(write("e.json", R"({"plate": [{"sigma": 5}]})")); }).find("plate[0]"),
            std::string::npos);
}

// ---- Force records ------------------------------------------------------------

constexpr double kLayer = 0.3;  // m of soil on the floor
constexpr int kCells = 80;      // 0.8 m x 0.8 m of 1 cm cells

SimParams record_params(SoilModel model) {
  SimParams p;
  p.grid = grid_of_cells(kCells, kCells, 0.01);
  p.blade.length_m = 0.3;
  p.soil.model = model;
  p.soil.material = SoilMaterial{};
  return p;
}

std::vector<float> flat() { return std::vector<float>(std::size_t(kCells * kCells), float(kLayer)); }

// A record of the force terracut itself puts on a blade (edge along X)
// pushed along +Z at 0.4 m/s, 3 cm deep for 0.5 s, then 8 cm deep: two
// depths, so that the cohesion (a force ~ width x depth) and the friction
// (~ width x depth^2, through the weight) can be told apart.
ForceRecord made_record(const SoilMaterial& truth, SoilModel model, double noise_n = 0.0) {
  SimParams p = record_params(model);
  p.soil.material = truth;
  Simulation sim(p, flat());
  ForceRecord r;
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(0.0, 1.0);
  const int n = 1000;
  for (int i = 0; i < n; ++i) {
    const double t = i / p.rate_hz;
    const double depth = t < 0.5 ? 0.03 : 0.08;
    const BladePose pose{{0.4, kLayer - depth, 0.05 + 0.4 * t}, Quat{}};
    const StepOutput& o = sim.step(pose);
    r.t_s.push_back(t);
    r.pose.push_back(pose);
    r.force_n.push_back(o.force.total_n + Vec3{noise_n * noise(rng), noise_n * noise(rng), noise_n * noise(rng)});
  }
  return r;
}

SoilMaterial truth_material() {
  SoilMaterial m;
  m.internal_friction_deg = 36.0;
  m.cohesion_pa = 900.0;
  return m;
}

SimParams wrong_start(SoilModel model) {
  SimParams p = record_params(model);
  p.soil.material.internal_friction_deg = 25.0;
  p.soil.material.cohesion_pa = 100.0;
  return p;
}

TEST(CalibrateRecord, TerracutsOwnRecordGivesItsMaterialBackFromAWrongStart) {
  const SoilMaterial truth = truth_material();
  const ForceRecord rec = made_record(truth, SoilModel::kVanish);
  RecordFit fit;
  fit.from_t_s = 0.01;  // the first step meets no force (no motion yet)
  const Calibration cal = calibrate_from_force_record(wrong_start(SoilModel::kVanish), flat(), rec, fit);
  // Noiseless: the fit stops when an iteration gains less than 1e-6 of the
  // residual; at that point the fields are exact to well under a hundredth
  // of a degree and a pascal.
  EXPECT_NEAR(cal.material.internal_friction_deg, truth.internal_friction_deg, 0.01);
  EXPECT_NEAR(cal.material.cohesion_pa, truth.cohesion_pa, 1.0);
  EXPECT_LT(cal.rms_relative, 1e-3);
  EXPECT_GT(cal.evaluations, 3);
  EXPECT_TRUE(cal.notes.empty());
}

TEST(CalibrateRecord, WithNoiseTheTruthIsWithinTheStatedUncertainty) {
  const SoilMaterial truth = truth_material();
  // 5 N of noise per sample and axis (the steady forces are 30-300 N).
  const ForceRecord rec = made_record(truth, SoilModel::kVanish, 5.0);
  RecordFit fit;
  fit.from_t_s = 0.01;
  fit.window_s = 0.01;
  const Calibration cal = calibrate_from_force_record(wrong_start(SoilModel::kVanish), flat(), rec, fit);
  const FittedField& phi = field(cal, "internal_friction_deg");
  const FittedField& c = field(cal, "cohesion_pa");
  EXPECT_GT(phi.uncertainty, 0.0);
  EXPECT_GT(c.uncertainty, 0.0);
  // Three standard uncertainties: a miss has odds of 0.3 % for a right one.
  EXPECT_LE(std::abs(phi.value - truth.internal_friction_deg), 3.0 * phi.uncertainty);
  EXPECT_LE(std::abs(c.value - truth.cohesion_pa), 3.0 * c.uncertainty);
  // And it is informative: the window means' noise is 5 / sqrt(10) N.
  EXPECT_LT(phi.uncertainty, 1.0);
}

TEST(CalibrateRecord, AFieldTheForceDoesNotFeelIsNamedNotInvented) {
  const SoilMaterial truth = truth_material();
  const ForceRecord rec = made_record(truth, SoilModel::kVanish);
  RecordFit fit;
  fit.from_t_s = 0.01;
  // The soil vanishes: no pile, so the repose never reaches the force.
  fit.fields = {"internal_friction_deg", "repose_deg"};
  SimParams start = record_params(SoilModel::kVanish);
  start.soil.material.cohesion_pa = truth.cohesion_pa;
  start.soil.material.internal_friction_deg = 30.0;
  const Calibration cal = calibrate_from_force_record(start, flat(), rec, fit);
  EXPECT_NEAR(cal.material.internal_friction_deg, truth.internal_friction_deg, 0.01);
  EXPECT_EQ(cal.material.repose_deg, start.soil.material.repose_deg);
  EXPECT_TRUE(std::isinf(field(cal, "repose_deg").uncertainty));
  ASSERT_EQ(cal.notes.size(), 1u);
  EXPECT_NE(cal.notes[0].find("repose_deg"), std::string::npos);
}

TEST(CalibrateRecord, FlowingSoilIsFittedToo) {
  // The soil piles ahead and its surcharge joins the force: the fit replays
  // the flow as well (the repose kept at the truth's).
  const SoilMaterial truth = truth_material();
  const ForceRecord rec = made_record(truth, SoilModel::kFlow);
  RecordFit fit;
  fit.from_t_s = 0.01;
  const Calibration cal = calibrate_from_force_record(wrong_start(SoilModel::kFlow), flat(), rec, fit);
  EXPECT_NEAR(cal.material.internal_friction_deg, truth.internal_friction_deg, 0.05);
  EXPECT_NEAR(cal.material.cohesion_pa, truth.cohesion_pa, 5.0);
}

// A trial step that leaves the valid materials (rake + delta + phi must
// stay under 179 degrees) is a rejected step, not the end of the fit.
TEST(CalibrateRecord, AStepPastTheMaterialsLimitIsRejectedNotFatal) {
  SoilMaterial truth = truth_material();
  truth.internal_friction_deg = 52.0;
  truth.soil_tool_friction_deg = 35.0;  // 90 + 35 + 52 = 177
  const ForceRecord rec = made_record(truth, SoilModel::kVanish);
  RecordFit fit;
  fit.from_t_s = 0.01;
  fit.fields = {"internal_friction_deg", "soil_tool_friction_deg"};
  SimParams start = record_params(SoilModel::kVanish);
  start.soil.material = truth;
  start.soil.material.internal_friction_deg = 40.0;
  start.soil.material.soil_tool_friction_deg = 20.0;
  const Calibration cal = calibrate_from_force_record(start, flat(), rec, fit);
  EXPECT_LT(cal.material.internal_friction_deg + cal.material.soil_tool_friction_deg + 90.0, 179.0);
  EXPECT_NEAR(cal.material.internal_friction_deg, 52.0, 0.1);
  EXPECT_NEAR(cal.material.soil_tool_friction_deg, 35.0, 0.1);
}

TEST(CalibrateRecord, BadFitsAreRefused) {
  const ForceRecord rec = made_record(truth_material(), SoilModel::kVanish);
  RecordFit fit;
  fit.fields = {"friction"};
  EXPECT_THROW(calibrate_from_force_record(record_params(SoilModel::kVanish), flat(), rec, fit), InputError);
  fit.fields = {};
  EXPECT_THROW(calibrate_from_force_record(record_params(SoilModel::kVanish), flat(), rec, fit), InputError);
  // The record at 1 kHz, the run at 500 Hz.
  SimParams p = record_params(SoilModel::kVanish);
  p.rate_hz = 500.0;
  EXPECT_THROW(calibrate_from_force_record(p, flat(), rec, RecordFit{}), InputError);
  fit.fields = {"cohesion_pa", "cohesion_pa"};
  EXPECT_NE(input_error_of([&] { calibrate_from_force_record(record_params(SoilModel::kVanish), flat(), rec, fit); })
                .find("cohesion_pa is given twice"),
            std::string::npos);
  RecordFit none;
  none.max_iterations = 0;
  EXPECT_NE(input_error_of([&] { calibrate_from_force_record(record_params(SoilModel::kVanish), flat(), rec, none); })
                .find("max_iterations"),
            std::string::npos);
  ForceRecord uneven = rec;
  uneven.t_s[500] += 0.0004;
  EXPECT_NE(input_error_of([&] { calibrate_from_force_record(record_params(SoilModel::kVanish), flat(), uneven, {}); })
                .find("not at a fixed rate"),
            std::string::npos);
  // Fewer windows than fields.
  RecordFit late;
  late.from_t_s = 10.0;
  EXPECT_THROW(calibrate_from_force_record(record_params(SoilModel::kVanish), flat(), rec, late), InputError);
}

using ForceRecordFile = TempDir;

TEST_F(ForceRecordFile, ARecordIsRead) {
  const fs::path p = write("r.csv",
                           "t_s,x_m,y_m,z_m,qw,qx,qy,qz,fx_n,fy_n,fz_n\n"
                           "0,0.4,0.27,0.05,2,0,0,0,0,0,0\n"
                           "0.001,0.4,0.27,0.0504,1,0,0,0,1.5,2,-30\n");
  const ForceRecord r = read_force_record(p);
  ASSERT_EQ(r.t_s.size(), 2u);
  EXPECT_EQ(r.pose[0].orientation.w, 1.0);  // normalised
  EXPECT_EQ(r.force_n[1].z, -30.0);
}

TEST_F(ForceRecordFile, BadRecordsAreRefusedNamingTheLine) {
  const std::string header = "t_s,x_m,y_m,z_m,qw,qx,qy,qz,fx_n,fy_n,fz_n\n";
  const std::string good = "0,0,0,0,1,0,0,0,0,0,0\n";
  EXPECT_NE(input_error_of([&] { read_force_record(write("a.csv", "t,x\n" + good)); }).find(":1: expected the header"),
            std::string::npos);
  EXPECT_NE(input_error_of([&] { read_force_record(write("b.csv", header + good + "0.001,0,0,0,1,0,0\n")); })
                .find(":3: 11 numbers expected"),
            std::string::npos);
  EXPECT_NE(input_error_of([&] { read_force_record(write("c.csv", header + good + "0.001,0,0,nan,1,0,0,0,0,0,0\n")); })
                .find(":3: 'nan' is not a finite number"),
            std::string::npos);
  EXPECT_NE(input_error_of([&] { read_force_record(write("d.csv", header + good + "0,0,0,0,1,0,0,0,0,0,0\n")); })
                .find(":3: times must increase"),
            std::string::npos);
  EXPECT_NE(input_error_of([&] { read_force_record(write("e.csv", header + good + "0.001,0,0,0,0,0,0,0,0,0,0\n")); })
                .find(":3: the orientation qw,qx,qy,qz is zero"),
            std::string::npos);
  EXPECT_NE(input_error_of([&] { read_force_record(write("f.csv", header + good)); }).find("fewer than two samples"),
            std::string::npos);
  EXPECT_NE(input_error_of([&] { read_force_record(write("g.csv", header + good + "0.001,0,0,0,1,0,0,0,0,0,1e5x\n")); })
                .find("'1e5x'"),
            std::string::npos);
  EXPECT_NE(input_error_of([&] {
              read_force_record(write("h.csv", header + good + "0.001,0,0,0,1,0,0,0,0,0,0\n0.0025,0,0,0,1,0,0,0,0,0,0\n"));
            }).find(":4: the samples are not at a fixed rate"),
            std::string::npos);
}

TEST(MaterialYaml, ListsEveryFieldOfTheMaterial) {
  const std::string y = material_yaml(truth_material());
  for (const char* key : {"unit_weight_n_per_m3: ", "internal_friction_deg: 36", "cohesion_pa: 900",
                          "soil_tool_friction_deg: ", "adhesion_pa: ", "repose_deg: "})
    EXPECT_NE(y.find(key), std::string::npos) << key;
}

}  // namespace
}  // namespace terracut::validation
