// Scenario files: a full parse, defaults, image terrain, overrides, the shipped
// scenarios, and every kind of bad input giving an error that names the file,
// the line and the field.
#include "terracut/io/scenario.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <string>

#include "../support/scenario_text.hpp"
#include "terracut/core/error.hpp"
#include "terracut/io/image.hpp"

#include "../support/peak_memory.hpp"

namespace terracut::io {
namespace {

namespace fs = std::filesystem;

// A fresh folder per test, removed afterwards.
class ScenarioTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("terracut_scenario_test_" + std::to_string(getpid()) + "_" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path write(const std::string& name, const std::string& text) {
    const fs::path path = dir_ / name;
    fs::create_directories(path.parent_path());
    std::ofstream(path) << text;
    return path;
  }

  fs::path dir_;
};

using test::line_of;
using test::replace;

// The error of parsing text as "bad.yaml", or "" when it parses.
std::string parse_error(const std::string& text) {
  try {
    parse_scenario(text, "/some/folder/bad.yaml");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// Expects an InputError naming the file, the line and the field, with a fragment.
void expect_error(const std::string& text, int line, const std::string& field,
                  const std::string& fragment) {
  const std::string message = parse_error(text);
  const std::string where = "/some/folder/bad.yaml:" + std::to_string(line) + ": ";
  EXPECT_EQ(message.rfind(where, 0), 0u) << "message: " << message << "\nexpected start: " << where;
  EXPECT_NE(message.find(field), std::string::npos) << "message: " << message;
  EXPECT_NE(message.find(fragment), std::string::npos) << "message: " << message;
}

const std::string kGood = R"(name: full
description: every field given
terrain:
  generator: mound
  resolution: [12, 8]
  size_m: [2.0, 1.0]
  origin_m: [-1.0, 0.5, 3.0]
  full_scale_m: 0.3
  mound: {centre_m: [0.1, 3.4], radius_m: 0.35}
representation: columns
rate_hz: 250
blade: {length_m: 1.25}
cuts:
  - name: A
    keyframes:
      - {t_s: 0.0, position_m: [0.0, 0.6, 2.9], rotation_deg: [0, 0, 0]}
      - {t_s: 1.5, position_m: [0.0, 0.7, 4.1], rotation_deg: [10, 20, 30]}
  - name: B_2
    keyframes:
      - {t_s: 0.25, position_m: [0.5, 0.6, 4.1]}
sequence: [B_2, A, B_2]
reference:
  mound: {centre_m: [0.1, 3.4], radius_m: 0.35, height_m: 0.3}
)";

TEST_F(ScenarioTest, ParsesEveryField) {
  const Scenario sc = parse_scenario(kGood, dir_ / "full.yaml");
  EXPECT_EQ(sc.name, "full");
  EXPECT_EQ(sc.description, "every field given");
  ASSERT_TRUE(sc.generator.has_value());
  EXPECT_EQ(sc.generator->kind, GeneratorKind::kMound);
  EXPECT_DOUBLE_EQ(sc.generator->mound.centre_x_m, 0.1);
  EXPECT_DOUBLE_EQ(sc.generator->mound.centre_z_m, 3.4);
  EXPECT_DOUBLE_EQ(sc.generator->mound.radius_m, 0.35);
  EXPECT_DOUBLE_EQ(sc.generator->mound.height_m, 0.3);  // the generator height is full_scale_m
  EXPECT_EQ(sc.resolution, (Resolution{12, 8}));
  EXPECT_DOUBLE_EQ(sc.size_x_m, 2.0);
  EXPECT_DOUBLE_EQ(sc.size_z_m, 1.0);
  EXPECT_DOUBLE_EQ(sc.origin_m.x, -1.0);
  EXPECT_DOUBLE_EQ(sc.origin_m.y, 0.5);
  EXPECT_DOUBLE_EQ(sc.origin_m.z, 3.0);
  EXPECT_DOUBLE_EQ(sc.full_scale_m, 0.3);
  EXPECT_EQ(sc.representation, Representation::kColumns);
  EXPECT_DOUBLE_EQ(sc.rate_hz, 250.0);
  EXPECT_DOUBLE_EQ(sc.blade.length_m, 1.25);
  ASSERT_EQ(sc.cuts.size(), 2u);
  EXPECT_EQ(sc.cuts[0].name, "A");
  ASSERT_EQ(sc.cuts[0].keyframes.size(), 2u);
  EXPECT_DOUBLE_EQ(sc.cuts[0].keyframes[1].t_s, 1.5);
  EXPECT_DOUBLE_EQ(sc.cuts[0].keyframes[1].pose.position_m.z, 4.1);
  const Quat q = sc.cuts[0].keyframes[1].pose.orientation;
  const Quat want = quat_from_euler_deg({10, 20, 30});
  EXPECT_NEAR(std::abs(q.w * want.w + q.x * want.x + q.y * want.y + q.z * want.z), 1.0, 1e-12);
  // A keyframe without rotation_deg has none.
  const Quat none = sc.cuts[1].keyframes[0].pose.orientation;
  EXPECT_NEAR(std::abs(none.w), 1.0, 1e-12);
  EXPECT_EQ(sc.sequence, (std::vector<int>{1, 0, 1}));
  EXPECT_EQ(sc.sequence_names(), (std::vector<std::string>{"B_2", "A", "B_2"}));
  ASSERT_TRUE(sc.reference_mound.has_value());
  EXPECT_DOUBLE_EQ(sc.reference_mound->height_m, 0.3);

  const GridSpec spec = grid_spec(sc);
  EXPECT_EQ(spec.cols, 12);
  EXPECT_EQ(spec.rows, 8);
  const std::vector<float> h = build_initial_heights(sc);
  ASSERT_EQ(h.size(), 96u);
  // The sample nearest the dome's centre: column 5 (x = -0.083), row 3 (z = 3.44).
  const double x = -1.0 + 5.5 * (2.0 / 12);
  const double z = 3.0 + 3.5 * (1.0 / 8);
  EXPECT_NEAR(h[3 * 12 + 5], height_at(sc.generator->mound, x, z), 1e-7);
}

TEST_F(ScenarioTest, DefaultsApplyWhenFieldsAreLeftOut) {
  const std::string text = R"(terrain:
  generator: plane
  resolution: 4
  size_m: [1, 1]
  full_scale_m: 0.5
blade: {length_m: 1}
cuts:
  - name: only
    keyframes:
      - {t_s: 0, position_m: [0, 0, 0]}
)";
  const Scenario sc = parse_scenario(text, dir_ / "my_stem.yaml");
  EXPECT_EQ(sc.name, "my_stem");
  EXPECT_EQ(sc.representation, Representation::kSurface);
  EXPECT_DOUBLE_EQ(sc.rate_hz, 1000.0);
  EXPECT_EQ(sc.resolution, (Resolution{4, 4}));
  EXPECT_DOUBLE_EQ(sc.origin_m.y, 0.0);
  EXPECT_EQ(sc.sequence, (std::vector<int>{0}));
  EXPECT_FALSE(sc.reference_mound.has_value());
  for (float v : build_initial_heights(sc)) EXPECT_EQ(v, 0.5f);  // plane default = full scale
}

TEST_F(ScenarioTest, ImageTerrainIsReadRelativeToTheScenarioAndScaled) {
  // A 4 x 3 gradient image in a sibling folder.
  std::vector<float> values(12);
  for (int i = 0; i < 12; ++i) values[std::size_t(i)] = float(i) / 11.0f;
  fs::create_directories(dir_ / "data");
  write_png16(dir_ / "data" / "ramp.png", values.data(), 4, 3, 1.0);
  const std::string text = R"(terrain:
  image: ../data/ramp.png
  size_m: [4, 3]
  full_scale_m: 2.0
blade: {length_m: 1}
cuts:
  - name: a
    keyframes: [{t_s: 0, position_m: [0, 0, 0]}]
)";
  const fs::path path = write("scenarios/ramp.yaml", text);
  Scenario sc = load_scenario(path);
  EXPECT_EQ(sc.resolution, (Resolution{4, 3}));  // the image's own size
  EXPECT_TRUE(fs::equivalent(sc.image_path, dir_ / "data" / "ramp.png"));
  const std::vector<float> h = build_initial_heights(sc);
  ASSERT_EQ(h.size(), 12u);
  for (int i = 0; i < 12; ++i)  // 16-bit quantisation: 1/65535 of full scale
    EXPECT_NEAR(h[std::size_t(i)], 2.0 * i / 11.0, 2.0 / 65535.0 + 1e-6) << i;

