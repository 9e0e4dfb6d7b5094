// The terrain renderer's level of detail (apps/viewer/terrain_renderer.cpp),
// drawn headless: the triangles drawn follow the view, not the terrain's
// size; a cut far away is seen through its chunks' errors (uploading it
// refines them, uploading the old heights back undoes that); close to the
// camera every cell of a cut is a quad. The pictures themselves are checked
// by viewer_render_test.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <memory>
#include <vector>

#include "gl_context.hpp"
#include "gfx_math.hpp"
#include "terrain_renderer.hpp"

namespace terracut::viewer {
namespace {

constexpr int kWidth = 640, kHeight = 400;

// A headless context and framebuffer, or nothing (the test skips) when this
// machine has no EGL; TERRACUT_REQUIRE_GL=1 makes that a failure.
struct Gl {
  std::unique_ptr<HeadlessContext> context;
  std::unique_ptr<Framebuffer> fb;
  std::string why;
  Gl() {
    try {
      context = std::make_unique<HeadlessContext>();
      fb = std::make_unique<Framebuffer>(kWidth, kHeight, 0);
      fb->bind();
      glViewport(0, 0, kWidth, kHeight);
      glEnable(GL_DEPTH_TEST);
    } catch (const ContextUnavailable& e) {
      why = e.what();
    }
  }
  bool ok() const { return context != nullptr; }
};

#define REQUIRE_GL(gl)                                                  \
  if (!(gl).ok()) {                                                     \
    if (std::getenv("TERRACUT_REQUIRE_GL")) FAIL() << (gl).why;         \
    GTEST_SKIP() << "no OpenGL context: " << (gl).why;                  \
  }

// 1 m x 1 m of soil 0.1 m deep at `side` x `side` samples.
GridSpec square(int side) {
  GridSpec g;
  g.cols = side;
  g.rows = side;
  g.size_x_m = 1.0;
  g.size_z_m = 1.0;
  g.full_scale_m = 0.2;
  return g;
}

// The whole terrain from 1.6 m away, 35 degrees above it.
Mat4 overview(Vec3f& eye) {
  eye = {0.5f, 0.9f, 1.8f};
  return perspective(0.8f, float(kWidth) / float(kHeight), 0.05f, 20.0f) *
         look_at(eye, {0.5f, 0.05f, 0.5f}, {0.0f, 1.0f, 0.0f});
}

std::int64_t drawn(TerrainRenderer& t, const Mat4& vp, Vec3f eye) {
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  t.draw(vp, eye, TerrainStyle{});
  glFinish();
  return t.triangle_count();
}

// A 2 cm deep trench 10 cm wide along Z at x in [0.45, 0.55] (samples whose
// centres are inside), as a cut leaves it.
std::vector<float> trenched(const GridSpec& g) {
  std::vector<float> h(std::size_t(g.sample_count()), 0.1f);
  for (int r = 0; r < g.rows; ++r)
    for (int c = 0; c < g.cols; ++c) {
      const double x = (c + 0.5) * g.cell_x_m();
      if (x > 0.45 && x < 0.55) h[std::size_t(r) * std::size_t(g.cols) + std::size_t(c)] = 0.08f;
    }
  return h;
}

TEST(TerrainRendererLod, TrianglesFollowTheViewNotTheTerrainSize) {
  Gl gl;
  REQUIRE_GL(gl);
  Vec3f eye;
  const Mat4 vp = overview(eye);
  std::vector<std::int64_t> counts;
  for (int side : {512, 2048, 4096}) {
    const GridSpec g = square(side);
    const std::vector<float> h = trenched(g);
    TerrainRenderer t(g, Representation::kSurface, h.data(), h.data());
    counts.push_back(drawn(t, vp, eye));
    // Past a cell per pixel: far fewer than every cell's two triangles.
    if (side >= 2048) {
      EXPECT_LT(counts.back(), std::int64_t(2) * side * side / 16) << side;
    }
    EXPECT_GT(t.chunk_count(), 0);
  }
  // Past what the screen can show (640 x 400 pixels for 1 m), a finer grid
  // of the same soil draws about the same number of triangles.
  EXPECT_LE(double(counts[2]), 1.25 * double(counts[1]));
  EXPECT_LE(double(counts[1]), 1.25 * double(counts[0]) + 1.0);
}

TEST(TerrainRendererLod, ACutIsSeenThroughItsChunksErrors) {
  Gl gl;
  REQUIRE_GL(gl);
  Vec3f eye;
  const Mat4 vp = overview(eye);
  const GridSpec g = square(2048);
  const std::vector<float> level(std::size_t(g.sample_count()), 0.1f);
  TerrainRenderer t(g, Representation::kSurface, level.data(), level.data());
  const std::int64_t flat = drawn(t, vp, eye);
  // A trench cut and uploaded (its rectangle only): the chunks over its
  // walls are refined.
  const std::vector<float> cut = trenched(g);
  const Rect rect{int(0.45 * 2048) - 1, 0, int(0.55 * 2048) + 2, g.rows};
  t.upload(cut.data(), rect);
  const std::int64_t with_cut = drawn(t, vp, eye);
  EXPECT_GT(with_cut, flat);
  // The old heights uploaded back: the same chunks as before the cut.
  t.upload(level.data(), rect);
  EXPECT_EQ(drawn(t, vp, eye), flat);
}

TEST(TerrainRendererLod, CloseToTheCameraACutIsDrawnCellByCell) {
  // Looking at a trench's wall from 5 cm, the chunks there have one quad per
  // cell; the level soil of the overview, with no cut, is drawn coarser.
  Gl gl;
  REQUIRE_GL(gl);
  const GridSpec g = square(1024);
  const std::vector<float> h = trenched(g);
  TerrainRenderer t(g, Representation::kSurface, h.data(), h.data());
  const Vec3f eye{0.40f, 0.13f, 0.5f};
  const Mat4 vp = perspective(0.8f, float(kWidth) / float(kHeight), 0.01f, 5.0f) *
                  look_at(eye, {0.45f, 0.09f, 0.5f}, {0.0f, 1.0f, 0.0f});
  drawn(t, vp, eye);
  EXPECT_EQ(t.finest_step(), 1);

  const std::vector<float> level(std::size_t(g.sample_count()), 0.1f);
  TerrainRenderer flat(g, Representation::kSurface, level.data(), level.data());
  Vec3f far_eye;
  const Mat4 far_vp = overview(far_eye);
  drawn(flat, far_vp, far_eye);
  EXPECT_GT(flat.finest_step(), 1);
}

}  // namespace
}  // namespace terracut::viewer
