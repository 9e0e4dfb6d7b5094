// Model-mediated teleoperation in one process: determinism, convergence of
// the local model to the remote's terrain and soil, the bound on force steps
// at updates, bad packets on both stations, and a link gone silent.
#include "terracut/session/mmt.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "terracut/core/error.hpp"
#include "terracut/core/wire.hpp"
#include "terracut/session/scenario.hpp"
#include "terracut/session/world.hpp"
#include "../support/scenario_text.hpp"

namespace terracut::session {
namespace {

namespace fs = std::filesystem;

const fs::path kTrench = fs::path(TERRACUT_SOURCE_DIR) / "scenarios" / "mmt_trench_clay.yaml";

using test::read_text;

// The trench scenario, with the remote's world written next to it from the
// same text after the edit (a different plane height, another soil).
Scenario trench_with_remote(const std::string& name, double remote_height_m,
                            const std::string& remote_soil) {
  const fs::path dir = fs::temp_directory_path() / ("terracut_mmt_" + name);
  fs::create_directories(dir);
  std::string remote = read_text(kTrench);
  std::ostringstream h;
  h << "height_m: " << remote_height_m;
  remote = test::replace(remote, "height_m: 0.3", h.str());
  remote = test::replace(remote, "preset: dry_sand", "preset: " + remote_soil);
  std::ofstream(dir / "remote.yaml") << remote;
  Scenario sc = load_scenario(kTrench);
  sc.mmt->remote_scenario = dir / "remote.yaml";
  sc.mmt->remote_soil.reset();
  return sc;
}

TEST(Mmt, SameSeedSameRunOtherSeedOtherLink) {
  Scenario sc = load_scenario(kTrench);
  // Bursty loss and held-back datagrams on top of the overrides' loss and jitter.
  for (net::LinkConditions* c : {&sc.mmt->to_remote, &sc.mmt->to_operator}) {
    c->burst.p_good_to_bad = 0.01;
    c->burst.p_bad_to_good = 0.3;
    c->reorder = 0.02;
  }
  MmtOverrides o;
  o.rtt_s = 0.1;
  o.loss = 0.05;
  o.jitter_s = 0.003;
  o.seed = 7;
  MmtRun a(sc, o), b(sc, o);
  a.run();
  b.run();
  const auto& ra = a.operator_station().records();
  const auto& rb = b.operator_station().records();
  ASSERT_EQ(ra.size(), rb.size());
  for (std::size_t i = 0; i < ra.size(); ++i) {
    ASSERT_EQ(ra[i].force_world_n.z, rb[i].force_world_n.z) << i;
    ASSERT_EQ(ra[i].remote_force_world_n.z, rb[i].remote_force_world_n.z) << i;
  }
  const auto& qa = a.remote_station().records();
  const auto& qb = b.remote_station().records();
  for (std::size_t i = 0; i < qa.size(); ++i) ASSERT_EQ(qa[i].tool_m.z, qb[i].tool_m.z) << i;
  EXPECT_EQ(a.summary().force_error_rms_mmt_n, b.summary().force_error_rms_mmt_n);
  // Jitter of 3 ms over 1 ms spacing reorders; loss loses.
  EXPECT_GT(a.operator_station().counters().rejected[net::Reject::kReordered], 0);
  EXPECT_GT(a.link().b().emulator().counters().lost, 0);
  EXPECT_GT(a.link().a().emulator().counters().held_back, 0);
  EXPECT_GT(a.link().b().emulator().counters().retransmits, 0);  // patches lost and resent
  // Every patch arrived but those still on their way at the end: in order
  // behind the unluckiest, they are at most the ones sent in the last
  // delay + jitter + hold-back + its retransmissions x the timeout.
  const net::LinkEmulator& to_operator = a.link().b().emulator();
  const net::LinkConditions& lc = to_operator.conditions();
  const double in_flight_s = lc.delay_s + lc.jitter_s + (lc.reorder > 0.0 ? lc.reorder_delay_s : 0.0) +
                             to_operator.counters().max_retransmits * to_operator.retransmit_s();
  const auto in_flight = std::int64_t(std::ceil(in_flight_s / sc.mmt->sense_period_s)) + 1;
  EXPECT_GT(to_operator.counters().max_retransmits, 0);
  EXPECT_LE(a.summary().patches - a.operator_station().counters().patches, in_flight);
  EXPECT_EQ(a.operator_station().counters().rejected.total(),
            a.operator_station().counters().rejected[net::Reject::kReordered]);
  o.seed = 8;
  MmtRun c(sc, o);
  c.run();
  EXPECT_NE(c.link().b().emulator().counters().lost, a.link().b().emulator().counters().lost);
}

TEST(Mmt, LocalModelConvergesToTheRemoteTerrainAndSoil) {
  // The remote's sand surface is 2 cm lower and its soil is clay.
  const Scenario sc = trench_with_remote("converge", 0.28, "clay");
  MmtRun run(sc);
  run.run();
  const MmtSummary s = run.summary();
  // Before the updates landed the worked region differed by the 2 cm (and
  // by the cuts made at different depths).
  EXPECT_GT(s.terrain_rms_max_m, 0.01);
  // After: equal to the remote's except where the local tool cut ahead of
  // what the remote had reported (the lower of the two is kept there); the
  // follower lags the command by less than a cell, so within a tenth of
  // the mismatch.
  EXPECT_LT(s.terrain_rms_final_m, 0.002);
  // The soil: the remote's estimate of its clay from its physical force
  // predicts the clay's cutting force at the remote's cut (depth 0.28 -
  // 0.22 = 6 cm, the 0.4 m blade) within its own residual (two of them and
  // 2 %), and the operator's model ends on that material.
  EarthmovingParams clay, estimate, applied;
  clay.soil = soil_preset(SoilPreset::kClay);
  estimate.soil = s.estimate.material;
  applied.soil = s.material_applied;
  const double truth = earthmoving_force(clay, 0.4, 0.06).horizontal_n;
  EXPECT_NEAR(earthmoving_force(estimate, 0.4, 0.06).horizontal_n, truth,
              2.0 * s.estimate.residual_rms_n + 0.02 * truth);
  EXPECT_NEAR(earthmoving_force(applied, 0.4, 0.06).horizontal_n,
              earthmoving_force(estimate, 0.4, 0.06).horizontal_n, 1e-9 * truth);
  EXPECT_GT(s.estimate.samples, 100);
}

TEST(Mmt, ForceStepAtUpdatesStaysUnderTheBound) {
  // Frequent large updates: patches every 10 ms of a terrain 3 cm off, a
  // soil twice as resistant, a short blend.
  Scenario sc = trench_with_remote("steps", 0.27, "clay");
  sc.mmt->sense_period_s = 0.01;
  sc.mmt->blend_s = 0.02;
  sc.mmt->max_update_step_n = 0.005;
  MmtRun run(sc);
  run.run();
  const MmtSummary s = run.summary();
  EXPECT_GT(s.patches, 50);
  EXPECT_GT(s.estimates, 10);  // the estimate is sent while it moves, then stays
  EXPECT_LE(s.max_update_step_n, 0.005 + 1e-12);
  // The bound held and still the material got where it was going.
  for (int f = 0; f < kSoilFieldCount; ++f)
    EXPECT_NEAR(field_value(s.material_applied, SoilField(f)),
                field_value(s.estimate.material, SoilField(f)),
                1e-9 * std::max(1.0, field_value(s.estimate.material, SoilField(f))))
        << to_string(SoilField(f));
  // Without the bound, the same updates step the force by more.
  sc.mmt->max_update_step_n = 100.0;
  MmtRun unbounded(sc);
  unbounded.run();
  EXPECT_GT(unbounded.summary().max_update_step_n, 2 * 0.005);
}

TEST(Mmt, DirectReflectionFailsWithDelayMmtHolds) {
  const Scenario sc = load_scenario(kTrench);
  MmtOverrides o;
  o.rtt_s = 0.0;
  MmtRun near(sc, o);
  near.run();
  o.rtt_s = 0.5;
  MmtRun far(sc, o);
  far.run();
  const MmtSummary a = near.summary(), b = far.summary();
  // Direct reflection renders a force a round trip old: its error grows
  // with the delay; the local model's does not grow as much.
  EXPECT_GT(b.force_error_rms_dfr_n, 1.5 * a.force_error_rms_dfr_n);
  EXPECT_LT(b.force_error_rms_mmt_n, b.force_error_rms_dfr_n);
}

TEST(Mmt, NoRenderedOrCappedForceReachesTheEstimate) {
  // The remote's own rendering (its haptic loop's low-speed cap, gain and
  // scale) is what a device would be sent, not what its soil does: with a
  // cap of 50 N s/m (every cut capped far below the soil's force) and with
  // the trench's 500 N s/m, the remote measures, sends and estimates from
  // the same physical force, bit for bit.
  const Scenario a = trench_with_remote("render_a", 0.3, "clay");
  Scenario b = trench_with_remote("render_b", 0.3, "clay");
  {
    std::string text = read_text(b.mmt->remote_scenario);
    text = test::replace(text, "low_speed_damping_n_s_per_m: 500", "low_speed_damping_n_s_per_m: 50");
    text = test::replace(text, "force_scale: 0.0025", "force_scale: 0.001");
    std::ofstream(b.mmt->remote_scenario) << text;
  }
  MmtRun ra(a), rb(b);
  ra.run();
  rb.run();
  const auto& qa = ra.remote_station().records();
  const auto& qb = rb.remote_station().records();
  ASSERT_EQ(qa.size(), qb.size());
  for (std::size_t i = 0; i < qa.size(); ++i) {
    ASSERT_EQ(qa[i].force_world_n.z, qb[i].force_world_n.z) << i;
    ASSERT_EQ(qa[i].estimate.material.cohesion_pa, qb[i].estimate.material.cohesion_pa) << i;
    ASSERT_EQ(qa[i].estimate.material.internal_friction_deg,
              qb[i].estimate.material.internal_friction_deg) << i;
  }
}

TEST(Mmt, TheSoilEstimateDoesNotDependOnTheToolsSpeed) {
  // The trench cut at its speed (1 m/s along the drag) and at half of it:
  // the soil's force does not depend on the speed, and neither does the
  // estimate of it: both predict the clay's force at the full 8 cm within
  // their residual (two of them and 2 %).
  Scenario slow = load_scenario(kTrench);
  for (Motion& cut : slow.base.cuts)
    for (Keyframe& k : cut.keyframes)
      if (k.t_s > 1.0) k.t_s = 1.0 + 2.0 * (k.t_s - 1.0);
  MmtRun at_speed(load_scenario(kTrench)), half(slow);
  at_speed.run();
  half.run();
  EarthmovingParams clay;
  clay.soil = soil_preset(SoilPreset::kClay);
  const double truth = earthmoving_force(clay, 0.4, 0.08).horizontal_n;
  for (const MmtSummary& s : {at_speed.summary(), half.summary()}) {
    EarthmovingParams e;
    e.soil = s.estimate.material;
    EXPECT_NEAR(earthmoving_force(e, 0.4, 0.08).horizontal_n, truth,
                2.0 * s.estimate.residual_rms_n + 0.02 * truth);
    // The operator's physical force follows the remote's after the first
    // second of cutting (the study's target: 5 %).
    EXPECT_LT(s.force_error_rel_mmt_after_1s, 0.05);
    EXPECT_LT(s.force_error_rms_mmt_after_1s_n, s.force_error_rms_dfr_after_1s_n);
  }
}

// The study's scenarios: a remote of known material is identified within
// its uncertainty, and a change of soil along the path is found again.
TEST(Mmt, ARemoteOfKnownMaterialIsIdentifiedWithinItsUncertainty) {
  for (const char* name : {"mmt_learn_clay.yaml", "mmt_learn_gravel.yaml"}) {
    MmtRun run(load_scenario(fs::path(TERRACUT_SOURCE_DIR) / "scenarios" / name));
    run.run();
    const MmtSummary s = run.summary();
    int identifiable = 0;
    for (int f = 0; f < kSoilFieldCount; ++f) {
      const SoilField field = SoilField(f);
      if (!s.estimate.is_identifiable(field)) continue;
      ++identifiable;
      EXPECT_LE(std::fabs(field_value(s.estimate.material, field) - field_value(s.remote_material, field)),
                2.0 * s.estimate.sd[std::size_t(f)])
          << name << " " << to_string(field) << " " << field_value(s.estimate.material, field)
          << " +- " << s.estimate.sd[std::size_t(f)] << ", truth "
          << field_value(s.remote_material, field);
    }
    // A vertical and a raked blade at one width: at least the adhesion and
    // the soil-tool friction (the vertical force's share) are identified.
    EXPECT_GE(identifiable, 2) << name;
    EXPECT_LT(s.force_error_rel_mmt_after_1s, 0.05) << name;
  }
}

TEST(Mmt, AChangeOfSoilIsReidentifiedWithinHalfASecond) {
  MmtRun run(load_scenario(fs::path(TERRACUT_SOURCE_DIR) / "scenarios" / "mmt_learn_change.yaml"));
  run.run();
  const MmtSummary s = run.summary();
  EXPECT_GE(s.estimate.restarts, 1);
  EXPECT_GE(s.reidentified_after_s, 0.0);
  EXPECT_LT(s.reidentified_after_s, 0.5);
  // The target on the operator's force, after the first second of
  // cutting (the round trip and 0.5 s after the change left out): within
  // 5 % of the remote's. It needs the remote arm's servo in the operator's
  // model: without it the blade's vertical reversals, where the plastic
  // penetration force flips, come a servo lag apart.
  ASSERT_TRUE(load_scenario(fs::path(TERRACUT_SOURCE_DIR) / "scenarios" / "mmt_learn_change.yaml").mmt->models_arm);
  EXPECT_LT(s.force_error_rel_mmt_after_1s, 0.05);
  // The soil beyond the change is the clay.
  for (int f = 0; f < kSoilFieldCount; ++f)
    EXPECT_EQ(field_value(s.remote_material, SoilField(f)),
              field_value(soil_preset(SoilPreset::kClay), SoilField(f)));
}

TEST(Mmt, TheRemoteArmStallsAtItsForceLimit) {
  // An arm that pushes at most 150 N against the clay's 500 N at 8 cm:
  // it stalls (holds) while the force exceeds that, so it falls behind
  // the command, and the force it measures stays about the limit instead
  // of the soil's full resistance at speed.
  Scenario sc = load_scenario(kTrench);
  MmtRun free_arm(sc);
  free_arm.run();
  sc.mmt->arm_force_limit_n = 150.0;
  MmtRun limited(sc);
  limited.run();
  const MmtSummary a = free_arm.summary(), b = limited.summary();
  EXPECT_EQ(a.stalled_ticks, 0);
  EXPECT_GT(b.stalled_ticks, 100);
  EXPECT_GT(b.tracking_max_m, 2.0 * a.tracking_max_m);
  EXPECT_LT(b.force_rms_remote_n, a.force_rms_remote_n);
}

TEST(Mmt, DeadbandSavesUpdatePackets) {
  Scenario sc = trench_with_remote("deadband", 0.28, "clay");
  MmtRun every(sc);
  every.run();
  sc.mmt->deadband = 0.1;
  MmtRun jnd(sc);
  jnd.run();
  EXPECT_LT(jnd.summary().update_packets_per_s, 0.8 * every.summary().update_packets_per_s);
  EXPECT_GT(jnd.summary().patches, 0);
}

// Stations driven by hand over one in-memory link.
struct Pair {
  explicit Pair(const Scenario& sc)
      : settings(*sc.mmt),
        remote_sc(load_remote_scenario(sc)),
        device(make_operator_device(sc)),
        link(settings.to_remote, settings.to_operator),
        op(sc, settings, *device, link.a(), 1u),
        remote(remote_sc, settings, sc.base.soil.material, op.simulation().grid(),
               link.b(), 2u) {}
  MmtSettings settings;
  Scenario remote_sc;
  std::unique_ptr<haptics::Device> device;
  net::EmulatedLink link;
  OperatorStation op;
  RemoteStation remote;
};

// A carrier that loses the first datagram of one type it is handed (after
// the emulator: the emulator sent it, the network lost it).
class LoseFirst final : public net::Endpoint {
 public:
  LoseFirst(net::Endpoint& inner, std::uint32_t link, net::MessageType type)
      : inner_(inner), link_(link), type_(type) {}
  void send(net::Channel channel, const std::uint8_t* data, std::size_t size, double now_s) override {
    net::Header h;
    if (!lost_ && net::decode_header(data, size, link_, h) == net::Reject::kNone && h.type == type_) {
      lost_ = true;
      lost_at_s_ = now_s;
      return;
    }
    inner_.send(channel, data, size, now_s);
  }
  void receive(double now_s, net::Inbox& out) override { inner_.receive(now_s, out); }
  using net::Endpoint::receive;
  bool lost() const { return lost_; }
  double lost_at_s() const { return lost_at_s_; }

