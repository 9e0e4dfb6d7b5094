// terracut-viewer rendered headless (EGL surfaceless) as a user would run
// it, and the images checked against geometry: the top camera puts the
// terrain exactly in its projected extent with +X to the right and +Z down,
// and a cut band changes colour while the terrain away from it does not.
// Without an EGL context (no Mesa) the viewer exits with status 77 and these
// tests are skipped, with the viewer's reason.
#include <gtest/gtest.h>

#include <cstdlib>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "png_rgb.hpp"
#include "../support/spawn.hpp"
#include "terracut/io/image.hpp"

extern char** environ;

namespace {

namespace fs = std::filesystem;
using terracut::viewer::RgbImage;

constexpr int kExitNoContext = 77;   // terracut-viewer's status when EGL gives no context
constexpr float kMargin = 0.1f;      // the top camera's empty margin on each side (camera.hpp)

struct Result {
  bool exited = false;
  int code = -1;
  std::string err;
};

std::string slurp(const fs::path& path) {
  std::ifstream f(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

// Where the top camera draws a terrain: the extent fitted, aspect kept, into
// the image shrunk by kMargin on every side, centred.
struct TopMapping {
  double x0, z0, px_per_m, left, top;
  TopMapping(int w, int h, double x0_m, double z0_m, double sx_m, double sz_m) : x0(x0_m), z0(z0_m) {
    const double iw = (1.0 - 2.0 * kMargin) * w, ih = (1.0 - 2.0 * kMargin) * h;
    px_per_m = std::min(iw / sx_m, ih / sz_m);
    left = 0.5 * (w - sx_m * px_per_m);
    top = 0.5 * (h - sz_m * px_per_m);
  }
  // World coordinates of pixel (u, v)'s centre.
  double x(int u) const { return x0 + (u + 0.5 - left) / px_per_m; }
  double z(int v) const { return z0 + (v + 0.5 - top) / px_per_m; }
};

const std::uint8_t* pixel(const RgbImage& im, int u, int v) {
  return im.pixels.data() + (std::size_t(v) * std::size_t(im.cols) + std::size_t(u)) * 3u;
}

int max_diff(const std::uint8_t* a, const std::uint8_t* b) {
  return std::max({std::abs(a[0] - b[0]), std::abs(a[1] - b[1]), std::abs(a[2] - b[2])});
}

double luminance(const std::uint8_t* p) { return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]; }

class ViewerRenderTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("terracut_viewer_test_" + std::to_string(getpid()) + "_" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  Result run(std::vector<std::string> argv) {
    argv.insert(argv.begin(), TERRACUT_VIEWER_BIN);
    const fs::path err = dir_ / "stderr.txt";
    Result r;
    const pid_t pid = terracut::test::spawn(argv, dir_ / "stdout.txt", err);
    if (pid < 0) {
      r.err = "cannot start " + argv[0];
      return r;
    }
    r.code = terracut::test::wait_exit(pid);
    r.exited = r.code >= 0;
    r.err = slurp(err);
    return r;
  }

  // Renders headless to dir/name; skips the test when no context can be made.
  RgbImage render(const fs::path& scenario, const std::string& name, std::vector<std::string> extra) {
    const fs::path png = dir_ / name;
    std::vector<std::string> argv = {scenario.string(), "--screenshot", png.string(), "--msaa", "0"};
    argv.insert(argv.end(), extra.begin(), extra.end());
    Result r = run(argv);
    if (r.exited && r.code == kExitNoContext) {
      skipped_ = "no OpenGL context: " + r.err;
      return {};
    }
    EXPECT_TRUE(r.exited && r.code == 0) << "terracut-viewer failed (" << r.code << "): " << r.err;
    if (!(r.exited && r.code == 0)) return {};
    return terracut::viewer::read_png_rgb(png);
  }

  fs::path write(const std::string& name, const std::string& text) {
    fs::path p = dir_ / name;
    std::ofstream(p) << text;
    return p;
  }

  fs::path dir_;
  std::string skipped_;
};

// Without an OpenGL context the render tests skip, unless
// TERRACUT_REQUIRE_GL is set (CI sets it, so a missing Mesa fails there).
bool gl_required() { return std::getenv("TERRACUT_REQUIRE_GL") != nullptr; }
#define SKIP_OR_FAIL_WITHOUT_GL(reason)                                        \
  do {                                                                         \
    if (gl_required()) FAIL() << "TERRACUT_REQUIRE_GL is set: " << (reason);   \
    GTEST_SKIP() << (reason);                                                  \
  } while (0)

#define RENDER_OR_SKIP(var, ...)              \
  RgbImage var = render(__VA_ARGS__);         \
  if (!skipped_.empty()) SKIP_OR_FAIL_WITHOUT_GL(skipped_); \
  ASSERT_GT(var.cols, 0)

// A 2 m x 1 m terrain (not square, to check the aspect is kept) with a 0.2 m
// high block over the quarter at low X and low Z; the tool parked far away.
const char* kExtentScenario = R"(
name: viewer_extent
terrain:
  generator: box
  resolution: [96, 48]
  size_m: [2.0, 1.0]
  origin_m: [-1.0, 0.0, 0.5]
  full_scale_m: 0.2
  box: {min_m: [-1.0, 0.5], max_m: [0.0, 1.0]}
blade: {length_m: 0.5}
cuts:
  - name: away
    keyframes:
      - {t_s: 0.0, position_m: [20.0, 1.0, 20.0]}
      - {t_s: 0.1, position_m: [21.0, 1.0, 20.0]}
)";

TEST_F(ViewerRenderTest, TopViewPutsTheTerrainInItsProjectedExtent) {
  const int w = 400, h = 300;
  fs::path sc = write("extent.yaml", kExtentScenario);
  RENDER_OR_SKIP(im, sc, "extent.png",
                 {"--camera", "top", "--no-panel", "--no-contours", "--frames", "0", "--size", "400x300"});
  ASSERT_EQ(im.cols, w);
  ASSERT_EQ(im.rows, h);
  const TopMapping map(w, h, -1.0, 0.5, 2.0, 1.0);
  // The background is a vertical gradient: compare with the same row's first
  // pixel (inside the margin). Pixels whose centre is 1.5 px or more inside
  // the extent are terrain; 1.5 px or more outside, background.
  const double edge_m = 1.5 / map.px_per_m;
  int inside = 0, outside = 0, bad_inside = 0, bad_outside = 0;
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const double x = map.x(u), z = map.z(v);
      const bool background = max_diff(pixel(im, u, v), pixel(im, 0, v)) <= 4;
      const double dist_in = std::min({x + 1.0, 1.0 - x, z - 0.5, 1.5 - z});  // > 0 inside
      if (dist_in >= edge_m) {
        ++inside;
        bad_inside += background ? 1 : 0;
      } else if (dist_in <= -edge_m) {
        ++outside;
        bad_outside += background ? 0 : 1;
      }
    }
  }
  EXPECT_GT(inside, 300 * 150);
  EXPECT_GT(outside, 2 * 40 * 300);
  EXPECT_EQ(bad_inside, 0) << "terrain pixels that look like the background";
  EXPECT_EQ(bad_outside, 0) << "background pixels covered by something";

  // Orientation: the block (x < 0, z < 1: left half, upper half of the image)
  // is drawn in the colour of the full height, lighter than the bare ground.
  // Stay 3 cells (~12 px) away from the block's sloped edges.
  const double cell = 2.0 / 96.0, keep = 3.0 * cell;
  double block_min = 1e9, ground_max = -1e9;
  int block_n = 0, ground_n = 0;
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const double x = map.x(u), z = map.z(v);
      if (x < -1.0 + keep || x > 1.0 - keep || z < 0.5 + keep || z > 1.5 - keep) continue;
      const bool in_block = x < -keep && z < 1.0 - keep;
      const bool in_ground = x > keep || z > 1.0 + keep;
      const double lum = luminance(pixel(im, u, v));
      if (in_block) {
        block_min = std::min(block_min, lum);
        ++block_n;
      } else if (in_ground) {
        ground_max = std::max(ground_max, lum);
        ++ground_n;
      }
    }
  }
  ASSERT_GT(block_n, 1000);
  ASSERT_GT(ground_n, 3000);
  EXPECT_GT(block_min, ground_max + 40.0)
      << "the block must be the upper-left quarter of the terrain (+X right, +Z down)";
}

