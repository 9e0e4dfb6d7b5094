// terracut against published soil-bin measurements (soilbin.hpp): a point's
// prediction is the steady cutting force of its blade, width, rake and depth
// in the published soil (McKyes' equation with McKyes & Ali's side
// crescents: the soil vanishes, no pile grows); the errors, the mean
// absolute relative error and the worst factor are what their definitions
// say; a data set is read back as written and a bad one is refused naming
// the file, the line and the field; the shipped folder reads.
#include "terracut/validation/soilbin.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "../support/input_error.hpp"
#include "terracut/core/earthmoving.hpp"

namespace terracut::validation {
namespace {

namespace fs = std::filesystem;
using terracut::test::input_error_of;

SoilMaterial sand() {
  SoilMaterial m;
  m.unit_weight_n_per_m3 = 1460.0 * kStandardGravity_m_per_s2;
  m.internal_friction_deg = 38.0;
  m.soil_tool_friction_deg = 26.6;
  m.cohesion_pa = 0.0;
  m.adhesion_pa = 0.0;
  return m;
}

SoilBinPoint point(double width, double rake, double depth, double speed) {
  SoilBinPoint p;
  p.id = "p";
  p.blade_width_m = width;
  p.rake_deg = rake;
  p.depth_m = depth;
  p.speed_m_per_s = speed;
  p.horizontal_n = 1.0;
  p.reading = "test";
  return p;
}

TEST(PredictSoilBin, IsTheSteadyCuttingForceOfTheBlade) {
  for (const auto& [w, rake, d] : {std::tuple{0.33, 90.0, 0.05}, std::tuple{0.33, 45.0, 0.10},
                                   std::tuple{0.051, 90.0, 0.10}, std::tuple{1.0, 60.0, 0.04}}) {
    const SoilBinPrediction p = predict_soilbin(point(w, rake, d, 0.1), sand());
    EarthmovingParams ep;
    ep.soil = sand();
    ep.rake_angle_deg = rake;
    const EarthmovingResult e = earthmoving_force(ep, w, d);
    // The depth is read off float32 heights (half an ulp of the layer is
    // below 1e-8 m): 1e-5 relative.
    EXPECT_NEAR(p.horizontal_n, e.horizontal_n, 1e-5 * e.horizontal_n) << w << " " << rake << " " << d;
    EXPECT_NEAR(p.vertical_n, e.vertical_n, 1e-5 * e.horizontal_n) << w << " " << rake << " " << d;
  }
}

class SoilBinFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("terracut_soilbin_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  void write(const std::string& name, const std::string& text) { std::ofstream(dir_ / name) << text; }
  static constexpr const char* kJson =
      R"({"citation": "A. Author (1999), a soil bin", "how_read": "table 2",
          "terracut_soil": {"density_kg_per_m3": 1460, "internal_friction_deg": 38,
                            "soil_tool_friction_deg": 26.6, "cohesion_pa": 0, "adhesion_pa": 0}})";
  static constexpr const char* kHeader =
      "point_id,blade_width_m,rake_angle_deg,depth_m,speed_m_per_s,horizontal_force_n,vertical_force_n,"
      "source_location,reading\n";
  fs::path dir_;
};

TEST_F(SoilBinFiles, ErrorsAreWhatTheirDefinitionsSay) {
  // Measured forces of 0.8x and 1.25x terracut's own prediction: errors
  // +25 % and -20 %, a mean absolute error of 22.5 %, a worst factor 1.25.
  const double a = predict_soilbin(point(0.33, 90.0, 0.05, 0.1), sand()).horizontal_n;
  const double b = predict_soilbin(point(0.33, 60.0, 0.10, 0.05), sand()).horizontal_n;
  write("set.json", kJson);
  write("set.csv", std::string(kHeader) + "a,0.33,90,0.05,0.1," + std::to_string(0.8 * a) +
                       ",,\"Fig. 3, left\",digitized +-2 %\n" + "b,0.33,60,0.10,0.05," + std::to_string(1.25 * b) +
                       ",12.5,table 2,table\n");
  const std::vector<SoilBinSet> sets = read_soilbin_sets(dir_);
  ASSERT_EQ(sets.size(), 1u);
  const SoilBinSet& s = sets[0];
  EXPECT_EQ(s.name, "set");
  EXPECT_EQ(s.citation, "A. Author (1999), a soil bin");
  EXPECT_NEAR(s.material.unit_weight_n_per_m3, 1460.0 * kStandardGravity_m_per_s2, 1e-9);
  ASSERT_EQ(s.points.size(), 2u);
  EXPECT_EQ(s.points[0].source_location, "Fig. 3, left");  // a quoted comma
  EXPECT_FALSE(s.points[0].vertical_n.has_value());
  EXPECT_EQ(*s.points[1].vertical_n, 12.5);
  const SoilBinComparison c = compare_soilbin(s);
  // std::to_string keeps 6 decimals: the measured values are exact to 1e-6 N.
  EXPECT_NEAR(c.error[0], 0.25, 1e-6);
  EXPECT_NEAR(c.error[1], -0.2, 1e-6);
  EXPECT_NEAR(c.mare, 0.225, 1e-6);
  EXPECT_NEAR(c.worst_factor, 1.25, 1e-6);
  EXPECT_FALSE(c.mare_met);
  EXPECT_TRUE(c.factor_met);
}

