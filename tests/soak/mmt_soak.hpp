// The teleoperation soak of terracut-soak (mmt_soak.cpp, docs/reliability.md).
#pragma once

#include <cstdint>
#include <filesystem>

namespace terracut::soak {

struct MmtSoakOptions {
  double duration_s = 10.0;
  std::filesystem::path scenario;  ///< with an mmt: section
  std::uint32_t seed = 1;
  bool enet = false;  ///< loopback UDP through ENet, wall clock; else the in-memory link
};

/// Runs both stations under a hostile peer; prints the figures. Returns the
/// exit status: 0 when every promise was kept. Throws InputError for a bad
/// scenario.
int run_mmt_soak(const MmtSoakOptions& options);

}  // namespace terracut::soak