// A flat 0.2 m layer; the blade (along X, wider than the terrain) comes in
// high from far away, plunges to y = 0.1 at z = 0.35, cuts along +Z to
// z = 0.65, rises and leaves: the band 0.35 < z < 0.65 is cut to half depth.
const char* kBandScenario = R"(
name: viewer_band
terrain:
  generator: plane
  resolution: 64
  size_m: [1.0, 1.0]
  full_scale_m: 0.2
  plane: {height_m: 0.2}
blade: {length_m: 1.4}
cuts:
  - name: band
    keyframes:
      - {t_s: 0.0, position_m: [6.0, 1.0, 0.35]}
      - {t_s: 0.2, position_m: [0.5, 1.0, 0.35]}
      - {t_s: 0.4, position_m: [0.5, 0.1, 0.35]}
      - {t_s: 0.7, position_m: [0.5, 0.1, 0.65]}
      - {t_s: 0.9, position_m: [0.5, 1.0, 0.65]}
      - {t_s: 1.1, position_m: [6.0, 1.0, 0.65]}
)";

void expect_band_changes(const RgbImage& before, const RgbImage& after, int w, int h) {
  ASSERT_EQ(before.cols, w);
  ASSERT_EQ(after.cols, w);
  const TopMapping map(w, h, 0.0, 0.0, 1.0, 1.0);
  // Inside the band (2 cells from its edges, where the surface slopes) every
  // pixel changes; on the terrain more than 4 cells from the band none does.
  const double cell = 1.0 / 64.0;
  int band = 0, band_changed = 0, far = 0, far_changed = 0;
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const double x = map.x(u), z = map.z(v);
      if (x < 2 * cell || x > 1.0 - 2 * cell || z < 2 * cell || z > 1.0 - 2 * cell) continue;
      const int d = max_diff(pixel(before, u, v), pixel(after, u, v));
      if (z > 0.35 + 2 * cell && z < 0.65 - 2 * cell) {
        ++band;
        band_changed += d > 25 ? 1 : 0;
      } else if (z < 0.35 - 4 * cell || z > 0.65 + 4 * cell) {
        ++far;
        far_changed += d > 3 ? 1 : 0;
      }
    }
  }
  EXPECT_GT(band, 5000);
  EXPECT_GT(far, 10000);
  EXPECT_EQ(band_changed, band) << "pixels of the cut band that kept their colour";
  EXPECT_EQ(far_changed, 0) << "pixels far from the cut that changed";
}