TEST_F(SoilBinFiles, ASetWithoutForcesIsListedWithoutPoints) {
  write("set.json", kJson);
  write("other.json", R"({"note": "a candidate, no material"})");
  const std::vector<SoilBinSet> sets = read_soilbin_sets(dir_);
  ASSERT_EQ(sets.size(), 1u);
  EXPECT_TRUE(sets[0].points.empty());
  const SoilBinComparison c = compare_soilbin(sets[0]);
  EXPECT_FALSE(c.mare_met);  // nothing compared meets nothing
}

TEST_F(SoilBinFiles, BadFilesAreRefusedNamingTheFileTheLineAndTheField) {
  const auto error = [&](const std::string& json, const std::string& csv) {
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    write("s.json", json);
    if (!csv.empty()) write("s.csv", csv);
    return input_error_of([&] { read_soilbin_sets(dir_); });
  };
  EXPECT_NE(error("{ \"terracut_soil\": ", "").find("s.json:"), std::string::npos);
  EXPECT_NE(error(R"({"terracut_soil": {"internal_friction_deg": 95}})", "")
                .find("terracut_soil.internal_friction_deg"),
            std::string::npos);
  EXPECT_NE(error(R"({"terracut_soil": {"colour": 1}})", "").find("colour"), std::string::npos);
  EXPECT_NE(error(kJson, "id,width\n").find("s.csv:1: expected the header"), std::string::npos);
  EXPECT_NE(error(kJson, std::string(kHeader) + "a,0.33,90,0.05,0.1,12\n").find("s.csv:2: 9 columns expected"),
            std::string::npos);
  EXPECT_NE(error(kJson, std::string(kHeader) + "a,0.33,90,x,0.1,12,,t,table\n").find("s.csv:2: depth_m: 'x'"),
            std::string::npos);
  EXPECT_NE(error(kJson, std::string(kHeader) + "a,0.33,90,0.05,0,12,,t,table\n").find("speed_m_per_s"),
            std::string::npos);
  EXPECT_NE(error(kJson, std::string(kHeader) + "a,0.33,90,0.05,0.1,12,,t,\n").find("reading"), std::string::npos);
  EXPECT_NE(error(kJson, std::string(kHeader)).find("no points"), std::string::npos);
  // Quotes only around a whole cell, and closed.
  EXPECT_NE(error(kJson, std::string(kHeader) + "a,0.33,90,0.05,0.1,12,,Tab\"le 2\",table\n")
                .find("s.csv:2: a quote inside an unquoted cell"),
            std::string::npos);
  EXPECT_NE(error(kJson, std::string(kHeader) + "a,0.33,90,0.05,0.1,12,,\"Fig. 3,table\n")
                .find("s.csv:2: unterminated quote"),
            std::string::npos);
  // A speed or a depth no soil bin runs at (a prediction would never end).
  EXPECT_NE(error(kJson, std::string(kHeader) + "a,0.33,90,0.05,1e-7,12,,t,table\n").find("speed_m_per_s: 1e-7 is outside"),
            std::string::npos);
  EXPECT_NE(error(kJson, std::string(kHeader) + "a,0.33,90,1e-7,0.1,12,,t,table\n").find("depth_m"),
            std::string::npos);
  // A rake that makes no failure wedge in this soil (170 + 26.6 + 38 > 179).
  EXPECT_NE(error(kJson, std::string(kHeader) + "a,0.33,170,0.05,0.1,12,,t,table\n").find("s.csv: point a:"),
            std::string::npos);
  // The published properties, all of them.
  EXPECT_NE(error(R"({"terracut_soil": {}})", "").find("density_kg_per_m3 or unit_weight_n_per_m3"),
            std::string::npos);
  EXPECT_NE(error(R"({"terracut_soil": {"density_kg_per_m3": 1460, "internal_friction_deg": 38}})", "")
                .find("give the soil's cohesion_pa"),
            std::string::npos);
}

TEST(SoilBinData, TheShippedFolderReads) {
  const std::vector<SoilBinSet> sets = read_soilbin_sets(fs::path(TERRACUT_SOURCE_DIR) / "data/soilbin");
  for (const SoilBinSet& s : sets) {
    EXPECT_TRUE(validate(s.material).empty()) << s.name;
    EXPECT_FALSE(s.citation.empty() && s.points.size() > 0) << s.name << ": points need a citation";
  }
}

}  // namespace
}  // namespace terracut::validation
