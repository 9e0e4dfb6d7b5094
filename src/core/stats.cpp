// Percentiles of per-step times. See stats.hpp.
#include "terracut/core/stats.hpp"

#include <algorithm>
#include <cmath>

namespace terracut {

TimingStats timing_stats(std::vector<double>& seconds) {
  TimingStats s;
  if (seconds.empty()) return s;
  std::sort(seconds.begin(), seconds.end());
  const std::size_t n = seconds.size();
  const auto rank = [&](double p) {
    std::size_t r = static_cast<std::size_t>(std::ceil(p / 100.0 * double(n)));
    return seconds[std::clamp<std::size_t>(r, 1, n) - 1] * 1e6;
  };
  s.p50_us = rank(50);
  s.p90_us = rank(90);
  s.p99_us = rank(99);
  s.max_us = seconds.back() * 1e6;
  double sum = 0.0;
  for (double v : seconds) sum += v;
  s.mean_us = sum / double(n) * 1e6;
  return s;
}

}  // namespace terracut