  // An override resamples the image to the new resolution.
  apply_overrides(sc, Resolution{2, 6}, std::nullopt, std::nullopt);
  EXPECT_EQ(build_initial_heights(sc).size(), 12u);
  EXPECT_EQ(grid_spec(sc).cols, 2);
  EXPECT_EQ(grid_spec(sc).rows, 6);
}

TEST_F(ScenarioTest, OverridesReplaceResolutionRepresentationAndSequence) {
  Scenario sc = parse_scenario(kGood, dir_ / "full.yaml");
  apply_overrides(sc, Resolution{30, 20}, Representation::kSurface,
                  std::vector<std::string>{"A", "A"});
  EXPECT_EQ(sc.resolution, (Resolution{30, 20}));
  EXPECT_EQ(sc.representation, Representation::kSurface);
  EXPECT_EQ(sc.sequence, (std::vector<int>{0, 0}));
  try {
    apply_overrides(sc, std::nullopt, std::nullopt, std::vector<std::string>{"A", "Z"});
    FAIL() << "unknown cut accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--sequence"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("'Z'"), std::string::npos) << e.what();
  }
  EXPECT_THROW(apply_overrides(sc, Resolution{0, 5}, std::nullopt, std::nullopt), InputError);
}

TEST(ScenarioSoil, TheSoilSectionChoosesTheModel) {
  // Absent: the paper's model.
  EXPECT_EQ(parse_scenario(kGood, "x.yaml").soil.model, SoilModel::kVanish);
  const std::string text = kGood + "soil:\n  model: flow\n  repose_deg: 40\n";
  const Scenario sc = parse_scenario(text, "x.yaml");
  EXPECT_EQ(sc.soil.model, SoilModel::kFlow);
  EXPECT_EQ(sc.soil.material.repose_deg, 40.0);
  EXPECT_EQ(sim_params(sc).soil.material.repose_deg, 40.0);
  // Errors name the file, the line and the field.
  const std::string zero = replace(text, "repose_deg: 40", "repose_deg: 0");
  expect_error(zero, line_of(zero, "repose_deg: 0"), "soil.repose_deg", "[1, 80]");
  const std::string tiny = replace(text, "repose_deg: 40", "repose_deg: 1e-300");
  expect_error(tiny, line_of(tiny, "repose_deg: 1e-300"), "soil.repose_deg", "[1, 80]");
  // The flow's settings without a model (which defaults to vanish) are a
  // mistake, named; with an explicit vanish they are kept.
  const std::string no_model = replace(text, "  model: flow\n", "");
  expect_error(no_model, line_of(no_model, "repose_deg: 40"), "soil.repose_deg", "add 'model: flow'");
  EXPECT_EQ(parse_scenario(replace(text, "model: flow", "model: vanish"), "x.yaml").soil.model, SoilModel::kVanish);
  const std::string mud = replace(text, "model: flow", "model: mud");
  expect_error(mud, line_of(mud, "model: mud"), "soil.model", "allowed: vanish, flow");
  EXPECT_EQ(sc.soil.edge, SoilEdge::kWall);
  EXPECT_EQ(parse_scenario(text + "  edge: open\n", "x.yaml").soil.edge, SoilEdge::kOpen);
  const std::string edge = text + "  edge: cliff\n";
  expect_error(edge, line_of(edge, "edge: cliff"), "soil.edge", "allowed: wall, open");
  EXPECT_EQ(sc.soil.settle, SoilSettle::kFans);
  EXPECT_EQ(parse_scenario(text + "  settle: passes\n", "x.yaml").soil.settle, SoilSettle::kPasses);
  const std::string settle = text + "  settle: fast\n";
  EXPECT_EQ(parse_scenario(text + "  settle: fans\n", "x.yaml").soil.settle, SoilSettle::kFans);
  expect_error(settle, line_of(settle, "settle: fast"), "soil.settle", "allowed: patches, passes, fans");
  const std::string typo = text + "  repose: 30\n";
  expect_error(typo, line_of(typo, "repose: 30"), "soil.repose", "unknown key");
}

