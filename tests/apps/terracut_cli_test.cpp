// The `terracut` command-line tool, run as a separate process: help texts,
// a successful run, bad input giving a message and exit code 1 (never a
// crash), heightmap, reproduce with and without figures, and validate (the
// soil's physical checks).
#include <gtest/gtest.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "terracut/core/generators.hpp"
#include "terracut/io/image.hpp"

extern char** environ;

#include "../support/spawn.hpp"

namespace {

namespace fs = std::filesystem;

struct Result {
  bool exited = false;  // false: killed by a signal (a crash)
  int code = -1;
  int signal = 0;
  std::string out;
  std::string err;
};

std::string slurp(const fs::path& path) {
  std::ifstream f(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

class CliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("terracut_cli_test_" + std::to_string(getpid()) + "_" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Runs a program with stdout and stderr captured in files.
  Result exec(std::vector<std::string> argv) {
    const fs::path out = dir_ / "stdout.txt";
    const fs::path err = dir_ / "stderr.txt";
    Result r;
    const pid_t pid = terracut::test::spawn(argv, out, err);
    if (pid < 0) {
      ADD_FAILURE() << "cannot start " << argv[0];
      return r;
    }
    int status = 0;
    waitpid(pid, &status, 0);
    r.exited = WIFEXITED(status);
    r.code = r.exited ? WEXITSTATUS(status) : -1;
    r.signal = WIFSIGNALED(status) ? WTERMSIG(status) : 0;
    r.out = slurp(out);
    r.err = slurp(err);
    return r;
  }

  Result terracut(std::vector<std::string> args) {
    args.insert(args.begin(), TERRACUT_BIN);
    return exec(std::move(args));
  }

  fs::path write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name) << text;
    return dir_ / name;
  }

  static std::string scenario(const char* name) {
    return (fs::path(TERRACUT_SOURCE_DIR) / "scenarios" / name).string();
  }

  fs::path dir_;
};

// A failure that is reported, not a crash: exit code 1 and a message.
void expect_clean_failure(const Result& r, const std::vector<std::string>& fragments, int code = 1) {
  EXPECT_TRUE(r.exited) << "killed by signal " << r.signal;
  EXPECT_EQ(r.code, code) << r.err;
  for (const std::string& f : fragments)
    EXPECT_NE(r.err.find(f), std::string::npos) << "stderr lacks '" << f << "':\n" << r.err;
}

TEST_F(CliTest, HelpOfEveryCommandSucceedsAndDescribesTheOptions) {
  const Result top = terracut({"--help"});
  EXPECT_EQ(top.code, 0);
  for (const char* word : {"run", "heightmap", "reproduce", "validate", "calibrate", "Exit codes"})
    EXPECT_NE(top.out.find(word), std::string::npos) << word;

  const Result run = terracut({"run", "--help"});
  EXPECT_EQ(run.code, 0);
  for (const char* word : {"--out", "--resolution", "COLSxROWS", "--representation", "columns",
                           "--sequence", "--quiet", "contact.csv", "contact_length",
                           "removed_volume", "height.npy", "removed.png", "summary.json"})
    EXPECT_NE(run.out.find(word), std::string::npos) << word;

  const Result hm = terracut({"heightmap", "--help"});
  EXPECT_EQ(hm.code, 0);
  for (const char* word : {"mound", "box", "plane", "--resolution", "--out", "--size",
                           "--full-scale", "--height", "--centre", "--radius", "--box-min",
                           "--box-max", "metres"})
    EXPECT_NE(hm.out.find(word), std::string::npos) << word;

  const Result rep = terracut({"reproduce", "--help"});
  EXPECT_EQ(rep.code, 0);
  for (const char* word : {"--out", "--scenarios", "--tools-dir", "--python", "--no-plots",
                           "report.md", "fig8_", "fig9_", "fig13_", "fig14_", "convergence.png"})
    EXPECT_NE(rep.out.find(word), std::string::npos) << word;

  const Result val = terracut({"validate", "--help"});
  EXPECT_EQ(val.code, 0);
  for (const char* word : {"--out", "--no-plot", "--quiet", "--python", "--tools-dir",
                           "report.md", "checks.csv", "cone/profiles.csv", "bulldozing/pile.csv",
                           "conservation/volume.csv", "soil_cone.png", "degrees", "m^3",
                           "microseconds", "Exit code"})
    EXPECT_NE(val.out.find(word), std::string::npos) << word;
  // Its checks are numbered as report.md's sections: cone, slopes,
  // bulldozing, conservation, bucket, speed.
  {
    std::size_t at = 0;
    int number = 1;
    for (const char* section : {"cone", "slopes", "bulldozing", "conservation", "bucket", "speed"}) {
      const std::string line = "  " + std::to_string(number++) + " " + section;
      const std::size_t found = val.out.find(line, at);
      EXPECT_NE(found, std::string::npos) << "validate --help lacks '" << line << "' after the previous check";
      if (found != std::string::npos) at = found;
    }
  }

  EXPECT_EQ(terracut({"--version"}).code, 0);
}

TEST_F(CliTest, RunWritesEveryOutput) {
  const fs::path out = dir_ / "out";
  const Result r = terracut({"run", scenario("mound_generator.yaml"), "--out", out.string(),
                             "--resolution", "16", "--quiet"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.out, "");  // --quiet
  for (const char* name : {"contact.csv", "height.npy", "removed.npy", "height.png",
                           "removed.png", "summary.json"}) {
    EXPECT_TRUE(fs::exists(out / name)) << name;
    EXPECT_GT(fs::file_size(out / name), 0u) << name;
  }
  EXPECT_EQ(slurp(out / "contact.csv").rfind("t,cut,x,y,z,qw,qx,qy,qz,contact_length,", 0), 0u);
}

// A blade with a top (scenarios/push_over_top.yaml): the run's line says
// how much fell over it, and summary.json holds the same figure; a blade
// without one says nothing of a top.
TEST_F(CliTest, RunSaysWhatFellOverTheBladesTop) {
  const fs::path out = dir_ / "over";
  const Result r = terracut({"run", scenario("push_over_top.yaml"), "--out", out.string()});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("over the blade's top "), std::string::npos) << r.out;
  const std::string summary = slurp(out / "summary.json");
  EXPECT_NE(summary.find("\"over_top_m3\""), std::string::npos);
  EXPECT_NE(summary.find("\"blade_height_m\": 0.1"), std::string::npos);
  const Result plain = terracut({"run", scenario("push_pile.yaml"), "--out", (dir_ / "plain").string()});
  ASSERT_EQ(plain.code, 0) << plain.err;
  EXPECT_EQ(plain.out.find("over the blade's top"), std::string::npos) << plain.out;
}

// With bodies, `terracut run` steps the Bullet world on the same terrain and
// writes bodies.csv: a box resting on 0.1 m of soil sinks at least by the
// 0.05 m cut under it (the blade's plate also shoves it) but never through
// the floor, and a box away from the cut stays where it was. (The physics
// itself is tested in tests/bullet.)
TEST_F(CliTest, RunWithBodiesWritesTheirPoses) {
  const fs::path sc = write("bodies.yaml", R"(
terrain: {generator: plane, plane: {height_m: 0.1}, resolution: 40, size_m: [1, 1], full_scale_m: 0.2}
blade: {length_m: 0.6}
bodies:
  - {name: cut, shape: box, size_m: [0.1, 0.1, 0.1], mass_kg: 1, position_m: [0.3, 0.15, 0.5]}
  - {name: still, shape: box, size_m: [0.1, 0.1, 0.1], mass_kg: 1, position_m: [0.85, 0.15, 0.5]}
cuts:
  - name: under
    keyframes:
      - {t_s: 0.0, position_m: [0.3, 0.05, 0.1]}
      - {t_s: 0.8, position_m: [0.3, 0.05, 0.9]}
      - {t_s: 1.5, position_m: [0.3, 0.05, 0.9]}
)");
  const fs::path out = dir_ / "out";
  const Result r = terracut({"run", sc.string(), "--out", out.string(), "--quiet"});
  if (r.err.find("built without Bullet") != std::string::npos) GTEST_SKIP() << r.err;
  ASSERT_EQ(r.code, 0) << r.err;
  std::ifstream csv(out / "bodies.csv");
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, "t,body,name,x,y,z,qw,qx,qy,qz,vx,vy,vz");
  double first_y[2] = {NAN, NAN}, last_y[2] = {NAN, NAN}, last_x[2] = {NAN, NAN};
  while (std::getline(csv, line)) {
    double t, x, y;
    int body;
    char name[32];
    ASSERT_EQ(std::sscanf(line.c_str(), "%lf,%d,%31[^,],%lf,%lf", &t, &body, name, &x, &y), 5) << line;
    ASSERT_TRUE(body == 0 || body == 1);
    if (std::isnan(first_y[body])) first_y[body] = y;
    last_y[body] = y;
    last_x[body] = x;
  }
  EXPECT_GT(first_y[0] - last_y[0], 0.05 - 0.006);
  EXPECT_GT(last_y[0], 0.05 - 0.006);  // half its height above the floor
  EXPECT_NEAR(last_y[1], first_y[1], 0.002);
  EXPECT_NEAR(last_x[1], 0.85, 0.002);
  EXPECT_NE(slurp(out / "summary.json").find("\"bodies\""), std::string::npos);
}

