// The snapshot exchange: frames are never torn, and a reader that uploads
// only each frame's dirty rectangle stays identical to the writer's grid.
#include "terracut/haptics/snapshot.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <thread>

namespace terracut::haptics {
namespace {

constexpr int kSide = 48;

GridSpec spec() {
  GridSpec s;
  s.cols = kSide;
  s.rows = kSide;
  return s;
}

// Step k writes the value k into row k % kSide and columns [k % 7, k % 7 + 20).
Rect write_step(HeightGrid& grid, std::int64_t k) {
  int r = int(k % kSide), c0 = int(k % 7);
  float values[20];
  for (float& v : values) v = float(k);
  return grid.set_heights({c0, r, c0 + 20, r + 1}, values);
}

// The value sample (c, r) must hold in a consistent frame of step k.
float expected(int c, int r, std::int64_t k) {
  for (std::int64_t j = k; j >= 1 && j > k - 64 * kSide; --j) {
    if (j % kSide == r && c >= j % 7 && c < j % 7 + 20) return float(j);
  }
  return 0.0f;
}

TEST(SnapshotExchange, SingleThreadDirtyRegionsKeepAMirrorExact) {
  HeightGrid grid(spec(), std::vector<float>(kSide * kSide, 0.0f));
  SnapshotExchange ex(grid);
  std::vector<float> mirror(grid.heights(), grid.heights() + kSide * kSide);
  EXPECT_EQ(ex.acquire(), nullptr);
  for (std::int64_t k = 1; k <= 500; ++k) {
    ex.note_changed(write_step(grid, k));
    ex.back().step = k;
    ex.publish(grid);
    // The reader takes only every third frame: dirty regions must accumulate.
    if (k % 3 != 0) continue;
    const ViewFrame* f = ex.acquire();
    ASSERT_NE(f, nullptr);
    EXPECT_EQ(f->step, k);
    for (int r = f->dirty.r0; r < f->dirty.r1; ++r)
      for (int c = f->dirty.c0; c < f->dirty.c1; ++c) mirror[size_t(r * kSide + c)] = f->heights[size_t(r * kSide + c)];
    ASSERT_EQ(mirror, f->heights) << "step " << k;
    ASSERT_EQ(std::vector<float>(grid.heights(), grid.heights() + kSide * kSide), f->heights);
    EXPECT_EQ(ex.acquire(), nullptr);
  }
}

TEST(SnapshotExchange, ConcurrentReaderNeverSeesATornFrame) {
  HeightGrid grid(spec(), std::vector<float>(kSide * kSide, 0.0f));
  SnapshotExchange ex(grid);
  constexpr std::int64_t kSteps = 20000;
  std::atomic<bool> done{false};
  std::atomic<long> frames_checked{0}, bad_frames{0};
  std::thread reader([&] {
    std::vector<float> mirror(kSide * kSide, 0.0f);
    std::int64_t last_step = 0;
    while (true) {
      bool finished = done.load(std::memory_order_acquire);
      if (const ViewFrame* f = ex.acquire()) {
        if (f->step < last_step) ++bad_frames;
        last_step = f->step;
        for (int r = f->dirty.r0; r < f->dirty.r1; ++r)
          for (int c = f->dirty.c0; c < f->dirty.c1; ++c) mirror[size_t(r * kSide + c)] = f->heights[size_t(r * kSide + c)];
        // Every sample of the frame belongs to the frame's step, and the
        // mirror built from dirty regions matches it.
        bool ok = mirror == f->heights;
        for (int r = 0; r < kSide && ok; ++r)
          for (int c = 0; c < kSide && ok; ++c) ok = f->heights[size_t(r * kSide + c)] == expected(c, r, f->step);
        if (!ok) ++bad_frames;
        ++frames_checked;
      } else if (finished) {
        break;
      }
    }
  });
  for (std::int64_t k = 1; k <= kSteps; ++k) {
    ex.note_changed(write_step(grid, k));
    ex.back().step = k;
    ex.publish(grid);
  }
  done.store(true, std::memory_order_release);
  reader.join();
  EXPECT_EQ(bad_frames.load(), 0);
  EXPECT_GT(frames_checked.load(), 0);
}

TEST(SnapshotExchange, AFrameSumsUpTheTicksTheReaderDidNotSee) {
  // A brief contact between two frames the reader takes is in the window's
  // maximum, and the mean is over every tick since the reader's last frame.
  HeightGrid grid(spec(), std::vector<float>(kSide * kSide, 0.0f));
  SnapshotExchange ex(grid);
  const double forces[] = {1.0, 50.0, 2.0};
  for (double f : forces) {
    ex.back().force_world_n = {0.0, 0.0, f};
    ex.back().contact.length_m = f / 100.0;
    ex.publish(grid);
  }
  const ViewFrame* a = ex.acquire();
  ASSERT_NE(a, nullptr);
  EXPECT_EQ(a->force_world_n.z, 2.0);  // the newest tick
  EXPECT_EQ(a->window.ticks, 3);
  EXPECT_EQ(a->window.force_max_n, 50.0);
  EXPECT_DOUBLE_EQ(a->window.mean(a->window.force_sum_n), 53.0 / 3.0);
  EXPECT_DOUBLE_EQ(a->window.contact_max_m, 0.5);
  // The next frame starts afresh.
  ex.back().force_world_n = {0.0, 3.0, 4.0};
  ex.back().contact.length_m = 0.0;
  ex.publish(grid);
  const ViewFrame* b = ex.acquire();
  ASSERT_NE(b, nullptr);
  EXPECT_EQ(b->window.ticks, 1);
  EXPECT_DOUBLE_EQ(b->window.force_max_n, 5.0);
  EXPECT_EQ(b->window.contact_max_m, 0.0);
  EXPECT_EQ(ViewWindow{}.mean(1.0), 0.0);
}

}  // namespace
}  // namespace terracut::haptics
