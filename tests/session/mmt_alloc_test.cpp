// Both MMT stations in one process over the emulated link (delay, jitter,
// independent and bursty loss, reordering) allocate nothing per tick in
// steady state, terrain patches and soil estimates included. This program
// replaces the global operator new and also malloc, calloc and realloc (so
// that zstd's and the C library's allocations are seen too), and counts every
// call over the ticks after a warm-up: the cut's plunge, by when the link's
// pooled buffers, the blends and zstd's contexts have met their working sizes.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <filesystem>

#include "terracut/session/mmt.hpp"
#include "terracut/session/scenario.hpp"

#include "../support/counting_new.hpp"
#include "../support/peak_memory.hpp"

// Under a sanitizer malloc is the sanitizer's: only operator new is counted
// there (TERRACUT_TEST_SANITIZED, peak_memory.hpp).
#if defined(TERRACUT_TEST_SANITIZED)
#define TERRACUT_COUNT_MALLOC 0
#endif
#ifndef TERRACUT_COUNT_MALLOC
#define TERRACUT_COUNT_MALLOC 1
#endif

namespace {
std::atomic<long> g_mallocs{0};
}

#if TERRACUT_COUNT_MALLOC
// glibc's own entry points, under the names it exports for interposers.
extern "C" void* __libc_malloc(std::size_t);
extern "C" void* __libc_calloc(std::size_t, std::size_t);
extern "C" void* __libc_realloc(void*, std::size_t);

extern "C" void* malloc(std::size_t size) {
  g_mallocs.fetch_add(1, std::memory_order_relaxed);
  return __libc_malloc(size);
}
extern "C" void* calloc(std::size_t n, std::size_t size) {
  g_mallocs.fetch_add(1, std::memory_order_relaxed);
  return __libc_calloc(n, size);
}
extern "C" void* realloc(void* p, std::size_t size) {
  g_mallocs.fetch_add(1, std::memory_order_relaxed);
  return __libc_realloc(p, size);
}
#endif

namespace terracut::session {
namespace {

namespace fs = std::filesystem;

TEST(MmtAllocation, BothStationsTicksAllocateNothingInSteadyState) {
  Scenario sc = load_scenario(fs::path(TERRACUT_SOURCE_DIR) / "scenarios/mmt_trench_clay.yaml");
  // The drag 5 cm deep instead of 8 (the keyframes at 0.22 m raised to
  // 0.25 m): at 1 m/s the low-speed cap (500 N s/m) then stands above the
  // clay's force, so the soil sets the force and the estimate moves and is
  // sent in the counted ticks (at 8 cm the cap holds both worlds' force and
  // the estimate takes no sample there).
  for (Motion& cut : sc.base.cuts)
    for (Keyframe& k : cut.keyframes)
      if (std::abs(k.pose.position_m.y - 0.22) < 1e-9) k.pose.position_m.y = 0.25;
  for (net::LinkConditions* c : {&sc.mmt->to_remote, &sc.mmt->to_operator}) {
    c->delay_s = 0.05;
    c->jitter_s = 0.004;
    c->loss = 0.02;
    c->burst.p_good_to_bad = 0.01;
    c->burst.p_bad_to_good = 0.3;
    c->reorder = 0.02;
  }
  MmtRun run(sc);
  const double rate = run.operator_station().rate_hz();
  // The warm-up: through the plunge (the path's 1.5 s keyframe) and 0.3 s of
  // cutting, so that patches of the cut's working size have come and gone.
  const std::int64_t warm = std::llround(1.8 * rate);
  ASSERT_LT(warm, run.total_ticks());
  for (std::int64_t i = 0; i < warm; ++i) run.tick();
  // The counters do see allocations (building both stations made plenty).
  ASSERT_GT(g_allocations.load(), 10);
  if (TERRACUT_COUNT_MALLOC) {
    ASSERT_GT(g_mallocs.load(), 10);
  }

  const StationCounters op_before = run.operator_station().counters();
  const StationCounters remote_before = run.remote_station().counters();
  const long news_before = g_allocations.load();
  const long mallocs_before = g_mallocs.load();
  while (run.ticks_run() < run.total_ticks()) run.tick();
  const long news = g_allocations.load() - news_before;
  const long mallocs = g_mallocs.load() - mallocs_before;

  const std::int64_t counted = run.total_ticks() - warm;
  EXPECT_EQ(news, 0) << "operator new calls in " << counted << " ticks of both stations";
  EXPECT_EQ(mallocs, 0) << "malloc/calloc/realloc calls in " << counted << " ticks";
  // What the counted ticks did: patches merged, estimates applied, commands
  // and measurements across a lossy link, the tool in the soil.
  const StationCounters& op = run.operator_station().counters();
  const StationCounters& remote = run.remote_station().counters();
  EXPECT_GT(op.patches - op_before.patches, 10);
  EXPECT_GT(op.estimates - op_before.estimates, 5);
  EXPECT_GT(remote.accepted - remote_before.accepted, counted / 4);
  EXPECT_GT(run.link().a().emulator().counters().lost, 0);
  EXPECT_GT(run.link().a().emulator().counters().held_back, 0);
  bool cut = false;
  for (std::size_t i = std::size_t(warm); i < run.remote_station().records().size(); ++i)
    cut = cut || run.remote_station().records()[i].contact_length_m > 0.0;
  EXPECT_TRUE(cut) << "the remote's tool never touched the soil in the counted ticks";
}

}  // namespace
}  // namespace terracut::session