TEST(ScenarioSoil, ABucketIsAShapeBehindTheEdgeAndNeedsSoilThatFlows) {
  const std::string flow = replace(kGood, "blade: {length_m: 1.25}",
                                   "blade:\n  length_m: 1.25\n  bucket: {depth_m: 0.4, height_m: 0.3}\n") +
                           "soil: {model: flow}\n";
  const Scenario sc = parse_scenario(flow, "x.yaml");
  EXPECT_EQ(sc.blade.bucket.depth_m, 0.4);
  EXPECT_EQ(sc.blade.bucket.height_m, 0.3);
  EXPECT_TRUE(sim_params(sc).blade.bucket.enabled());
  // Without it, a flat blade.
  EXPECT_FALSE(parse_scenario(kGood, "x.yaml").blade.bucket.enabled());
  // Errors name the line and the field.
  const std::string vanish = replace(flow, "soil: {model: flow}\n", "");
  expect_error(vanish, line_of(vanish, "bucket:"), "blade.bucket", "soil that flows");
  const std::string flat = replace(flow, "height_m: 0.3", "height_m: 0");
  expect_error(flat, line_of(flat, "bucket:"), "blade.bucket.height_m", "> 0");
  const std::string typo = replace(flow, "depth_m: 0.4", "deep_m: 0.4");
  expect_error(typo, line_of(typo, "bucket:"), "blade.bucket.deep_m", "unknown key");
  // A bucket's height is its own: a blade's top with one is refused.
  const std::string topped = replace(flow, "  length_m: 1.25\n", "  length_m: 1.25\n  height_m: 0.5\n");
  expect_error(topped, line_of(topped, "height_m: 0.5"), "blade.height_m", "blade.bucket.height_m");
}

// A flat blade's top (BladeSpec::height_m): unbounded when left out, a
// height > 0 when given; errors name the line and the field.
TEST(ScenarioBlade, ABladesTopIsOptionalAndPositive) {
  EXPECT_EQ(parse_scenario(kGood, "x.yaml").blade.height_m, std::numeric_limits<double>::infinity());
  const std::string topped = replace(kGood, "blade: {length_m: 1.25}", "blade: {length_m: 1.25, height_m: 0.4}");
  EXPECT_EQ(parse_scenario(topped, "x.yaml").blade.height_m, 0.4);
  EXPECT_EQ(sim_params(parse_scenario(topped, "x.yaml")).blade.height_m, 0.4);
  for (const char* bad : {"0", "-0.1", ".nan", "tall"}) {
    const std::string text = replace(kGood, "blade: {length_m: 1.25}",
                                     std::string("blade: {length_m: 1.25, height_m: ") + bad + "}");
    expect_error(text, line_of(text, "height_m"), "blade.height_m", "");
  }
}

