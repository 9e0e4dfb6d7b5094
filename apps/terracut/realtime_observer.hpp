// `terracut run --realtime`: pace the steps to the wall clock at the
// scenario's rate and report whether the step fits the period.
#pragma once

#include <memory>

#include "terracut/io/run.hpp"

namespace terracut::cli {

/// A run observer that waits for each step's deadline (rate_hz) and adds a
/// "realtime" entry to summary.json: step time and period-jitter percentiles
/// (p50, p99, max) and the count of missed deadlines.
std::unique_ptr<io::RunObserver> make_realtime_observer(double rate_hz);

}  // namespace terracut::cli