TEST_F(ViewerRenderTest, CutBandChangesColourByRemovedDepth) {
  fs::path sc = write("band.yaml", kBandScenario);
  const std::vector<std::string> common = {"--camera", "top", "--no-panel", "--no-contours",
                                           "--color", "removed", "--size", "320x320"};
  std::vector<std::string> first = common;
  first.insert(first.end(), {"--frames", "0"});
  RENDER_OR_SKIP(before, sc, "before.png", first);
  RENDER_OR_SKIP(after, sc, "after.png", common);  // the whole script
  expect_band_changes(before, after, 320, 320);
}

TEST_F(ViewerRenderTest, CutBandChangesColourByHeight) {
  fs::path sc = write("band.yaml", kBandScenario);
  const std::vector<std::string> common = {"--camera", "top", "--no-panel", "--no-contours",
                                           "--size", "320x320"};
  std::vector<std::string> first = common;
  first.insert(first.end(), {"--frames", "0"});
  RENDER_OR_SKIP(before, sc, "before.png", first);
  RENDER_OR_SKIP(after, sc, "after.png", common);
  expect_band_changes(before, after, 320, 320);
}

TEST_F(ViewerRenderTest, ColumnsRepresentationRendersTheSameBand) {
  fs::path sc = write("band.yaml", kBandScenario);
  const std::vector<std::string> common = {"--camera", "top", "--no-panel", "--no-contours",
                                           "--color", "removed", "--representation", "columns",
                                           "--size", "320x320"};
  std::vector<std::string> first = common;
  first.insert(first.end(), {"--frames", "0"});
  RENDER_OR_SKIP(before, sc, "before.png", first);
  RENDER_OR_SKIP(after, sc, "after.png", common);
  expect_band_changes(before, after, 320, 320);
}