TEST(ScenarioOptions, ParseResolutionAndNameLists) {
  EXPECT_EQ(parse_resolution("50"), (Resolution{50, 50}));
  EXPECT_EQ(parse_resolution("64x32"), (Resolution{64, 32}));
  EXPECT_EQ(parse_resolution("7X9"), (Resolution{7, 9}));
  for (const char* bad : {"0", "-3", "abc", "5x", "x5", "70000", "65536x65536", "1.5", ""}) {
    try {
      parse_resolution(bad);
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("--resolution"), std::string::npos) << e.what();
    }
  }
  EXPECT_EQ(parse_name_list("A, B,C"), (std::vector<std::string>{"A", "B", "C"}));
  EXPECT_THROW(parse_name_list("A,,B"), InputError);
  EXPECT_THROW(parse_name_list(""), InputError);
}

TEST(ScenarioErrors, UnknownKeySaysWhichKeysAreAllowed) {
  const std::string text = replace(kGood, "rate_hz: 250", "rate: 250");
  expect_error(text, line_of(text, "rate: 250"), "rate", "unknown key 'rate'");
  EXPECT_NE(parse_error(text).find("rate_hz"), std::string::npos);  // listed as allowed
  const std::string nested = replace(kGood, "  size_m: [2.0, 1.0]", "  sizes_m: [2.0, 1.0]");
  expect_error(nested, line_of(nested, "sizes_m"), "terrain.sizes_m", "allowed keys");
  const std::string in_keyframe = replace(kGood, "rotation_deg: [10, 20, 30]", "rot: [10, 20, 30]");
  expect_error(in_keyframe, line_of(in_keyframe, "rot:"), "cuts[0].keyframes[1].rot",
               "unknown key");
}

TEST(ScenarioErrors, RepeatedKeyIsRefused) {
  const std::string text = replace(kGood, "rate_hz: 250", "rate_hz: 250\nrate_hz: 300");
  expect_error(text, line_of(text, "rate_hz: 300"), "rate_hz", "twice");
}

TEST(ScenarioErrors, MissingFieldsAreNamed) {
  const std::string no_length = replace(kGood, "blade: {length_m: 1.25}", "blade: {}");
  expect_error(no_length, line_of(no_length, "blade:"), "blade.length_m", "missing");
  const std::string no_size = replace(kGood, "  size_m: [2.0, 1.0]\n", "");
  expect_error(no_size, line_of(no_size, "terrain:"), "terrain.size_m", "missing");
  const std::string no_t = replace(kGood, "{t_s: 1.5, position_m", "{position_m");
  expect_error(no_t, line_of(no_t, "{position_m: [0.0, 0.7"), "cuts[0].keyframes[1].t_s",
               "missing");
  const std::string no_res = replace(kGood, "  resolution: [12, 8]\n", "");
  expect_error(no_res, line_of(no_res, "terrain:"), "terrain.resolution", "generator");
  const std::string no_cuts = kGood.substr(0, kGood.find("cuts:"));
  expect_error(no_cuts, 1, "cuts", "missing");
  const std::string empty_value = replace(kGood, "rate_hz: 250", "rate_hz:");
  expect_error(empty_value, line_of(empty_value, "rate_hz:"), "rate_hz", "no value");
}

TEST(ScenarioErrors, NanAndInfinityAreRefused) {
  const std::string nan_rate = replace(kGood, "rate_hz: 250", "rate_hz: .nan");
  expect_error(nan_rate, line_of(nan_rate, ".nan"), "rate_hz", "finite");
  const std::string inf_pos = replace(kGood, "[0.0, 0.7, 4.1]", "[0.0, .inf, 4.1]");
  expect_error(inf_pos, line_of(inf_pos, ".inf"), "cuts[0].keyframes[1].position_m[1]", "finite");
  const std::string nan_scale = replace(kGood, "full_scale_m: 0.3", "full_scale_m: .NaN");
  expect_error(nan_scale, line_of(nan_scale, ".NaN"), "terrain.full_scale_m", "finite");
}

TEST(ScenarioErrors, ZeroAndNegativeSizesAreRefused) {
  const std::string neg_size = replace(kGood, "size_m: [2.0, 1.0]", "size_m: [2.0, -1.0]");
  expect_error(neg_size, line_of(neg_size, "size_m"), "terrain.size_m[1]", "> 0");
  const std::string zero_blade = replace(kGood, "length_m: 1.25", "length_m: 0");
  expect_error(zero_blade, line_of(zero_blade, "length_m: 0"), "blade.length_m", "> 0");
  const std::string zero_rate = replace(kGood, "rate_hz: 250", "rate_hz: 0");
  expect_error(zero_rate, line_of(zero_rate, "rate_hz"), "rate_hz", "must be in (0, ");
  const std::string neg_radius = replace(kGood, "radius_m: 0.35}", "radius_m: -0.35}");
  expect_error(neg_radius, line_of(neg_radius, "radius_m: -0.35"), "terrain.mound.radius_m", "> 0");
  const std::string neg_time = replace(kGood, "t_s: 0.0,", "t_s: -1.0,");
  expect_error(neg_time, line_of(neg_time, "t_s: -1.0"), "cuts[0].keyframes[0].t_s", ">= 0");
}