// What the device check lowers is said once, when the session is built,
// and kept in summary.json's warnings (experiment 1's surface and cutting
// damping exceed a Falcon's).
TEST_F(CliTest, HapticsSaysEachDeviceCheckWarningOnce) {
  const fs::path out = dir_ / "exp1";
  const Result r = terracut({"haptics", scenario("paper_experiment1.yaml"), "--device", "script",
                             "--no-plot", "--quiet", "--out", out.string()});
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string line = "terracut haptics: warning: cutting damping";
  const std::size_t first = r.err.find(line);
  ASSERT_NE(first, std::string::npos) << r.err;
  EXPECT_EQ(r.err.find(line, first + 1), std::string::npos) << "said twice:\n" << r.err;
  EXPECT_NE(slurp(out / "summary.json").find("cutting damping"), std::string::npos);
}

// `terracut haptics` on a scenario with bodies: the Bullet world is stepped
// by the haptic loop, bodies.csv is written beside haptics.csv (whose bodies'
// force columns are filled while the plate pushes the rock) and summary.json
// has a "bodies" entry. A build without Bullet refuses the scenario, naming
// it, with exit code 1 and nothing written. (The forces themselves are
// checked in bodies_engine_test.cpp.)
TEST_F(CliTest, HapticsWithBodiesFeelsThemAndWritesTheirPoses) {
  const fs::path out = dir_ / "rock";
  const Result r = terracut({"haptics", scenario("rock_push.yaml"), "--device", "script",
                             "--no-plot", "--quiet", "--out", out.string()});
  if (r.err.find("built without Bullet") != std::string::npos) {
    expect_clean_failure(r, {"rock_push.yaml", "bodies", "libbullet-dev"});
    EXPECT_FALSE(fs::exists(out / "haptics.csv"));
    GTEST_SKIP() << "built without Bullet: " << r.err;
  }
  ASSERT_EQ(r.code, 0) << r.err;
  for (const char* name : {"haptics.csv", "summary.json", "bodies.csv"})
    EXPECT_TRUE(fs::exists(out / name)) << name;
  const std::string bodies = slurp(out / "bodies.csv");
  EXPECT_EQ(bodies.rfind("t,body,name,x,y,z,qw,qx,qy,qz,vx,vy,vz\n0,0,rock,", 0), 0u);
  // One row for the start, then one per tick (4.5 s at 1 kHz).
  EXPECT_EQ(std::count(bodies.begin(), bodies.end(), '\n'), 1 + 1 + 4500);
  const std::string summary = slurp(out / "summary.json");
  EXPECT_NE(summary.find("\"bodies\": {"), std::string::npos) << summary;
  EXPECT_NE(summary.find("\"peak_tool_force_n\""), std::string::npos) << summary;
  // haptics.csv: some ticks have a force from the rock along +Z (fb_z > 0).
  std::ifstream csv(out / "haptics.csv");
  std::string line;
  std::getline(csv, line);
  std::vector<std::string> names;
  for (std::size_t a = 0, b; a <= line.size(); a = b + 1) {
    b = line.find(',', a);
    if (b == std::string::npos) b = line.size();
    names.push_back(line.substr(a, b - a));
  }
  const auto fb_z = std::find(names.begin(), names.end(), "fb_z");
  ASSERT_NE(fb_z, names.end()) << line;
  const std::size_t col = std::size_t(fb_z - names.begin());
  int pushed = 0;
  while (std::getline(csv, line)) {
    std::size_t at = 0;
    for (std::size_t k = 0; k < col; ++k) at = line.find(',', at) + 1;
    if (std::strtod(line.c_str() + at, nullptr) > 0.0) ++pushed;
  }
  EXPECT_GT(pushed, 800);

  const Result help = terracut({"haptics", "--help"});
  for (const char* word : {"bodies.csv", "fb_x", "rock_push.yaml"})
    EXPECT_NE(help.out.find(word), std::string::npos) << word;
}

