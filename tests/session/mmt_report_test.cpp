// The comparison of a session from its two stations' records
// (session::compare_records, src/session/mmt_report.cpp): each operator tick
// is compared with the remote's first tick that followed its command or a
// newer one, whatever the delay, the lost commands and the remote's idle
// ticks before the first command; the force errors are then exactly the
// difference built into the records.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "terracut/session/mmt.hpp"

namespace terracut::session {
namespace {

// The remote's horizontal force for command q: any function of q will do.
double force_of(std::uint32_t q) { return 100.0 + 50.0 * std::sin(0.01 * double(q)); }

TEST(MmtReport, EachOperatorTickMeetsTheRemotesFirstTickFollowingItsCommand) {
  constexpr int kTicks = 3000, kIdle = 40, kLag = 57;
  constexpr double kError = 12.5;  // the operator's force is the remote's + this, along x
  std::mt19937 rng(7);
  std::vector<OperatorRecord> op(kTicks);
  for (int i = 0; i < kTicks; ++i) {
    op[std::size_t(i)].t_s = i * 1e-3;
    op[std::size_t(i)].command_sequence = std::uint32_t(i);
    op[std::size_t(i)].force_world_n = {force_of(std::uint32_t(i)) + kError, 0.0, 0.0};
    op[std::size_t(i)].remote_force_world_n = {force_of(std::uint32_t(i)) - 2.0 * kError, 0.0, 0.0};
  }
  // The remote: idle ticks (no command yet), then commands arriving kLag
  // ticks late, 10 % of them lost: it follows the newest one it has.
  std::vector<RemoteRecord> rm;
  for (int j = 0; j < kIdle; ++j) rm.push_back(RemoteRecord{});
  std::uint32_t newest = 0;
  bool any = false;
  for (int j = 0; j < kTicks + kLag; ++j) {
    const int arriving = j - kLag;
    if (arriving >= 0 && arriving < kTicks && (arriving == 0 || std::uniform_real_distribution<>(0, 1)(rng) > 0.1)) {
      newest = std::uint32_t(arriving);
      any = true;
    }
    RemoteRecord r;
    r.active = any;
    r.command_sequence = newest;
    r.force_world_n = any ? Vec3{force_of(newest), 0.0, 0.0} : Vec3{};
    rm.push_back(r);
  }
  MmtSummary s;
  compare_records(op, rm, s);
  // A lost command is met by the next that arrived: its force differs by
  // that command's change (50 x 0.01 N a command at most, a few commands
  // at most): the error is kError within that.
  const double slack = 50.0 * 0.01 * 6.0;
  EXPECT_NEAR(s.force_error_rms_mmt_n, kError, slack);
  EXPECT_NEAR(s.force_error_max_mmt_n, kError, slack);
  EXPECT_NEAR(s.force_error_rms_dfr_n, 2.0 * kError, slack);
  EXPECT_GT(s.force_rms_remote_n, 50.0);
  // Without losses it is exact.
  for (int j = kIdle; j < int(rm.size()); ++j) {
    const int arriving = std::min(std::max(j - kIdle - kLag, 0), kTicks - 1);
    rm[std::size_t(j)].active = j - kIdle >= kLag;
    rm[std::size_t(j)].command_sequence = std::uint32_t(arriving);
    rm[std::size_t(j)].force_world_n = {force_of(std::uint32_t(arriving)), 0.0, 0.0};
  }
  compare_records(op, rm, s);
  EXPECT_NEAR(s.force_error_rms_mmt_n, kError, 1e-9);
  EXPECT_NEAR(s.force_error_max_mmt_n, kError, 1e-9);
}

TEST(MmtReport, NoRemoteTickFollowedAnyCommandNoErrorToReport) {
  std::vector<OperatorRecord> op(100);
  for (std::size_t i = 0; i < op.size(); ++i) {
    op[i].command_sequence = std::uint32_t(i);
    op[i].force_world_n = {5.0, 0.0, 0.0};
  }
  std::vector<RemoteRecord> rm(100);  // never active
  MmtSummary s;
  compare_records(op, rm, s);
  EXPECT_EQ(s.force_error_rms_mmt_n, 0.0);
  EXPECT_EQ(s.tracking_rms_m, 0.0);
}

}  // namespace
}  // namespace terracut::session