TEST(ScenarioErrors, ZeroAndAbsurdResolutionsAreRefused) {
  const std::string zero = replace(kGood, "resolution: [12, 8]", "resolution: 0");
  expect_error(zero, line_of(zero, "resolution"), "terrain.resolution", "at least 1");
  const std::string side = replace(kGood, "resolution: [12, 8]", "resolution: [100000, 8]");
  expect_error(side, line_of(side, "resolution"), "terrain.resolution", "absurd");
  const std::string total = replace(kGood, "resolution: [12, 8]", "resolution: 20000");
  expect_error(total, line_of(total, "resolution"), "terrain.resolution", "absurd");
  const std::string huge = replace(kGood, "resolution: [12, 8]", "resolution: 99999999999999999999");
  expect_error(huge, line_of(huge, "resolution"), "terrain.resolution", "out of range");
  const std::string fraction = replace(kGood, "resolution: [12, 8]", "resolution: 12.5");
  expect_error(fraction, line_of(fraction, "resolution"), "terrain.resolution", "whole number");
}

TEST(ScenarioErrors, WrongTypesAreRefused) {
  const std::string word = replace(kGood, "rate_hz: 250", "rate_hz: fast");
  expect_error(word, line_of(word, "fast"), "rate_hz", "expected a number, got 'fast'");
  const std::string short_list = replace(kGood, "[0.0, 0.7, 4.1]", "[0.0, 0.7]");
  expect_error(short_list, line_of(short_list, "[0.0, 0.7]"), "cuts[0].keyframes[1].position_m",
               "3 numbers");
  const std::string scalar_blade = replace(kGood, "blade: {length_m: 1.25}", "blade: 1.25");
  expect_error(scalar_blade, line_of(scalar_blade, "blade: 1.25"), "blade", "mapping");
  const std::string cuts_map = kGood.substr(0, kGood.find("cuts:")) + "cuts: {name: A}\n";
  expect_error(cuts_map, line_of(cuts_map, "cuts:"), "cuts", "expected a list");
}

TEST(ScenarioErrors, KeyframesMustStrictlyIncrease) {
  const std::string backwards = replace(kGood, "t_s: 1.5", "t_s: -0.0");
  expect_error(backwards, line_of(backwards, "t_s: -0.0"), "cuts[0].keyframes[1].t_s",
               "strictly increase");
  const std::string same = replace(kGood, "t_s: 1.5", "t_s: 0.0");
  expect_error(same, line_of(same, "{t_s: 0.0, position_m: [0.0, 0.7"),
               "cuts[0].keyframes[1].t_s", "strictly increase");
  const std::string none = replace(
      kGood, "    keyframes:\n      - {t_s: 0.25, position_m: [0.5, 0.6, 4.1]}", "    keyframes: []");
  expect_error(none, line_of(none, "keyframes: []"), "cuts[1].keyframes", "at least one");
}

TEST(ScenarioErrors, SequenceMustNameDefinedCuts) {
  const std::string text = replace(kGood, "sequence: [B_2, A, B_2]", "sequence: [B_2, D]");
  expect_error(text, line_of(text, "sequence"), "sequence[1]", "unknown cut 'D'");
  const std::string empty = replace(kGood, "sequence: [B_2, A, B_2]", "sequence: []");
  expect_error(empty, line_of(empty, "sequence"), "sequence", "empty");
}

TEST(ScenarioErrors, CutListAndNamesAreChecked) {
  const std::string dup = replace(kGood, "- name: B_2", "- name: A");
  expect_error(dup, line_of(dup, "- name: A\n    keyframes:\n      - {t_s: 0.25"),
               "cuts[1].name", "duplicate cut name 'A'");
  const std::string bad_name = replace(kGood, "- name: B_2", "- name: 'B,2'");
  expect_error(bad_name, line_of(bad_name, "'B,2'"), "cuts[1].name", "letters, digits");
  const std::string no_cuts = kGood.substr(0, kGood.find("cuts:")) + "cuts: []\n";
  expect_error(no_cuts, line_of(no_cuts, "cuts: []"), "cuts", "empty");
}

TEST(ScenarioErrors, UnknownGeneratorAndRepresentation) {
  const std::string gen = replace(kGood, "generator: mound", "generator: hill");
  expect_error(gen, line_of(gen, "hill"), "terrain.generator", "unknown generator 'hill'");
  const std::string rep = replace(kGood, "representation: columns", "representation: voxels");
  expect_error(rep, line_of(rep, "voxels"), "representation", "unknown representation");
  const std::string block = replace(kGood, "generator: mound", "generator: box");
  expect_error(block, line_of(block, "  mound:"), "terrain.mound", "only allowed with");
}

TEST(ScenarioErrors, ImageAndGeneratorBothOrNeither) {
  const std::string both = replace(kGood, "  generator: mound", "  generator: mound\n  image: x.png");
  expect_error(both, line_of(both, "terrain:"), "terrain", "not both");
  const std::string neither = replace(kGood, "  generator: mound\n", "");
  expect_error(neither, line_of(neither, "terrain:"), "terrain", "one of them is required");
}

TEST(ScenarioErrors, MissingImageNamesThePathAndTheField) {
  const std::string text = R"(terrain:
  image: ../images/nothing_here.png
  size_m: [1, 1]
  full_scale_m: 1
blade: {length_m: 1}
cuts: [{name: a, keyframes: [{t_s: 0, position_m: [0, 0, 0]}]}]
)";
  expect_error(text, 2, "terrain.image", "/some/folder/../images/nothing_here.png");
  EXPECT_NE(parse_error(text).find("not found"), std::string::npos);
}