TEST_F(ViewerRenderTest, PanelIsDrawnOnTheLeft) {
  fs::path sc = write("band.yaml", kBandScenario);
  RENDER_OR_SKIP(with_panel, sc, "panel.png", {"--frames", "30", "--size", "900x600"});
  RENDER_OR_SKIP(without, sc, "nopanel.png", {"--frames", "30", "--size", "900x600", "--no-panel"});
  // The panel covers the left 390 px with a dark window; the rest is the scene.
  int changed = 0, dark = 0, n = 0;
  for (int v = 0; v < 600; ++v)
    for (int u = 0; u < 380; ++u) {
      ++n;
      changed += max_diff(pixel(with_panel, u, v), pixel(without, u, v)) > 20 ? 1 : 0;
      dark += luminance(pixel(with_panel, u, v)) < 90.0 ? 1 : 0;
    }
  EXPECT_GT(changed, n / 2);
  EXPECT_GT(dark, n / 2);
}

TEST_F(ViewerRenderTest, HeightmapPngIsDrawnWithItsSlope) {
  // A ramp rising along +X: the height colour brightens from left to right.
  const int n = 64;
  std::vector<float> ramp(std::size_t(n) * n);
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) ramp[std::size_t(r) * n + c] = float(c) / float(n - 1);
  const fs::path png = dir_ / "ramp.png";
  terracut::io::write_png16(png, ramp.data(), n, n, 1.0);
  RENDER_OR_SKIP(im, png, "ramp_view.png",
                 {"--camera", "top", "--no-panel", "--no-contours", "--size", "300x300"});
  const TopMapping map(300, 300, 0.0, 0.0, 1.0, 1.0);
  double third[3] = {0, 0, 0};
  int count[3] = {0, 0, 0};
  for (int v = 0; v < 300; ++v)
    for (int u = 0; u < 300; ++u) {
      const double x = map.x(u), z = map.z(v);
      if (x < 0.02 || x > 0.98 || z < 0.02 || z > 0.98) continue;
      if (std::abs(z - 0.5) < 0.08) continue;  // the parked tool, above the middle
      const int k = std::min(2, int(x * 3.0));
      third[k] += luminance(pixel(im, u, v));
      ++count[k];
    }
  for (int k = 0; k < 3; ++k) third[k] /= std::max(count[k], 1);
  EXPECT_LT(third[0] + 10.0, third[1]);
  EXPECT_LT(third[1] + 10.0, third[2]);
}

// A big box resting on a flat 0.1 m layer (0.5 x 0.2 x 0.3 m, turned 30
// degrees about Y, so that its footprint shows the orientation), the tool
// far away. From the top, every pixel of the box's footprint differs from the
// same scenario without the box and is drawn in the bodies' cool colour
// (blue above red, where the soil is red above blue); every pixel away from
// it is unchanged.
const char* kBoxScenario = R"(
name: viewer_box
terrain:
  generator: plane
  resolution: 64
  size_m: [1.0, 1.0]
  full_scale_m: 0.2
  plane: {height_m: 0.1}
blade: {length_m: 0.3}
bodies:
  - {name: block, shape: box, size_m: [0.5, 0.2, 0.3], mass_kg: 60,
     position_m: [0.5, 0.2, 0.5], rotation_deg: [0, 30, 0]}
