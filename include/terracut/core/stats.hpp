// Percentiles of per-step times: the one percentile type of terracut, used
// for the batch run's step timers and the haptic loop's kept records. (The
// pacer keeps its own fixed-size histograms, pacer.hpp, because the loop
// thread may not allocate or sort.)
#pragma once

#include <vector>

namespace terracut {

/// Nearest-rank percentiles of a set of times, microseconds (all zero for an
/// empty set).
struct TimingStats {
  double p50_us = 0.0;
  double p90_us = 0.0;
  double p99_us = 0.0;
  double max_us = 0.0;
  double mean_us = 0.0;
};

/// The nearest-rank percentiles of times given in seconds (sorted in place),
/// in microseconds: the p-th percentile is the value of rank ceil(p/100 * n).
TimingStats timing_stats(std::vector<double>& seconds);

}  // namespace terracut