TEST_F(ScenarioTest, CorruptImageNamesTheImageAndTheField) {
  write("junk.png", "this is not a PNG file at all");
  const std::string text = R"(terrain:
  image: junk.png
  size_m: [1, 1]
  full_scale_m: 1
blade: {length_m: 1}
cuts: [{name: a, keyframes: [{t_s: 0, position_m: [0, 0, 0]}]}]
)";
  const fs::path path = write("s.yaml", text);
  try {
    load_scenario(path);
    FAIL() << "corrupt image accepted";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_EQ(m.rfind(path.string() + ":2: terrain.image: ", 0), 0u) << m;
    EXPECT_NE(m.find("junk.png"), std::string::npos) << m;
  }
}

TEST(ScenarioErrors, MalformedYamlGivesFileAndLine) {
  const std::string text = "name: x\nterrain: {generator: mound\nblade: [1, 2\n";
  const std::string m = parse_error(text);
  EXPECT_EQ(m.rfind("/some/folder/bad.yaml:", 0), 0u) << m;
  EXPECT_NE(m.find("malformed YAML"), std::string::npos) << m;
  const std::string tabs = replace(kGood, "rate_hz: 250", "rate_hz: [250");
  const std::string m2 = parse_error(tabs);
  EXPECT_NE(m2.find("malformed YAML"), std::string::npos) << m2;
  EXPECT_NE(m2.find("bad.yaml:"), std::string::npos) << m2;
}

TEST(ScenarioErrors, EmptyDocumentAndNonMappingDocument) {
  EXPECT_NE(parse_error("").find("bad.yaml:1: "), std::string::npos) << parse_error("");
  EXPECT_NE(parse_error("- 1\n- 2\n").find("expected a mapping"), std::string::npos);
}

TEST(ScenarioErrors, AbsurdlyLongCutIsRefused) {
  const std::string text = replace(kGood, "t_s: 1.5", "t_s: 1e9");
  expect_error(text, line_of(text, "1e9"), "cuts[0].keyframes[1].t_s", "absurd");
}

// A whole sequence is capped too: cut A lasts 3e5 s (7.5e7 steps at 250 Hz,
// under the per-cut cap), and the sequence runs it twice (1.5e8 steps).
TEST(ScenarioErrors, AbsurdlyLongSequenceIsRefused) {
  std::string text = replace(kGood, "t_s: 1.5", "t_s: 3e5");
  EXPECT_NO_THROW(parse_scenario(replace(text, "sequence: [B_2, A, B_2]", "sequence: [A]"), "x.yaml"));
  text = replace(text, "sequence: [B_2, A, B_2]", "sequence: [A, A]");
  expect_error(text, line_of(text, "sequence:"), "sequence", "1e8 steps");
  Scenario sc = parse_scenario(replace(kGood, "t_s: 1.5", "t_s: 3e5"), "x.yaml");
  try {
    apply_overrides(sc, std::nullopt, std::nullopt, std::vector<std::string>{"A", "A"});
    FAIL() << "accepted";
  } catch (const terracut::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--sequence"), std::string::npos) << e.what();
  }
}

// Finite but absurd numbers (beyond 1e9 in SI units) are refused where they
// are written, before they can overflow heights or volumes.
TEST(ScenarioErrors, AbsurdMagnitudesAreRefused) {
  const std::string size = replace(kGood, "size_m: [2.0, 1.0]", "size_m: [1e300, 1.0]");
  expect_error(size, line_of(size, "1e300"), "terrain.size_m[0]", "1e9");
  const std::string scale = replace(kGood, "full_scale_m: 0.3", "full_scale_m: 2e9");
  expect_error(scale, line_of(scale, "2e9"), "terrain.full_scale_m", "1e9");
}

// ---- Bounded parsing: keyframe caps, nesting depth, top-level keys --------

// A scenario whose cuts hold the given numbers of keyframes, each written as
// `element` (the scan counts list elements, whatever they are), followed by
// `tail`.
std::string scenario_with_keyframes(const std::vector<std::size_t>& counts, const std::string& element,
                                    const std::string& tail = "") {
  std::string text = "terrain: {generator: plane, resolution: 4, size_m: [1, 1], full_scale_m: 1}\n"
                     "blade: {length_m: 0.5}\ncuts:\n";
  for (std::size_t i = 0; i < counts.size(); ++i) {
    text += "  - name: c" + std::to_string(i) + "\n    keyframes:\n";
    for (std::size_t k = 0; k < counts[i]; ++k) text += "      - " + element + "\n";
  }
  return text + tail;
}

using test::peak_rss_bytes;
using test::small_growth;