cuts:
  - name: away
    keyframes:
      - {t_s: 0.0, position_m: [20.0, 1.0, 20.0]}
      - {t_s: 0.2, position_m: [21.0, 1.0, 20.0]}
)";

TEST_F(ViewerRenderTest, RigidBodyIsDrawnWhereItRests) {
  const int w = 320, h = 320;
  const std::string with_text = kBoxScenario;
  const std::string without_text = with_text.substr(0, with_text.find("bodies:")) +
                                   with_text.substr(with_text.find("cuts:"));
  const fs::path with_sc = write("box.yaml", with_text);
  const fs::path without_sc = write("nobox.yaml", without_text);
  const std::vector<std::string> common = {"--camera", "top", "--no-panel", "--no-contours",
                                           "--size", "320x320"};
  // The box as the viewer gets it from the loop (the whole 0.2 s script).
  const fs::path png = dir_ / "box.png";
  std::vector<std::string> argv = {with_sc.string(), "--screenshot", png.string(), "--msaa", "0"};
  argv.insert(argv.end(), common.begin(), common.end());
  const Result r = run(argv);
  if (r.exited && r.code == kExitNoContext) SKIP_OR_FAIL_WITHOUT_GL("no OpenGL context: " + r.err);
  if (r.err.find("built without") != std::string::npos) {
    EXPECT_EQ(r.code, 2) << r.err;  // refused as bad input, with the reason
    GTEST_SKIP() << r.err;
  }
  ASSERT_TRUE(r.exited && r.code == 0) << "terracut-viewer failed (" << r.code << "): " << r.err;
  const RgbImage with = terracut::viewer::read_png_rgb(png);
  RENDER_OR_SKIP(without, without_sc, "nobox.png", common);
  ASSERT_EQ(with.cols, w);

  const TopMapping map(w, h, 0.0, 0.0, 1.0, 1.0);
  const double c = std::cos(30.0 * M_PI / 180.0), s = std::sin(30.0 * M_PI / 180.0);
  const double hx = 0.25, hz = 0.15, px = 1.0 / map.px_per_m;
  int inside = 0, inside_changed = 0, inside_cool = 0, far = 0, far_changed = 0;
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const double dx = map.x(u) - 0.5, dz = map.z(v) - 0.5;
      if (std::abs(dx) > 0.48 || std::abs(dz) > 0.48) continue;  // the terrain only
      // Body-frame coordinates: world = R_y(30 deg) body, body = R_y(-30 deg) world.
      const double bx = c * dx - s * dz, bz = s * dx + c * dz;
      const std::uint8_t* p = pixel(with, u, v);
      const int d = max_diff(p, pixel(without, u, v));
      if (std::abs(bx) < hx - 2 * px && std::abs(bz) < hz - 2 * px) {
        ++inside;
        inside_changed += d > 25 ? 1 : 0;
        inside_cool += p[2] > p[0] ? 1 : 0;
      } else if (std::abs(bx) > hx + 3 * px || std::abs(bz) > hz + 3 * px) {
        ++far;
        far_changed += d > 3 ? 1 : 0;
      }
    }
  }
  // The footprint: 0.5 x 0.3 m at about 256 px per metre.
  EXPECT_GT(inside, 8000);
  EXPECT_GT(far, 40000);
  EXPECT_EQ(inside_changed, inside) << "pixels of the box drawn in the terrain's colour";
  EXPECT_EQ(inside_cool, inside) << "pixels of the box not in the bodies' colour";
  EXPECT_EQ(far_changed, 0) << "pixels away from the box that changed";
  // The soil itself is warm (red above blue).
  const std::uint8_t* soil = pixel(without, w / 2, h / 2);
  EXPECT_GT(soil[0], soil[2]);
}

