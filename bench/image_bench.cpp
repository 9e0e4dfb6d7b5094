// Benchmark of loading a large terrain: reading an 8192 x 8192 16-bit grey
// PNG and resampling it to the simulation's grid size.
//
// The PNG is written once before the benchmarks (untimed) into the system's
// temporary folder and removed at exit. Its content is a terrain-like height
// map: a dome and long waves plus a few least-significant bits of noise, so
// it does not compress unrealistically well.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <random>
#include <string>
#include <unistd.h>
#include <vector>

#include "terracut/io/image.hpp"

namespace {

constexpr int kSide = 8192;

std::filesystem::path g_png;

void write_test_png(const std::filesystem::path& path) {
  std::vector<float> v(size_t(kSide) * kSide);
  std::mt19937 rng(8192);
  std::uniform_int_distribution<int> noise(-4, 4);
  for (int r = 0; r < kSide; ++r) {
    double z = (r + 0.5) / kSide - 0.5;
    for (int c = 0; c < kSide; ++c) {
      double x = (c + 0.5) / kSide - 0.5;
      double q = 1.0 - (x * x + z * z) / 0.16;
      double h = 0.3 + (q > 0.0 ? 0.5 * std::sqrt(q) : 0.0) +
                 0.05 * std::sin(2.0 * std::numbers::pi * 7.0 * x) * std::cos(2.0 * std::numbers::pi * 5.0 * z);
      v[size_t(r) * kSide + c] = float(h + noise(rng) / 65535.0);
    }
  }
  terracut::io::write_png16(path, v.data(), kSide, kSide, 1.0);
}

void bm_read(benchmark::State& state) {
  for (auto _ : state) {
    terracut::io::Image image = terracut::io::read_png(g_png);
    benchmark::DoNotOptimize(image.values.data());
  }
  state.counters["side"] = kSide;
  state.counters["file_mib"] = double(std::filesystem::file_size(g_png)) / (1024.0 * 1024.0);
}

void bm_read_resample(benchmark::State& state) {
  int target = int(state.range(0));
  for (auto _ : state) {
    terracut::io::Image image = terracut::io::read_png(g_png);
    terracut::io::Image grid = terracut::io::resample(image, target, target);
    benchmark::DoNotOptimize(grid.values.data());
  }
  state.counters["side"] = kSide;
  state.counters["target_side"] = target;
}

}  // namespace

int main(int argc, char** argv) {
  g_png = std::filesystem::temp_directory_path() /
          ("terracut_bench_" + std::to_string(::getpid()) + "_8192.png");
  write_test_png(g_png);
  benchmark::RegisterBenchmark("png/read/side:8192", bm_read)
      ->Iterations(3)->Unit(benchmark::kMillisecond)->UseRealTime();
  // Shrinking by 2 (box filter), by a non-integer factor, and enlarging.
  benchmark::RegisterBenchmark("png/read_resample/side:8192", bm_read_resample)
      ->Arg(4096)->Arg(6000)->Arg(10000)->Iterations(3)->Unit(benchmark::kMillisecond)->UseRealTime();
  benchmark::Initialize(&argc, argv);
  int rc = 0;
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) {
    rc = 1;
  } else {
    benchmark::RunSpecifiedBenchmarks();
  }
  benchmark::Shutdown();
  std::error_code ec;
  std::filesystem::remove(g_png, ec);
  return rc;
}