// --realtime paces the steps to the wall clock and reports the loop's timing.
// Only the presence and consistency of the figures is checked: their values
// depend on the machine's load.
TEST_F(CliTest, RealtimeRunReportsStepTimeJitterAndMissedDeadlines) {
  const fs::path out = dir_ / "out";
  const Result r = terracut({"run", scenario("mound_generator.yaml"), "--out", out.string(),
                             "--resolution", "16", "--realtime"});
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string summary = slurp(out / "summary.json");
  for (const char* key : {"\"realtime\"", "\"missed_deadlines\"", "\"period_jitter\"",
                          "\"step_time\"", "\"p50_us\"", "\"p99_us\"", "\"max_us\""})
    EXPECT_NE(summary.find(key), std::string::npos) << key;
  // A readable line on stdout (the scenario steps at 500 Hz); the JSON only
  // in summary.json.
  EXPECT_NE(r.out.find("realtime at 500 Hz:"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("missed deadlines"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find('{'), std::string::npos) << r.out;
}

TEST_F(CliTest, RunOptionsOverrideTheScenario) {
  const fs::path out = dir_ / "out";
  const Result r = terracut({"run", scenario("mound_generator.yaml"), "--out", out.string(),
                             "--resolution", "10x6", "--representation", "columns",
                             "--sequence", "pass2,pass2"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("mound_generator"), std::string::npos) << r.out;  // the summary line
  const std::string summary = slurp(out / "summary.json");
  EXPECT_NE(summary.find("\"representation\": \"columns\""), std::string::npos) << summary;
  EXPECT_NE(summary.find("\"resolution\": [\n        10,\n        6\n      ]"), std::string::npos)
      << summary;
  const std::string csv = slurp(out / "contact.csv");
  EXPECT_EQ(csv.find(",pass1,"), std::string::npos);
  EXPECT_NE(csv.find(",pass2,"), std::string::npos);
}

TEST_F(CliTest, BadScenarioExitsWithTheMessageOnStderr) {
  const fs::path bad = write("bad.yaml",
                             "terrain:\n  generator: plane\n  resolution: 4\n  size_m: [1, 1]\n"
                             "  full_scale_m: 1\nblade: {length_m: 1, width_m: 2}\n"
                             "cuts: [{name: a, keyframes: [{t_s: 0, position_m: [0, 0, 0]}]}]\n");
  expect_clean_failure(terracut({"run", bad.string(), "--out", (dir_ / "o").string()}),
                       {bad.string() + ":6: blade.width_m: unknown key"});
  EXPECT_FALSE(fs::exists(dir_ / "o" / "contact.csv"));

  const fs::path malformed = write("malformed.yaml", "terrain: {generator: plane\n");
  expect_clean_failure(terracut({"run", malformed.string(), "--out", (dir_ / "o").string()}),
                       {malformed.string() + ":", "malformed YAML"});

  const fs::path nan = write("nan.yaml",
                             "terrain:\n  generator: plane\n  resolution: 4\n  size_m: [1, .nan]\n"
                             "  full_scale_m: 1\nblade: {length_m: 1}\n"
                             "cuts: [{name: a, keyframes: [{t_s: 0, position_m: [0, 0, 0]}]}]\n");
  expect_clean_failure(terracut({"run", nan.string(), "--out", (dir_ / "o").string()}),
                       {nan.string() + ":4: terrain.size_m[1]", "finite"});

  const fs::path no_image = write("noimage.yaml",
                                  "terrain:\n  image: missing.png\n  size_m: [1, 1]\n"
                                  "  full_scale_m: 1\nblade: {length_m: 1}\n"
                                  "cuts: [{name: a, keyframes: [{t_s: 0, position_m: [0, 0, 0]}]}]\n");
  expect_clean_failure(terracut({"run", no_image.string(), "--out", (dir_ / "o").string()}),
                       {":2: terrain.image", (dir_ / "missing.png").string()});

  expect_clean_failure(
      terracut({"run", (dir_ / "nothing.yaml").string(), "--out", (dir_ / "o").string()}),
      {(dir_ / "nothing.yaml").string(), "not found"});
}

TEST_F(CliTest, BadOptionsAreReported) {
  const std::string sc = scenario("mound_generator.yaml");
  const std::string out = (dir_ / "o").string();
  expect_clean_failure(terracut({"run", sc, "--out", out, "--resolution", "0"}), {"--resolution"});
  expect_clean_failure(terracut({"run", sc, "--out", out, "--resolution", "100000"}),
                       {"--resolution", "absurd"});
  expect_clean_failure(terracut({"run", sc, "--out", out, "--sequence", "pass1,nope"}),
                       {"--sequence", "'nope'"});
  // Command-line usage errors exit with 2.
  expect_clean_failure(terracut({"run", sc, "--out", out, "--representation", "voxels"}),
                       {"--representation"}, 2);
  expect_clean_failure(terracut({"run", sc}), {"--out"}, 2);
  expect_clean_failure(terracut({}), {"subcommand", "run, heightmap"}, 2);
  // A word that is no subcommand is named, with the real ones listed.
  expect_clean_failure(terracut({"frobnicate"}),
                       {"unknown subcommand 'frobnicate'", "run, heightmap, reproduce, validate"}, 2);
  // An unknown option is named first, before the required ones it hides.
  expect_clean_failure(terracut({"run", "--bogus"}), {"unknown option", "--bogus"}, 2);
  expect_clean_failure(terracut({"run", sc, "--bogus"}), {"--bogus"}, 2);
  // An output folder that cannot be made.
  write("file", "x");
  expect_clean_failure(terracut({"run", sc, "--out", (dir_ / "file" / "sub").string()}),
                       {(dir_ / "file" / "sub").string()});
}

TEST_F(CliTest, HeightmapWritesTheGeneratorAsA16BitPng) {
  const fs::path png = dir_ / "mound.png";
  const Result r = terracut({"heightmap", "mound", "--resolution", "9x7", "--size", "2,1",
                             "--full-scale", "0.5", "--radius", "0.45", "--out", png.string()});
  ASSERT_EQ(r.code, 0) << r.err;
  const terracut::io::Image image = terracut::io::read_png(png);
  ASSERT_EQ(image.cols, 9);
  ASSERT_EQ(image.rows, 7);
  EXPECT_EQ(image.bit_depth, 16);
  terracut::GridSpec spec;
  spec.cols = 9;
  spec.rows = 7;
  spec.size_x_m = 2.0;
  spec.size_z_m = 1.0;
  spec.full_scale_m = 0.5;
  terracut::Generator gen = terracut::default_generator(terracut::GeneratorKind::kMound, spec);
  gen.mound.radius_m = 0.45;
  const std::vector<float> h = terracut::generate_heights(spec, gen);
  for (std::size_t i = 0; i < h.size(); ++i)
    EXPECT_NEAR(image.values[i], h[i] / 0.5, 0.6 / 65535.0) << i;

  expect_clean_failure(terracut({"heightmap", "box", "--resolution", "4", "--radius", "1",
                                 "--out", (dir_ / "b.png").string()}),
                       {"--radius", "mound"});
  expect_clean_failure(terracut({"heightmap", "plane", "--resolution", "4", "--full-scale", "0",
                                 "--out", (dir_ / "p.png").string()}),
                       {"--full-scale"});
  expect_clean_failure(terracut({"heightmap", "plane", "--resolution", "4", "--out",
                                 (dir_ / "no" / "such" / "p.png").string()}),
                       {"p.png"});
}

TEST_F(CliTest, ReproduceWithoutPlotsWritesTheReport) {
  const fs::path out = dir_ / "rep";
  const Result r = terracut({"reproduce", "--out", out.string(), "--no-plots", "--quiet"});
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string report = slurp(out / "report.md");
  for (const char* word : {"Experiment 1", "RMS error", "drop-out", "Experiment 2",
                           "(C,A,B)", "(B,C,A)", "final shapes match"})
    EXPECT_NE(report.find(word), std::string::npos) << word;
  for (const char* rep : {"columns", "surface"}) {
    for (const char* n : {"5", "15", "25", "35", "50", "100", "200"})
      EXPECT_TRUE(fs::exists(out / "exp1" / rep / n / "contact.csv")) << rep << " " << n;
    for (const char* seq : {"ABC", "CAB", "BCA", "AB"})
      EXPECT_TRUE(fs::exists(out / "exp2" / rep / seq / "height.npy")) << rep << " " << seq;
  }
  EXPECT_TRUE(fs::exists(out / "exp1" / "exact.csv"));
  EXPECT_TRUE(fs::exists(out / "exp1" / "errors.csv"));
  EXPECT_TRUE(fs::exists(out / "reproduce.json"));
}

TEST_F(CliTest, ReproduceWithoutPythonStillWritesTheReportAndFails) {
  const fs::path out = dir_ / "rep";
  const Result r = terracut(
      {"reproduce", "--out", out.string(), "--python", "/nonexistent/python3", "--quiet"});
  expect_clean_failure(r, {"/nonexistent/python3", "figures not made"}, 3);
  const std::string report = slurp(out / "report.md");
  EXPECT_NE(report.find("could not be made"), std::string::npos);
  EXPECT_NE(report.find("Experiment 1"), std::string::npos);
  EXPECT_EQ(report.find("fig8_"), std::string::npos);  // no links to figures that do not exist
}

TEST_F(CliTest, ReproduceDrawsEveryFigure) {
  const Result probe = exec({"/usr/bin/python3", "-c", "import numpy, matplotlib"});
  if (probe.code != 0) GTEST_SKIP() << "/usr/bin/python3 with numpy and matplotlib not available";
  const fs::path out = dir_ / "rep";
  const Result r = terracut({"reproduce", "--out", out.string(), "--quiet"});
  ASSERT_EQ(r.code, 0) << r.err;
  for (const char* name :
       {"fig8_columns.png", "fig8_surface.png", "fig9_columns.png", "fig9_surface.png",
        "fig13_columns.png", "fig13_surface.png", "fig14_columns.png", "fig14_surface.png",
        "convergence.png"}) {
    ASSERT_TRUE(fs::exists(out / name)) << name;
    EXPECT_EQ(slurp(out / name).substr(1, 3), "PNG") << name;
    EXPECT_NE(slurp(out / "report.md").find(std::string("](") + name + ")"), std::string::npos)
        << name << " not embedded in report.md";
  }
}

// The soil's physical checks (docs/validation.md) end to end: every output
// is written, and every check passes (exit code 0, no FAIL in the report).
TEST_F(CliTest, ValidateWritesItsOutputsAndEveryCheckPasses) {
  const fs::path out = dir_ / "val";
  const Result r = terracut({"validate", "--out", out.string(), "--no-plot", "--quiet"});
  ASSERT_TRUE(r.exited) << "killed by signal " << r.signal;
  for (const char* name :
       {"report.md", "checks.csv", "validate.json", "cone/profiles.csv", "cone/flanks.csv",
        "cone/height_34.npy", "cone/height_45.npy", "slope/profiles.csv", "slope/slopes.csv",
        "bulldozing/pile.csv", "bulldozing/centre.csv", "bulldozing/wall.csv", "bulldozing/height_w1.npy",
        "bulldozing/height_w2.npy", "conservation/scenario.yaml", "conservation/volume.csv"})
    ASSERT_TRUE(fs::exists(out / name)) << name << "\n" << r.err;
  const std::string report = slurp(out / "report.md");
  for (const char* word : {"A column of sand collapses into a cone", "Slopes below and above",
                           "Bulldozing", "The blade is a wall", "Conservation over a long mixed run", "Speed"})
    EXPECT_NE(report.find(word), std::string::npos) << word;
  EXPECT_EQ(report.find("soil_cone.png"), std::string::npos);  // --no-plot: no figure links
  // The mixed run's scenario is one `terracut run` accepts.
  EXPECT_EQ(terracut({"run", (out / "conservation" / "scenario.yaml").string(), "--out",
                      (dir_ / "mixed").string(), "--quiet"})
                .code,
            0);
  // Every check passes; stderr names the failing ones.
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(report.find("FAIL"), std::string::npos) << r.err;
  EXPECT_EQ(slurp(out / "checks.csv").find("FAIL"), std::string::npos);
}

// With figures: every picture the report shows is drawn (the DEM section's
// surface maps were linked but not drawn by the full run until 2026-12-05).
TEST_F(CliTest, ValidateDrawsEveryFigureItsReportShows) {
  const Result probe = exec({"/usr/bin/python3", "-c", "import numpy, matplotlib"});
  if (probe.code != 0) GTEST_SKIP() << "/usr/bin/python3 with numpy and matplotlib not available";
  const fs::path out = dir_ / "val";
  const Result r = terracut({"validate", "--out", out.string(), "--quiet"});
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string report = slurp(out / "report.md");
  int shown = 0;
  for (std::size_t at = report.find("]("); at != std::string::npos; at = report.find("](", at + 2)) {
    const std::size_t end = report.find(')', at);
    ASSERT_NE(end, std::string::npos);
    const std::string name = report.substr(at + 2, end - at - 2);
    if (name.size() < 4 || name.substr(name.size() - 4) != ".png") continue;
    ++shown;
    ASSERT_TRUE(fs::exists(out / name)) << name << " is shown in report.md but not drawn";
    EXPECT_EQ(slurp(out / name).substr(1, 3), "PNG") << name;
  }
  EXPECT_GE(shown, 5);  // cone, slope, bulldozing, conservation, bucket at least
}

// Calibration from material tests (docs/validation.md, "Calibration"): the
// fitted fields with their uncertainties on stdout, calibration.json and a
// soil.yaml that a scenario takes as its soil: section.
TEST_F(CliTest, CalibrateFromTestsWritesASoilSectionAScenarioTakes) {
  const fs::path tests = write("tests.json", R"({"bulk_density_kg_per_m3": [1500, 1520],
      "repose_deg": [31, 33], "plate": [{"sigma_pa": 2000, "tau_pa": 900}],
      "shear": [{"sigma_pa": 1000, "tau_pa": 900}, {"sigma_pa": 3000, "tau_pa": 2300},
                {"sigma_pa": 5000, "tau_pa": 3700}]})");
  const fs::path out = dir_ / "cal";
  const Result r = terracut({"calibrate", "--tests", tests.string(), "--out", out.string()});
  ASSERT_EQ(r.code, 0) << r.err;
  for (const char* word : {"internal_friction_deg", "cohesion_pa", "uncertainty", "soil:"})
    EXPECT_NE(r.out.find(word), std::string::npos) << word;
  ASSERT_TRUE(fs::exists(out / "calibration.json"));
  const std::string soil = slurp(out / "soil.yaml");
  // tau = 200 + 0.7 sigma exactly: phi = atan(0.7) = 34.9920 degrees.
  EXPECT_NE(soil.find("internal_friction_deg: 34.992"), std::string::npos) << soil;
  EXPECT_NE(soil.find("cohesion_pa: 200"), std::string::npos) << soil;
  // The section in a scenario: `terracut run` takes it.
  const fs::path sc = write("calibrated.yaml", "terrain:\n  generator: plane\n  resolution: 64\n"
                                               "  size_m: [1.0, 1.0]\n  full_scale_m: 0.2\n"
                                               "blade:\n  length_m: 0.3\n" + soil +
                                               "cuts:\n  - name: c\n    keyframes:\n"
                                               "      - {t_s: 0.0, position_m: [0.5, 0.15, 0.2]}\n"
                                               "      - {t_s: 0.2, position_m: [0.5, 0.15, 0.4]}\n");
  const Result run = terracut({"run", sc.string(), "--out", (dir_ / "run").string(), "--quiet"});
  EXPECT_EQ(run.code, 0) << run.err;
  EXPECT_NE(slurp(dir_ / "run" / "summary.json").find("34.99"), std::string::npos);
}

// A force record made by `terracut run` itself (its contact.csv's poses and
// its force.csv's force, at the scenario's rate) on a soil of 36 degrees and
// 900 Pa gives that soil back, from a scenario that starts at dry sand's.
TEST_F(CliTest, CalibrateFromARecordGivesTheSoilThatMadeIt) {
  const std::string scene = "terrain:\n  generator: plane\n  resolution: 80\n  size_m: [0.8, 0.8]\n"
                            "  full_scale_m: 0.3\nblade:\n  length_m: 0.3\n";
  // The blade goes from 3 to 8 cm deep: two depths tell cohesion from friction.
  const std::string cut = "cuts:\n  - name: c\n    keyframes:\n"
                          "      - {t_s: 0.0, position_m: [0.4, 0.27, 0.05]}\n"
                          "      - {t_s: 1.0, position_m: [0.4, 0.22, 0.45]}\n";
  const fs::path truth = write("truth.yaml", scene + "soil:\n  internal_friction_deg: 36\n  cohesion_pa: 900\n" + cut);
  const fs::path start = write("start.yaml", scene + "soil:\n  preset: dry_sand\n" + cut);
  ASSERT_EQ(terracut({"run", truth.string(), "--out", (dir_ / "truth").string(), "--quiet"}).code, 0);
  std::ifstream contact(dir_ / "truth" / "contact.csv"), force(dir_ / "truth" / "force.csv");
  std::ofstream record(dir_ / "record.csv");
  record << "t_s,x_m,y_m,z_m,qw,qx,qy,qz,fx_n,fy_n,fz_n\n";
  std::string a, b;
  std::getline(contact, a);
  std::getline(force, b);
  int rows = 0;
  while (std::getline(contact, a) && std::getline(force, b)) {
    // contact: t,cut,x,y,z,qw,qx,qy,qz,...; force: t,cut,fx,fy,fz,...
    std::vector<std::string> c, f;
    for (std::stringstream ss(a); std::getline(ss, a, ',');) c.push_back(a);
    for (std::stringstream ss(b); std::getline(ss, b, ',');) f.push_back(b);
    ASSERT_GE(c.size(), 9u);
    ASSERT_GE(f.size(), 5u);
    record << c[0] << "," << c[2] << "," << c[3] << "," << c[4] << "," << c[5] << "," << c[6] << "," << c[7] << ","
           << c[8] << "," << f[2] << "," << f[3] << "," << f[4] << "\n";
    ++rows;
  }
  record.close();
  ASSERT_GT(rows, 900);
  const Result r = terracut({"calibrate", "--record", (dir_ / "record.csv").string(), "--scenario", start.string(),
                             "--from-s", "0.01", "--out", (dir_ / "cal").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string soil = slurp(dir_ / "cal" / "soil.yaml");
  const auto value = [&](const std::string& key) {
    const std::size_t at = soil.find(key + ": ");
    return at == std::string::npos ? -1.0 : std::stod(soil.substr(at + key.size() + 2));
  };
  // contact.csv and force.csv print 9 significant digits: the poses and
  // forces are the run's to 1e-9 relative; the fit stops when a step gains
  // less than 1e-6 of the residual.
  EXPECT_NEAR(value("internal_friction_deg"), 36.0, 0.02) << soil;
  EXPECT_NEAR(value("cohesion_pa"), 900.0, 2.0) << soil;
}

TEST_F(CliTest, CalibrateRefusesBadInputNamingIt) {
  expect_clean_failure(terracut({"calibrate"}), {"give --tests FILE, --record FILE --scenario FILE, or --dem-run DIR"});
  expect_clean_failure(terracut({"calibrate", "--record", write("r.csv", "x\n").string()}), {"needs --scenario"});
  expect_clean_failure(terracut({"calibrate", "--record", write("r.csv", "t_s,x\n").string(), "--scenario",
                                 scenario("mound_generator.yaml")}),
                       {"r.csv:1: expected the header"});
  expect_clean_failure(terracut({"calibrate", "--tests", write("t.json", R"({"shear": [{"sigma_pa": 1000, "tau_pa": 5}]})").string()}),
                       {"shear: the Mohr-Coulomb line needs tests at two normal stresses"});
  expect_clean_failure(terracut({"calibrate", "--tests", (dir_ / "absent.json").string()}), {"absent.json: cannot be read"});
  const Result both = terracut({"calibrate", "--tests", "a", "--record", "b"});
  EXPECT_EQ(both.code, 2) << both.err;
}

}  // namespace