TEST_F(ViewerRenderTest, CommandLineErrorsExitWithTwoAndHelpShowsTheDefaults) {
  // docs/viewer.md: every command-line error exits 2 (CLI11's own code for
  // an unknown option is 109).
  const std::string sc = (fs::path(TERRACUT_SOURCE_DIR) / "scenarios/trench_dry_sand.yaml").string();
  Result r = run({sc, "--bogus"});
  ASSERT_TRUE(r.exited);
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("--bogus"), std::string::npos) << r.err;
  r = run({sc, "--msaa", "99"});
  EXPECT_EQ(r.code, 2) << r.err;
  r = run({sc, "--extent", "-1"});
  EXPECT_EQ(r.code, 2) << r.err;
  // --help exits 0 and shows the heightmap defaults and the exit codes.
  const fs::path out = dir_ / "stdout.txt";
  r = run({"--help"});
  EXPECT_EQ(r.code, 0);
  const std::string help = slurp(out);
  EXPECT_NE(help.find("Exit codes"), std::string::npos) << help;
  EXPECT_NE(help.find("77"), std::string::npos) << help;
  EXPECT_NE(help.find("--extent"), std::string::npos);
  EXPECT_NE(help.find("=1 "), std::string::npos) << help;    // --extent's default, metres
  EXPECT_NE(help.find("=0.2"), std::string::npos) << help;   // --full-scale's
}

TEST_F(ViewerRenderTest, MissingScenarioIsReportedByName) {
  Result r = run({(dir_ / "no_such.yaml").string(), "--screenshot", (dir_ / "x.png").string()});
  ASSERT_TRUE(r.exited) << "the viewer crashed";
  EXPECT_EQ(r.code, 1);  // bad input, as `terracut` has it (apps/exit_codes.hpp)
  EXPECT_NE(r.err.find("no_such.yaml"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "x.png"));
}

// The first hour's headless errors: each is named, with the bad-input code,
// and never aborts (an abort is a signal: wait_exit gives no exit code).
TEST_F(ViewerRenderTest, AScreenshotIntoAMissingFolderIsNamedBeforeDrawing) {
  const std::string sc = (fs::path(TERRACUT_SOURCE_DIR) / "scenarios/mound_generator.yaml").string();
  const fs::path missing = dir_ / "no_such_folder";
  Result r = run({sc, "--screenshot", (missing / "x.png").string(), "--frames", "1"});
  ASSERT_TRUE(r.exited) << "the viewer crashed: " << r.err;
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find("--screenshot"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(missing.string()), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(missing));
}

TEST_F(ViewerRenderTest, AScreenshotThatCannotBeWrittenIsNamedAfterDrawing) {
  // The folder exists, but the PNG's name is a folder: the write fails after
  // the frames are drawn, with the context still holding the renderers.
  const std::string sc = (fs::path(TERRACUT_SOURCE_DIR) / "scenarios/mound_generator.yaml").string();
  const fs::path taken = dir_ / "taken.png";
  fs::create_directories(taken);
  Result r = run({sc, "--screenshot", taken.string(), "--frames", "1", "--msaa", "0"});
  ASSERT_TRUE(r.exited) << "the viewer crashed: " << r.err;
  if (r.code == kExitNoContext) SKIP_OR_FAIL_WITHOUT_GL("no OpenGL context: " + r.err);
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find("taken.png"), std::string::npos) << r.err;
}

TEST_F(ViewerRenderTest, MmtWithoutAnMmtSectionIsNamedHeadless) {
  // The session is opened after the context exists: its refusal must not
  // abort on the way out.
  const std::string sc = (fs::path(TERRACUT_SOURCE_DIR) / "scenarios/trench_dry_sand.yaml").string();
  Result r = run({sc, "--mmt", "--screenshot", (dir_ / "x.png").string(), "--frames", "1"});
  ASSERT_TRUE(r.exited) << "the viewer crashed: " << r.err;
  if (r.code == kExitNoContext) SKIP_OR_FAIL_WITHOUT_GL("no OpenGL context: " + r.err);
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find("no mmt: section"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "x.png"));
}

}  // namespace