// One keyframe over the cap is refused while the text is scanned, naming the
// cut's keyframes and the cap: before the document is built (a malformed
// line after the keyframes is never reached) and with little memory
// (building 100000 keyframes in yaml-cpp takes about 640 MB).
TEST(ScenarioErrors, KeyframeCapPerCutRefusesWhileScanning) {
  const std::string cap = std::to_string(kMaxKeyframesPerCut);
  const std::string text = scenario_with_keyframes({2, kMaxKeyframesPerCut + 1},
                                                   "{t_s: 0, position_m: [0.5, 0.1, 0.5]}", "broken: [\n");
  const std::int64_t before = peak_rss_bytes();
  const std::string m = parse_error(text);
  EXPECT_LT(peak_rss_bytes() - before, small_growth(64));
  const int line = line_of(text, "  - name: c1") + 1;  // the line of its key
  EXPECT_EQ(m.rfind("/some/folder/bad.yaml:" + std::to_string(line) + ": cuts[1].keyframes: ", 0), 0u) << m;
  EXPECT_NE(m.find("more than " + cap + " keyframes; a cut may have at most " + cap), std::string::npos) << m;
  // At the cap the scan lets it through (these elements then fail as keyframes).
  const std::string at_cap = parse_error(scenario_with_keyframes({kMaxKeyframesPerCut}, "0"));
  EXPECT_NE(at_cap.find("cuts[0].keyframes[0]: expected a mapping"), std::string::npos) << at_cap;
}

// The cap on all cuts together, and the same caps for lists given by alias
// (which the scan does not expand; they are counted before any keyframe is read).
TEST(ScenarioErrors, KeyframeCapInAllCutsIsRefused) {
  const std::string all = std::to_string(kMaxKeyframes);
  const std::size_t third = kMaxKeyframes / 3 + 1;
  const std::string text = scenario_with_keyframes({third, third, third}, "0", "broken: [\n");
  ASSERT_GT(3 * third, kMaxKeyframes);
  ASSERT_LE(2 * third, kMaxKeyframes);
  const std::string m = parse_error(text);
  EXPECT_EQ(m.rfind("/some/folder/bad.yaml:" + std::to_string(line_of(text, "  - name: c2") + 1) +
                        ": cuts[2].keyframes: ", 0), 0u) << m;
  EXPECT_NE(m.find("the cuts have more than " + all + " keyframes in all; a scenario may have at most " + all),
            std::string::npos) << m;

  std::string list;
  for (std::size_t k = 0; k < kMaxKeyframesPerCut; ++k) list += k ? ", 0" : "0";
  const std::string aliased = "terrain: {generator: plane, resolution: 4, size_m: [1, 1], full_scale_m: 1}\n"
                              "blade: {length_m: 0.5}\ncuts:\n"
                              "  - {name: a, keyframes: &k [" + list + "]}\n"
                              "  - {name: b, keyframes: *k}\n"
                              "  - {name: c, keyframes: *k}\n";
  const std::string m2 = parse_error(aliased);
  EXPECT_EQ(m2.rfind("/some/folder/bad.yaml:6: cuts[2].keyframes: the cuts have more than " + all, 0), 0u) << m2;
}

// Lists and mappings nested absurdly deep: the message says so and where,
// instead of yaml-cpp's "bad file".
TEST(ScenarioErrors, DeepNestingSaysSoAndWhere) {
  const std::string deep = std::string(1000, '[') + std::string(1000, ']');
  const std::string text = replace(kGood, "representation: columns", "representation:\n  - " + deep);
  const std::string m = parse_error(text);
  EXPECT_EQ(m.rfind("/some/folder/bad.yaml:" + std::to_string(line_of(text, "  - [[")) + ": representation[0][0]", 0),
            0u) << m;
  EXPECT_NE(m.find("nested more than " + std::to_string(kMaxScenarioDepth) + " levels deep"), std::string::npos) << m;
  EXPECT_EQ(m.find("bad file"), std::string::npos) << m;
  // Just within the limit, the scan passes it on (and the field is then refused as a list).
  const int within = kMaxScenarioDepth - 1;
  const std::string ok = replace(kGood, "representation: columns",
                                 "representation: " + std::string(within, '[') + std::string(within, ']'));
  EXPECT_NE(parse_error(ok).find("representation: expected a text value, got a list"), std::string::npos)
      << parse_error(ok);
}

// An unknown top-level key is refused while scanning (a malformed line after
// it is never reached), with the message the document's check gives, and so
// is a top-level key given twice.
TEST(ScenarioErrors, TopLevelKeysAreCheckedWhileScanning) {
  const std::string text = kGood + "bad_key: 1\nbroken: [\n";
  expect_error(text, line_of(text, "bad_key"), "bad_key",
               "unknown key 'bad_key'; allowed keys here: name, description, terrain, representation, "
               "rate_hz, blade, cuts, sequence, reference, soil");
  const std::string twice = kGood + "rate_hz: 100\n";
  expect_error(twice, line_of(twice, "rate_hz: 100"), "rate_hz",
               "key given twice (first at line " + std::to_string(line_of(kGood, "rate_hz")) + ")");
  // Malformed YAML before any such key is still reported as malformed.
  EXPECT_NE(parse_error("name: [x\nbad_key: 1\n").find("malformed YAML"), std::string::npos);
}

// The error of loading the scenario file, or "" when it loads.
std::string load_error(const fs::path& path) {
  std::string message;
  try { load_scenario(path); } catch (const InputError& e) { message = e.what(); }
  return message;
}