 private:
  net::Endpoint& inner_;
  std::uint32_t link_;
  net::MessageType type_;
  bool lost_ = false;
  double lost_at_s_ = 0.0;
};

// The remote's first estimate is lost on its way (a 1 s round trip, the
// deadband on: nothing new may go for seconds). The estimate is state and
// travels unreliably, newest wins, and goes again when none has gone for
// estimate_resend_s: the operator has one at most a resend period (and a
// tick) after the lost one would have arrived. On the in-order reliable
// channel it waited for the retransmission, a round trip (1 s) later.
TEST(Mmt, ALostEstimateIsReplacedWithinOneResendPeriod) {
  Scenario sc = load_scenario(fs::path(TERRACUT_SOURCE_DIR) / "scenarios" / "mmt_learn_gravel.yaml");
  MmtSettings& m = *sc.mmt;
  m.to_remote.delay_s = m.to_operator.delay_s = 0.5;
  m.to_remote.jitter_s = m.to_operator.jitter_s = 0.0;
  m.to_remote.loss = m.to_operator.loss = 0.0;
  m.deadband = 0.1;
  ASSERT_LT(m.estimate_resend_s, 0.9);  // shorter than the round trip it replaces
  const double rate = sc.base.rate_hz;
  const Scenario remote_sc = load_remote_scenario(sc);
  std::unique_ptr<haptics::Device> device = make_operator_device(sc);
  net::MemoryLink memory;
  LoseFirst lossy(memory.b(), m.link_id, net::MessageType::kEstimate);
  net::EmulatedEndpoint to_remote(memory.a(), m.to_remote), to_operator(lossy, m.to_operator);
  OperatorStation op(sc, m, *device, to_remote, 1u);
  RemoteStation remote(remote_sc, m, sc.base.soil.material, op.simulation().grid(), to_operator, 2u);
  double received_s = -1.0;
  for (int i = 0; i / rate < 4.0 && received_s < 0.0; ++i) {
    op.tick(i / rate);
    remote.tick(i / rate);
    if (op.last_estimate().samples > 0) received_s = i / rate;
  }
  ASSERT_TRUE(lossy.lost());
  ASSERT_GE(received_s, 0.0) << "no estimate reached the operator";
  EXPECT_GT(received_s, lossy.lost_at_s());
  EXPECT_LE(received_s, lossy.lost_at_s() + m.estimate_resend_s + 2.0 / rate);
}

// With the remote's arm in the operator's model (mmt.operator.models_arm)
// the local blade makes the remote's motion: the remote's tool at its first
// tick that followed a command is where the local tool was at that command
// (the same servo from the same commands; a link without delay, loss or
// jitter, so that each command arrives on its own tick). The price: the
// local tool, and the force rendered from it, lags the hand as the
// remote's arm lags its command: on the trench's steady 1 m/s (1.5 to
// 2.7 s) a first-order servo of time constant tau stepped at dt is
// (tau - dt) x v behind.
TEST(Mmt, TheOperatorsModelMovesAsTheRemoteArmDoes) {
  Scenario sc = load_scenario(kTrench);
  MmtSettings& m = *sc.mmt;
  m.to_remote.delay_s = m.to_operator.delay_s = 0.0;
  m.to_remote.jitter_s = m.to_operator.jitter_s = 0.0;
  m.to_remote.loss = m.to_operator.loss = 0.0;
  const double rate = sc.base.rate_hz;
  const double tau = m.follower_time_constant_s;
  ASSERT_GT(tau, 2.0 / rate);
  for (const bool models_arm : {true, false}) {
    m.models_arm = models_arm;
    Pair p(sc);
    for (int i = 0; i / rate < 3.0; ++i) {
      p.op.tick(i / rate);
      p.remote.tick(i / rate);
    }
    // Per operator tick: the hand (what the remote was commanded), the local
    // tool and the remote's tool at its first tick that followed.
    const auto& op = p.op.records();
    const auto& rm = p.remote.records();
    std::vector<Vec3> hand, local, remote;
    std::size_t j = 0;
    for (const OperatorRecord& o : op) {
      while (j < rm.size() && !(rm[j].active && std::int32_t(rm[j].command_sequence - o.command_sequence) >= 0)) ++j;
      if (j >= rm.size() || rm[j].command_sequence != o.command_sequence) break;
      hand.push_back(rm[j].commanded_m);
      local.push_back(o.tool_m);
      remote.push_back(rm[j].tool_m);
    }
    ASSERT_GT(hand.size(), std::size_t(2.5 * rate)) << models_arm;
    const std::size_t k = std::size_t(std::llround(2.0 * rate));
    const double speed = length(hand[k] - hand[k - 1]) * rate;
    EXPECT_NEAR(speed, 1.0, 1e-6);
    const double lag = (tau - 1.0 / rate) * speed;
    double apart_max = 0.0, hand_local_max = 0.0;
    for (std::size_t i = 0; i < hand.size(); ++i) {
      apart_max = std::max(apart_max, length(local[i] - remote[i]));
      hand_local_max = std::max(hand_local_max, length(local[i] - hand[i]));
    }
    if (models_arm) {
      EXPECT_LT(apart_max, 1e-9);
      EXPECT_NEAR(length(hand[k] - local[k]), lag, 1e-6 * lag);
    } else {
      // The local tool is the hand; the remote's arm is the servo's lag behind it.
      EXPECT_LT(hand_local_max, 1e-9);
      EXPECT_NEAR(length(hand[k] - remote[k]), lag, 1e-6 * lag);
    }
  }
}

TEST(Mmt, BadPacketsOnBothStationsAreCountedNeverFatal) {
  Scenario sc = load_scenario(kTrench);
  sc.mmt->to_remote.delay_s = sc.mmt->to_operator.delay_s = 0.0;
  sc.mmt->to_remote.jitter_s = sc.mmt->to_operator.jitter_s = 0.0;
  Pair p(sc);
  const std::uint32_t link = sc.mmt->link_id;
  auto inject = [](net::Endpoint& from, const std::vector<std::uint8_t>& d) {
    from.send(net::Channel::kUnreliable, d.data(), d.size(), 0.0);
  };
  // A valid command, replayed, an older one, a foreign one, a truncated
  // one, a corrupted one and a measurement sent the wrong way.
  net::Command c;
  c.pose.position_m = {0, 0.35, 0.75};
  std::vector<std::uint8_t> d(net::kHeaderSize + net::kCommandPayloadSize + net::kCrcSize);
  auto command = [&](std::uint32_t session, std::uint32_t seq, std::uint32_t link_id) {
    net::encode_command({net::MessageType::kCommand, link_id, session, seq, 1000u * seq}, c, d.data());
    return d;
  };
  inject(p.link.a(), command(99, 10, link));
  inject(p.link.a(), command(99, 10, link));  // replayed
  inject(p.link.a(), command(99, 9, link));   // older
  inject(p.link.a(), command(99, 11, link + 1));  // foreign
  auto cut = command(99, 12, link);
  cut.resize(20);
  inject(p.link.a(), cut);
  auto flipped = command(99, 13, link);
  flipped[50] ^= 0x40;
  inject(p.link.a(), flipped);
  std::vector<std::uint8_t> m(net::kHeaderSize + net::kMeasurementPayloadSize + net::kCrcSize);
  net::encode_measurement({net::MessageType::kMeasurement, link, 99, 1, 0}, net::Measurement{}, m.data());
  inject(p.link.a(), m);
  inject(p.link.a(), std::vector<std::uint8_t>{1, 2, 3});
  p.remote.tick(0.0);
  const net::RejectCounts& rr = p.remote.counters().rejected;
  EXPECT_EQ(p.remote.counters().accepted, 1);
  EXPECT_EQ(rr[net::Reject::kDuplicate], 1);
  EXPECT_EQ(rr[net::Reject::kReordered], 1);
  EXPECT_EQ(rr[net::Reject::kForeign], 1);
  EXPECT_EQ(rr[net::Reject::kTruncated], 2);
  EXPECT_EQ(rr[net::Reject::kBadChecksum], 1);
  EXPECT_EQ(rr[net::Reject::kBadType], 1);

  // The operator: a command (the wrong way), a patch outside the grid, a
  // patch that is not zstd, a non-finite estimate, a stale measurement.
  inject(p.link.b(), command(5, 1, link));
  net::Patch patch;
  patch.rect = {95, 95, 105, 100};  // the grid has 100 x 100 samples
  patch.heights.assign(50, 0.3f);
  std::vector<std::uint8_t> pd;
  net::encode_patch({net::MessageType::kPatch, link, 5, 1, 0}, patch, pd);
  inject(p.link.b(), pd);
  patch.rect = {0, 0, 10, 5};
  net::encode_patch({net::MessageType::kPatch, link, 5, 2, 0}, patch, pd);
  for (std::size_t i = net::kHeaderSize + net::kPatchFixedSize; i + net::kCrcSize < pd.size(); ++i)
    pd[i] = 0x5A;
  wire::put_u32(pd.data() + pd.size() - 4, wire::crc32(pd.data(), pd.size() - 4));
  inject(p.link.b(), pd);
  std::vector<std::uint8_t> e(net::kHeaderSize + net::kEstimatePayloadSize + net::kCrcSize);
  net::Estimate bad;
  bad.material.cohesion_pa = std::nan("");
  net::encode_estimate({net::MessageType::kEstimate, link, 5, 1, 0}, bad, e.data());
  inject(p.link.b(), e);
  // A valid material that leaves the vertical blade no failure wedge
  // (90 + 89 + 89 degrees): refused, not applied.
  net::Estimate steep;
  steep.material.internal_friction_deg = 89.0;
  steep.material.soil_tool_friction_deg = 89.0;
  net::encode_estimate({net::MessageType::kEstimate, link, 5, 2, 0}, steep, e.data());
  inject(p.link.b(), e);
  net::encode_measurement({net::MessageType::kMeasurement, link, 5, 2, 5000}, net::Measurement{}, m.data());
  inject(p.link.b(), m);
  net::encode_measurement({net::MessageType::kMeasurement, link, 5, 3, 4000}, net::Measurement{}, m.data());
  inject(p.link.b(), m);  // newer sequence, older time: stale
  p.op.tick(0.0);
  const net::RejectCounts& ro = p.op.counters().rejected;
  EXPECT_EQ(ro[net::Reject::kBadType], 1);
  EXPECT_EQ(ro[net::Reject::kBadPayload], 4);
  EXPECT_EQ(ro[net::Reject::kStale], 1);
  EXPECT_EQ(p.op.counters().patches, p.remote.counters().patches);  // only the real ones
  // The stations go on working.
  for (int i = 1; i < 100; ++i) {
    p.op.tick(i * 0.001);
    p.remote.tick(i * 0.001);
  }
  EXPECT_GT(p.op.counters().accepted, 50);
}

// The estimate travels unreliably, newest wins: across the sequence's wrap
// an estimate is newer, and one older than the newest accepted (reordered
// on the way) is refused and counted, never applied.
TEST(Mmt, AnOlderEstimateArrivingLateIsRefusedAcrossTheWrap) {
  Scenario sc = load_scenario(kTrench);
  sc.mmt->to_remote.delay_s = sc.mmt->to_operator.delay_s = 0.0;
  sc.mmt->to_remote.jitter_s = sc.mmt->to_operator.jitter_s = 0.0;
  sc.mmt->to_remote.loss = sc.mmt->to_operator.loss = 0.0;
  Pair p(sc);
  const std::uint32_t link = sc.mmt->link_id;
  std::vector<std::uint8_t> e(net::kHeaderSize + net::kEstimatePayloadSize + net::kCrcSize);
  auto send = [&](std::uint32_t seq, std::uint64_t t_ns, double unit_weight) {
    net::Estimate est;
    est.material.unit_weight_n_per_m3 = unit_weight;
    est.samples = 20;
    net::encode_estimate({net::MessageType::kEstimate, link, 7, seq, t_ns}, est, e.data());
    p.link.b().send(net::Channel::kUnreliable, e.data(), e.size(), 0.0);
  };
  send(0xFFFFFFFEu, 1000, 17000.0);
  send(1u, 3000, 18000.0);           // after the wrap: newer
  send(0xFFFFFFFFu, 2000, 17500.0);  // sent between them, arrived last
  p.op.tick(0.0);
  EXPECT_EQ(p.op.counters().estimates, 2);
  EXPECT_EQ(p.op.counters().rejected[net::Reject::kReordered], 1);
  EXPECT_EQ(p.op.last_estimate().material.unit_weight_n_per_m3, 18000.0);
  // The same estimate again (the remote's resend) is accepted and changes nothing.
  send(2u, 4000, 18000.0);
  p.op.tick(0.001);
  EXPECT_EQ(p.op.counters().estimates, 3);
  EXPECT_EQ(p.op.last_estimate().material.unit_weight_n_per_m3, 18000.0);
}

TEST(Mmt, SilentLinkStopsTheRemoteToolAndFadesTheOperatorsForce) {
  Scenario sc = load_scenario(kTrench);
  const double timeout = sc.mmt->timeout_s;
  const double rate = sc.base.rate_hz;
  // The operator goes quiet at 2.0 s, mid-trench (the tool moves at 1 m/s).
  {
    Pair p(sc);
    int i = 0;
    for (; i / rate < 2.0; ++i) {
      p.op.tick(i / rate);
      p.remote.tick(i / rate);
    }
    for (; i / rate < 2.6; ++i) p.remote.tick(i / rate);
    const auto& r = p.remote.records();
    // Commands stop arriving at 2.0 s + the 50 ms delay; the tool holds still
    // once the timeout has passed, within one follower step.
    const double hold_from = 2.0 + sc.mmt->to_remote.delay_s + sc.mmt->to_remote.jitter_s + timeout + 0.002;
    const std::size_t k = std::size_t(std::ceil(hold_from * rate));
    ASSERT_LT(k, r.size());
    EXPECT_TRUE(r[k].holding);
    const double step = sc.mmt->follower_speed_m_per_s / rate;
    EXPECT_LE(length(r.back().tool_m - r[k].tool_m), step + 1e-12);
    // Before the silence it was moving.
    EXPECT_GT(length(r[std::size_t(1.9 * rate)].tool_m - r[std::size_t(1.8 * rate)].tool_m), 0.05);
  }
  // The remote goes quiet at 2.0 s: the operator's force fades to zero.
  {
    Pair p(sc);
    int i = 0;
    for (; i / rate < 2.0; ++i) {
      p.op.tick(i / rate);
      p.remote.tick(i / rate);
    }
    const double before = length(p.op.records().back().force_device_n);
    EXPECT_GT(before, 0.5);
    for (; i / rate < 2.6; ++i) p.op.tick(i / rate);
    const auto& r = p.op.records();
    const double safety = sc.haptics.safety.watchdog_timeout_s + sc.haptics.safety.watchdog_ramp_s;
    const double faded_by = 2.0 + sc.mmt->to_operator.delay_s + sc.mmt->to_operator.jitter_s + timeout + safety + 0.002;
    const std::size_t k = std::size_t(std::ceil(faded_by * rate));
    ASSERT_LT(k, r.size());
    EXPECT_TRUE(r[k].link_silent);
    for (std::size_t j = k; j < r.size(); ++j) EXPECT_EQ(length(r[j].force_device_n), 0.0) << j;
  }
}

// Runs the trench to mid-cut (edge at z = 0.3, 8 cm deep, moving along -Z),
// then sends the operator a patch 5 cm below the sand over the whole region
// around the tool, and reads two samples 50 ms and 150 ms later: one ahead
// of the edge, within 0.15 m of it all that time and not yet cut (x = 0.01,
// z = 0.19), one far from the tool (x = 0.51, z = 0.41).
struct PatchUnderTool {
  float ahead_50ms, far_50ms, far_150ms;
};
PatchUnderTool patch_under_tool(double exclusion_m) {
  Scenario sc = load_scenario(kTrench);
  sc.mmt->to_remote.delay_s = sc.mmt->to_operator.delay_s = 0.0;
  sc.mmt->to_remote.jitter_s = sc.mmt->to_operator.jitter_s = 0.0;
  sc.mmt->exclusion_m = exclusion_m;
  const double rate = sc.base.rate_hz;
  Pair p(sc);
  int i = 0;
  for (; i / rate < 1.8; ++i) {
    p.op.tick(i / rate);
    p.remote.tick(i / rate);
  }
  EXPECT_GT(p.op.rig().loop().last().contact_length_m, 0.3);
  net::Patch patch;
  patch.rect = {20, 40, 80, 90};  // x in [-0.6, 0.6], z in [-0.2, 0.8]
  patch.heights.assign(std::size_t(patch.rect.area()), 0.25f);
  std::vector<std::uint8_t> d;
  net::encode_patch({net::MessageType::kPatch, sc.mmt->link_id, 77, 0, 0}, patch, d);
  const double t0 = i / rate;
  p.link.b().send(net::Channel::kReliable, d.data(), d.size(), t0);
  const HeightGrid& g = p.op.simulation().grid();
  EXPECT_NEAR(g.sample_z(59), 0.19, 1e-9);
  EXPECT_NEAR(g.sample_x(75), 0.51, 1e-9);
  PatchUnderTool out{};
  for (; i / rate <= t0 + 0.05 + 1e-9; ++i) p.op.tick(i / rate);  // the remote is quiet now
  out.ahead_50ms = g.height(50, 59);
  out.far_50ms = g.height(75, 70);
  for (; i / rate <= t0 + 0.15 + 1e-9; ++i) p.op.tick(i / rate);
  out.far_150ms = g.height(75, 70);
  return out;
}

TEST(Mmt, PatchesLeaveTheSoilUnderTheToolAloneWhileItCuts) {
  const double blend_s = load_scenario(kTrench).mmt->blend_s;  // 0.1
  const PatchUnderTool with = patch_under_tool(0.15);
  EXPECT_EQ(with.ahead_50ms, 0.3f);  // untouched while the tool feels it
  // Away from the tool the blend runs: half-way at 50 ms (one tick of
  // ramp either way), done at 150 ms.
  const double tick = 0.05 / (blend_s * 1000.0);
  EXPECT_NEAR(with.far_50ms, 0.3 - 0.05 * (0.05 / blend_s), tick + 1e-6);
  EXPECT_FLOAT_EQ(with.far_150ms, 0.25f);
  // Without the exclusion the same patch lowers the soil ahead of the edge.
  const PatchUnderTool without = patch_under_tool(0.0);
  EXPECT_LT(without.ahead_50ms, 0.3f - 0.01f);
}

TEST(Mmt, ARestartedOperatorIsANewSession) {
  Scenario sc = load_scenario(kTrench);
  sc.mmt->to_remote.delay_s = sc.mmt->to_operator.delay_s = 0.0;
  sc.mmt->to_remote.jitter_s = sc.mmt->to_operator.jitter_s = 0.0;
  Pair p(sc);
  const std::uint32_t link = sc.mmt->link_id;
  std::vector<std::uint8_t> d(net::kHeaderSize + net::kCommandPayloadSize + net::kCrcSize);
  auto send = [&](std::uint32_t session, std::uint32_t seq, Vec3 at, double t) {
    net::Command c;
    c.pose.position_m = at;
    net::encode_command({net::MessageType::kCommand, link, session, seq, std::uint64_t(t * 1e9)},
                        c, d.data());
    p.link.a().send(net::Channel::kUnreliable, d.data(), d.size(), t);
    p.remote.tick(t);
  };
  // An operator at sequence 500, then one restarted from sequence 0 elsewhere.
  send(1, 500, {0, 0.35, 0.75}, 0.0);
  send(1, 501, {0, 0.35, 0.75}, 0.001);
  send(2, 0, {0.3, 0.35, 0.5}, 0.002);
  send(2, 1, {0.3, 0.35, 0.5}, 0.003);
  EXPECT_EQ(p.remote.counters().accepted, 4);
  EXPECT_EQ(p.remote.counters().sessions, 2);
  EXPECT_EQ(p.remote.counters().rejected.total(), 0);
  // The new session's packets are ordered among themselves.
  send(2, 0, {0.3, 0.35, 0.5}, 0.004);
  EXPECT_EQ(p.remote.counters().rejected[net::Reject::kReordered], 1);
}

// The live stations of `terracut mmt --role` keep no records (an hour at
// 1 kHz would be about 1.1 GB) and stream each tick's row instead: the
// streamed files are the batch writer's, byte for byte, and an unwritable
// file is named.
TEST(Mmt, StreamedStationFilesEqualTheBatchFiles) {
  const Scenario sc = trench_with_remote("stream", 0.28, "clay");
  MmtRun run(sc);
  const fs::path dir = fs::temp_directory_path() / "terracut_mmt_stream_out";
  fs::create_directories(dir);
  StationCsv op = StationCsv::operator_csv(dir / "operator_streamed.csv");
  StationCsv rm = StationCsv::remote_csv(dir / "remote_streamed.csv");
  std::int64_t ticks = 0;
  while (run.ticks_run() < run.total_ticks()) {
    run.tick();
    op.add(run.operator_station().last_record());
    rm.add(run.remote_station().last_record());
    ++ticks;
  }
  op.finish();
  rm.finish();
  ASSERT_EQ(std::int64_t(run.operator_station().records().size()), ticks);
  ASSERT_GT(ticks, 1000);
  write_operator_csv(run.operator_station().records(), dir / "operator.csv");
  write_remote_csv(run.remote_station().records(), dir / "remote.csv");
  EXPECT_EQ(read_text(dir / "operator_streamed.csv"), read_text(dir / "operator.csv"));
  EXPECT_EQ(read_text(dir / "remote_streamed.csv"), read_text(dir / "remote.csv"));

  const fs::path bad = dir / "no_such_folder" / "operator.csv";
  try {
    StationCsv::operator_csv(bad);
    FAIL() << "an unwritable file was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(bad.string() + ": cannot create"), std::string::npos)
        << e.what();
  }
}

TEST(Mmt, BadSettingsNameTheField) {
  const std::string text = read_text(kTrench);
  auto fails = [&](const std::string& from, const std::string& to, const std::string& want) {
    try {
      parse_scenario(test::replace(text, from, to), kTrench);
      ADD_FAILURE() << "accepted: " << to;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(want), std::string::npos) << e.what();
    }
  };
  fails("loss: 0.0", "loss: 1.5", "mmt.link.loss: must be in [0, 1)");
  fails("blend_s: 0.1", "blend_s: -1", "mmt.operator.blend_s");
  fails("forgetting: 0.999", "forgetting: 0.999\n    estimate_resend_s: 0",
        "mmt.remote.estimate_resend_s: must be in (0, 60]");
  fails("blend_s: 0.1", "blend_s: 0.1\n    models_arm: sometimes", "mmt.operator.models_arm");
  fails("sense_period_s: 0.05", "sense_periods: 0.05", "sense_periods");
  fails("soil: clay", "soil: mud", "unknown");
  // The link is dead only after a silence longer than the one that fades the force.
  fails("timeout_s: 0.2", "timeout_s: 0.2\n  link_lost_s: 0.1",
        "mmt.link_lost_s: 0.1 s is not longer than timeout_s (0.2 s)");
  fails("timeout_s: 0.2", "timeout_s: 0.2\n  link_lost_s: 4000", "mmt.link_lost_s: must be in (0, 3600]");
  // A remote whose grid is not the operator's.
  const fs::path dir = fs::temp_directory_path() / "terracut_mmt_grid";
  fs::create_directories(dir);
  std::ofstream(dir / "remote.yaml") << test::replace(text, "resolution: 100", "resolution: 50");
  Scenario sc = load_scenario(kTrench);
  sc.mmt->remote_scenario = dir / "remote.yaml";
  try {
    MmtRun run(sc);
    ADD_FAILURE() << "accepted a remote grid of another size";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("mmt.remote.scenario"), std::string::npos) << e.what();
  }
  MmtOverrides o;
  o.loss = 1.0;
  EXPECT_THROW(MmtRun(load_scenario(kTrench), o), InputError);
}

}  // namespace
}  // namespace terracut::session