// A scenario path that is a symbolic link loop says so, rather than "not
// found"; a dangling link says where it points; the same for the image.
TEST_F(ScenarioTest, SymlinkLoopAndDanglingLinkAreNamed) {
  fs::create_symlink(dir_ / "b.yaml", dir_ / "a.yaml");
  fs::create_symlink(dir_ / "a.yaml", dir_ / "b.yaml");
  const std::string loop = load_error(dir_ / "a.yaml");
  EXPECT_EQ(loop.rfind((dir_ / "a.yaml").string() + ": cannot be resolved: it is a symbolic link loop", 0), 0u)
      << loop;
  EXPECT_EQ(loop.find("not found"), std::string::npos) << loop;

  fs::create_symlink(dir_ / "gone.yaml", dir_ / "dangling.yaml");
  const std::string dangling = load_error(dir_ / "dangling.yaml");
  EXPECT_NE(dangling.find("scenario file not found (a symbolic link to '" + (dir_ / "gone.yaml").string() +
                          "', which does not exist)"),
            std::string::npos) << dangling;

  fs::create_symlink(dir_ / "y.png", dir_ / "x.png");
  fs::create_symlink(dir_ / "x.png", dir_ / "y.png");
  const fs::path path = write("image.yaml", R"(terrain:
  image: x.png
  size_m: [1, 1]
  full_scale_m: 1
blade: {length_m: 1}
cuts: [{name: a, keyframes: [{t_s: 0, position_m: [0, 0, 0]}]}]
)");
  const std::string image = load_error(path);
  EXPECT_EQ(image.rfind(path.string() + ":2: terrain.image: image file '" + (dir_ / "x.png").string() +
                            "' cannot be resolved: it is a symbolic link loop", 0),
            0u) << image;
}

TEST_F(ScenarioTest, MissingScenarioFileIsNamed) {
  const fs::path path = dir_ / "nope.yaml";
  try {
    load_scenario(path);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
  }
  EXPECT_THROW(load_scenario(dir_), InputError);  // a folder, not a file
}

// ---- The shipped scenarios -------------------------------------------------

fs::path shipped(const char* name) { return fs::path(TERRACUT_SOURCE_DIR) / "scenarios" / name; }

TEST(ShippedScenarios, Experiment1IsTheHorizontalCutThroughTheMound) {
  const Scenario sc = load_scenario(shipped("paper_experiment1.yaml"));
  ASSERT_TRUE(sc.reference_mound.has_value());
  EXPECT_EQ(sc.image.cols, 256);
  EXPECT_DOUBLE_EQ(sc.full_scale_m, sc.reference_mound->height_m);
  ASSERT_EQ(sc.cuts.size(), 1u);
  const Motion& cut = sc.cuts[0];
  EXPECT_DOUBLE_EQ(cut.duration_s(), 2.0);
  const Vec3 a = cut.keyframes.front().pose.position_m;
  const Vec3 b = cut.keyframes.back().pose.position_m;
  EXPECT_DOUBLE_EQ(a.y, 0.5 * sc.reference_mound->height_m);  // half the peak
  EXPECT_DOUBLE_EQ(a.y, b.y);
  EXPECT_LT(a.z, sc.origin_m.z);                        // starts before the terrain
  EXPECT_GT(b.z, sc.origin_m.z + sc.size_z_m);          // ends after it
  EXPECT_GE(sc.blade.length_m, 2.0 * sc.reference_mound->radius_m);
  // The image is the reference dome: resampled heights match it where it is smooth.
  Scenario at50 = sc;
  apply_overrides(at50, Resolution{50, 50}, std::nullopt, std::nullopt);
  const std::vector<float> h = build_initial_heights(at50);
  const double centre = h[25 * 50 + 25];
  EXPECT_NEAR(centre, height_at(*sc.reference_mound, 0.51, 0.51), 0.002);
}

TEST(ShippedScenarios, Experiment2DefinesCutsABC) {
  const Scenario sc = load_scenario(shipped("paper_experiment2.yaml"));
  EXPECT_EQ(sc.resolution, (Resolution{35, 35}));
  for (float v : build_initial_heights(sc)) EXPECT_EQ(v, 1.0f);  // a full cube
  ASSERT_EQ(sc.cuts.size(), 3u);
  EXPECT_EQ(sc.sequence_names(), (std::vector<std::string>{"A", "B", "C"}));
  // Direction of the blade (local +X) at the end of each cut: A tilts up 45
  // degrees at +X (its -X end dips), C tilts the other way with slope 1/2.
  auto end_dir = [&](int i) { return rotate(sc.cuts[std::size_t(i)].keyframes.back().pose.orientation, {1, 0, 0}); };
  EXPECT_NEAR(end_dir(0).y / end_dir(0).x, 1.0, 1e-9);
  EXPECT_NEAR(end_dir(1).y, 0.0, 1e-12);
  EXPECT_NEAR(end_dir(2).y / end_dir(2).x, -0.5, 1e-7);
  // B runs the opposite way along Z to A and C.
  const auto dz = [&](int i) {
    return sc.cuts[std::size_t(i)].keyframes.back().pose.position_m.z -
           sc.cuts[std::size_t(i)].keyframes.front().pose.position_m.z;
  };
  EXPECT_GT(dz(0), 0.0);
  EXPECT_LT(dz(1), 0.0);
  EXPECT_GT(dz(2), 0.0);
  for (const Motion& m : sc.cuts) EXPECT_DOUBLE_EQ(m.duration_s(), 2.0);
}

}  // namespace
}  // namespace terracut::io
