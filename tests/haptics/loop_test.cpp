// The haptic loop in deterministic mode (fake clock, no sleeping): the trench
// scenario with the script and sim devices, bad and missing samples, the
// closed loop's energy, unsafe stiffness, the loop's statistics and the
// viewer feed.
#include "terracut/haptics/loop.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <numbers>
#include <thread>
#include <utility>

#include "haptics_fixture.hpp"
#include "terracut/core/error.hpp"
#include "terracut/core/soil_ahead.hpp"
#include "terracut/haptics/script_device.hpp"
#include "terracut/haptics/sim_hand.hpp"
#include "terracut/io/scenario.hpp"

namespace terracut::haptics {
namespace {

using test::trench;

// A loop on the trench scenario with the given device and settings.
test::LoopRig trench_loop(const HapticSettings& settings, Device& device, std::int64_t ticks,
                          SnapshotExchange* snapshot = nullptr) {
  const io::Scenario& sc = trench().scenario;
  return test::make_loop_rig(settings, sc, sc.cuts[0].keyframes[0].pose.orientation, device,
                             test::test_loop_options(ticks, snapshot));
}

const Motion& trench_cut() { return trench().scenario.cuts[0]; }
// The trench's one rate, the loop's.
double trench_rate_hz() { return trench().scenario.rate_hz; }

DevicePath trench_path(const HapticSettings& s) {
  return DevicePath(trench_cut(), Workspace(s.workspace));
}

std::int64_t ticks_of(const HapticSettings& s) {
  return std::llround((trench_cut().duration_s() + s.settle_s) * trench_rate_hz());
}

// The trench's soil flows: after each step, what the loop's earthmoving
// model is given (the depth ahead and the pile over the failure wedge,
// read from the same grid the loop reads).
// The highest soil on a grid, world metres: at the end of the trench, the
// pile's top, above which the rising blade has left all soil.
double soil_top_m(const HeightGrid& grid) {
  const std::size_t n = std::size_t(grid.spec().rows) * std::size_t(grid.spec().cols);
  return grid.spec().origin_m.y + *std::max_element(grid.heights(), grid.heights() + n);
}

// Out of the soil: no contact, above the floor, and before the plunge or
// above the pile's top as the blade rises out (rising through the pile,
// the pile's sides still rub on the blade's faces: the penetration model's
// friction, with no contact of the edge).
bool out_of_soil(const LoopRecord& r, double top_m) {
  return r.contact_length_m == 0.0 && r.tool.position_m.y > 0.0 &&
         (r.t_s < 1.0 || r.tool.position_m.y > top_m);
}

class PileProbe final : public StepListener {
 public:
  explicit PileProbe(std::size_t steps) { ahead.reserve(steps); }
  Vec3 on_step(const StepOutput& out) noexcept override {
    // The script device moves along -Z while cutting; soil_ahead only uses
    // the direction of the velocity.
    ahead.push_back(soil_ahead(sim->grid(), sim->params().representation, out.edge,
                               Vec3{0.0, 0.0, -1.0}, depth_lookahead_m(sim->grid().spec())));
    return {};
  }
  const Simulation* sim = nullptr;
  std::vector<SoilAhead> ahead;
};

TEST(HapticLoop, ScriptTrenchForcesFollowTheContact) {
  const HapticSettings& s = trench().haptics;
  const io::Scenario& sc = trench().scenario;
  ASSERT_EQ(sc.soil.model, SoilModel::kFlow);  // the trench's sand flows
  ScriptDevice device(trench_path(s));
  PileProbe probe(std::size_t(ticks_of(s)));
  auto loop = test::make_loop_rig(s, sc, sc.cuts[0].keyframes[0].pose.orientation, device,
                                  test::test_loop_options(ticks_of(s)), {&probe});
  probe.sim = loop.sim.get();
  loop->run_deterministic();
  const std::vector<LoopRecord> rs = loop->records();
  ASSERT_EQ(std::int64_t(rs.size()), ticks_of(s));
  ASSERT_EQ(probe.ahead.size(), rs.size());  // one step per tick

  const SoilMaterial soil = sc.soil.material;
  const double cell = 2.0 / 100;  // the scenario's cell size, metres
  const double gamma = soil.unit_weight_n_per_m3;
  const double tan_repose = std::tan(soil.repose_deg * std::numbers::pi / 180.0);
  const double beta = s.forces.low_speed_damping_n_s_per_m;
  const HeightGrid& grid = loop->simulation().grid();
  const std::size_t samples = std::size_t(grid.spec().rows) * std::size_t(grid.spec().cols);
  const double top = soil_top_m(grid);
  int cutting = 0, outside = 0;
  double first_pile = -1.0, last_pile = 0.0, first_h = 0.0, last_h = 0.0;
  for (std::size_t i = 0; i < rs.size(); ++i) {
    const LoopRecord& r = rs[i];
    // Never more than the Falcon's maximum.
    ASSERT_LE(length(r.force_device_n), s.safety.max_force_n * (1 + 1e-12)) << r.t_s;
    if (out_of_soil(r, top)) {
      // Out of the soil and above the floor: exactly no force.
      ++outside;
      EXPECT_EQ(length(r.force_world_n), 0.0) << r.t_s;
      EXPECT_EQ(length(r.force_device_n), 0.0) << r.t_s;
    }
    // Steady cutting along -Z at 1 m/s, 8 cm deep, after the soft start.
    if (r.t_s > 1.8 && r.t_s < 2.6) {
      ++cutting;
      const SoilAhead& a = probe.ahead[i];
      EXPECT_NEAR(r.contact_length_m, 0.4, 1e-9) << r.t_s;    // the whole blade is in the sand
      EXPECT_NEAR(r.cut_depth_m, 0.08, 0.5 * cell) << r.t_s;  // sand at 0.3, edge at 0.22
      EXPECT_NEAR(a.depth_m, 0.08, 0.5 * cell) << r.t_s;      // the pile is not depth of cut
      EXPECT_NEAR(r.velocity_m_per_s.z, -1.0, 1e-6) << r.t_s;
      // The pile ahead stands above the sand, and no higher than the 2-D
      // bulldozing balance allows: all the cut soil (w d x, x pushed since
      // the plunge began at z = 0.75) in a wedge at the repose angle,
      // h = sqrt(2 d x tan(repose)), plus a cell's rise.
      const double pushed = 0.75 - r.tool.position_m.z;
      EXPECT_GT(a.pile_m, 0.0) << r.t_s;
      EXPECT_LT(a.pile_m, std::sqrt(2.0 * 0.08 * pushed * tan_repose) + cell * tan_repose)
          << r.t_s;
      // The soil resists the motion (+Z on the tool) and lifts the vertical
      // plate (McKyes: V < 0 for alpha = 90 deg): the physical force is the
      // cutting force (with side failure) at this width and depth with the
      // pile's weight on the failure wedge as its surcharge.
      EarthmovingParams ep;
      ep.soil = soil;
      ep.rake_angle_deg = sc.blade.rake_angle_deg;
      const EarthmovingResult fee = earthmoving_force(ep, a.width_m, a.depth_m, gamma * a.pile_m);
      EXPECT_GT(fee.horizontal_n, 0.0);
      EXPECT_NEAR(r.physical_force_world_n.z, fee.horizontal_n, 1e-6 * fee.horizontal_n) << r.t_s;
      EXPECT_NEAR(r.physical_force_world_n.y, -fee.vertical_n, 1e-6 * fee.horizontal_n) << r.t_s;
      EXPECT_NEAR(r.physical_force_world_n.x, 0.0, 1e-9);
      // The device renders it under the low-speed damper's cap (beta |v|).
      const double scale = std::min(1.0, beta * std::abs(r.velocity_m_per_s.z) / fee.horizontal_n);
      EXPECT_NEAR(r.force_world_n.z, fee.horizontal_n * scale, 1e-6 * fee.horizontal_n) << r.t_s;
      EXPECT_NEAR(r.force_world_n.y, -fee.vertical_n * scale, 1e-6 * fee.horizontal_n) << r.t_s;
      if (first_pile < 0.0) {
        first_pile = a.pile_m;
        first_h = r.physical_force_world_n.z;
      }
      last_pile = a.pile_m;
      last_h = r.physical_force_world_n.z;
      // On the device: scaled by force_scale and turned into the device frame
      // (world +Z is "toward the operator", device +x; world +Y is device +z).
      if (r.flags == 0) {
        EXPECT_NEAR(r.force_device_n.x, r.force_world_n.z * s.forces.force_scale, 1e-9);
        EXPECT_NEAR(r.force_device_n.z, r.force_world_n.y * s.forces.force_scale, 1e-9);
        EXPECT_NEAR(r.force_device_n.y, r.force_world_n.x * s.forces.force_scale, 1e-9);
      }
    }
  }
  EXPECT_GT(outside, 1000);
  EXPECT_EQ(cutting, 799);
  // The pile grows as the blade pushes, and the force with it: more than
  // without any pile (the FEE of the bare cut) and more at the end than at
  // the start of the steady cut.
  EarthmovingParams bare;
  bare.soil = soil;
  bare.rake_angle_deg = sc.blade.rake_angle_deg;
  const double h0 = earthmoving_force(bare, 0.4, 0.08).horizontal_n;
  EXPECT_GT(first_h, h0);
  EXPECT_GT(last_pile, first_pile + cell * tan_repose);
  EXPECT_GT(last_h, first_h);

  // Nothing vanishes: the soil's volume is the initial volume, to float32
  // rounding of each sample (half an ulp of 0.5 m per sample, per cell area).
  double initial = 0.0, now = 0.0;
  for (std::size_t k = 0; k < samples; ++k) {
    initial += grid.initial()[k];
    now += grid.heights()[k];
  }
  const double cell_area = cell * cell;
  EXPECT_NEAR(now * cell_area, initial * cell_area, double(samples) * 3e-8 * cell_area);
  // The trench: its floor on the centre line stays at the cut level (the
  // edge went to 0.22 m and nothing digs deeper; the toes of the walls that
  // slumped at the repose angle reach the middle by at most one cell's rise
  // at that angle), the pile's top is ahead of where the cut ended
  // (z < -0.6), windrows stand beside the trench (soil spilled round the
  // blade's ends), and every slope has relaxed to the repose angle
  // (within the relaxation's stated tolerance, 2 % of the repose slope).
  const GridSpec& spec = grid.spec();
  const auto h = [&](int row, int col) { return double(grid.height(col, row)); };
  const int mid_col = spec.cols / 2;
  double top_z = 0.0, top_h = 0.0;
  for (int row = 0; row < spec.rows; ++row) {
    const double z = spec.origin_m.z + (row + 0.5) * spec.cell_z_m();
    if (std::abs(z) < 0.4) {
      EXPECT_GE(h(row, mid_col), 0.22 - 1e-6) << "z = " << z;
      EXPECT_LE(h(row, mid_col), 0.22 + cell * tan_repose) << "z = " << z;
      // Beside the trench (|x| in 0.2 .. 0.4 m), higher than the sand was.
      double berm = 0.0;
      for (int col = 0; col < spec.cols; ++col) {
        const double x = spec.origin_m.x + (col + 0.5) * spec.cell_x_m();
        if (std::abs(x) > 0.2 && std::abs(x) < 0.4) berm = std::max(berm, h(row, col));
      }
      // (Half a cell's rise: the spill round the blade's ends is built at
      // each step, docs/soil.md, and more of it lands in the trench's
      // corner than the pass-by-pass spill put there: the windrows stand
      // about 5 mm lower, 1.3 cm above the sand where the trench begins.)
      EXPECT_GT(berm, 0.3 + 0.5 * cell * tan_repose) << "z = " << z;
    }
    for (int col = 0; col < spec.cols; ++col) {
      if (h(row, col) > top_h) {
        top_h = h(row, col);
        top_z = z;
      }
      for (const auto& [dr, dc] :
           {std::pair{0, 1}, std::pair{1, 0}, std::pair{1, 1}, std::pair{1, -1}}) {
        const int r2 = row + dr, c2 = col + dc;
        if (r2 >= spec.rows || c2 < 0 || c2 >= spec.cols) continue;
        const double dist = std::hypot(dr * spec.cell_z_m(), dc * spec.cell_x_m());
        EXPECT_LE(std::abs(h(r2, c2) - h(row, col)), 1.02 * tan_repose * dist)
            << row << "," << col << " to " << r2 << "," << c2;
      }
    }
  }
  EXPECT_LT(top_z, -0.6);
  EXPECT_EQ(loop->counters().bad_samples, 0);
  EXPECT_EQ(loop->safety().counters().nonfinite, 0);
}

// The trench scenario's blade over the middle of the sand, driven by keyframes.
Motion trench_motion(std::vector<Keyframe> keyframes) {
  Motion m;
  m.name = "test";
  m.keyframes = std::move(keyframes);
  return m;
}

TEST(HapticLoop, PlungingIntoSandMeetsItsBearingCapacity) {
  // Straight down at 1 m/s from 5 cm above the 0.3 m sand to 8 cm into it.
  const HapticSettings& s = trench().haptics;
  const Motion plunge = trench_motion({{0.0, {{0.0, 0.35, 0.0}, {}}},
                                       {0.2, {{0.0, 0.35, 0.0}, {}}},
                                       {0.33, {{0.0, 0.22, 0.0}, {}}},
                                       {0.6, {{0.0, 0.22, 0.0}, {}}}});
  ScriptDevice device(DevicePath(plunge, Workspace(s.workspace)));
  auto loop = trench_loop(s, device, 600);
  loop->run_deterministic();
  const ForceModelParams& fp = loop->force_model().params();
  const double beta = fp.low_speed_damping_n_s_per_m * loop->force_model().rendering().cutting_gain;
  int checked = 0;
  for (const LoopRecord& r : loop->records()) {
    const double depth = double(0.3f) - r.tool.position_m.y;  // the grid's float32 sand
    if (depth <= 0.0) {
      EXPECT_EQ(r.penetration_force_n, 0.0) << r.t_s;  // above the sand
      continue;
    }
    if (r.t_s > 0.4) {
      // At rest in the sand (the velocity filter settled): no resistance to
      // a motion that is not there.
      EXPECT_NEAR(r.penetration_force_n, 0.0, 1e-9) << r.t_s;
      continue;
    }
    if (r.t_s > 0.33) continue;  // stopping: the filtered velocity decays
    // Going down: up, the tip's bearing and the faces' friction over the
    // whole 0.4 m edge at the depth below the sand beside it, regularised.
    ASSERT_LT(r.velocity_m_per_s.y, 0.0) << r.t_s;
    const PenetrationResult p = penetration_resistance(
        trench().scenario.soil.material, trench().scenario.blade.edge_thickness_m, 0.4, depth);
    const double expected = std::min(p.down_n(), beta * -r.velocity_m_per_s.y);
    EXPECT_NEAR(r.penetration_force_n, expected, 1e-6 * expected + 1e-9) << r.t_s;
    EXPECT_NEAR(r.force_world_n.y, r.penetration_force_n, 1e-9) << r.t_s;  // nothing else
    if (depth > 0.02) {
      EXPECT_GT(r.penetration_force_n, 100.0) << r.t_s;
    }
    ++checked;
  }
  EXPECT_GE(checked, 70);  // 8 cm at 1 m/s
}

TEST(HapticLoop, TurningTheBuriedBladeMeetsATorque) {
  // Into the sand, then a quarter turn about +Y in 1 s, then the other way.
  const HapticSettings& s = trench().haptics;
  const Motion turn = trench_motion({{0.0, {{0.0, 0.35, 0.0}, {}}},
                                     {0.2, {{0.0, 0.22, 0.0}, {}}},
                                     {0.4, {{0.0, 0.22, 0.0}, {}}},
                                     {1.4, {{0.0, 0.22, 0.0}, quat_from_euler_deg({0, 90, 0})}},
                                     {2.4, {{0.0, 0.22, 0.0}, {}}}});
  ScriptDevice device(DevicePath(turn, Workspace(s.workspace)));
  auto loop = trench_loop(s, device, 2400);
  loop->run_deterministic();
  int positive = 0, negative = 0;
  for (const LoopRecord& r : loop->records()) {
    if (r.t_s > 0.5 && r.t_s < 1.35) {
      EXPECT_NEAR(r.yaw_rate_rad_per_s, std::numbers::pi / 2, 1e-3) << r.t_s;
      EXPECT_LT(r.twist_torque_n_m, 0.0) << r.t_s;  // against the turn
      ++positive;
    }
    if (r.t_s > 1.5 && r.t_s < 2.35) {
      EXPECT_NEAR(r.yaw_rate_rad_per_s, -std::numbers::pi / 2, 1e-3) << r.t_s;
      EXPECT_GT(r.twist_torque_n_m, 0.0) << r.t_s;
      ++negative;
    }
    // A centred blade: the two halves' forces cancel to a part of the edge
    // (f ds against T = f L^2 / 4: |F| <= T 4 ds / L^2 = T / 2 per metre, ds = 2 cm).
    if (r.t_s > 0.5 && r.t_s < 2.35) {
      EXPECT_LE(std::hypot(r.force_world_n.x, r.force_world_n.z),
                0.5 * std::abs(r.twist_torque_n_m) + 1e-9)
          << r.t_s;
    }
  }
  EXPECT_GT(positive, 800);
  EXPECT_GT(negative, 800);
}

TEST(HapticLoop, EndsWhenTheDeviceFallsSilentAndCountsOnlyTheSilencesBetween) {
  // The device is silent for its first 200 ticks (a bridge not yet sending),
  // sends, falls silent for 120 ticks in the middle, sends again, and stops
  // for good at tick 1500.
  const HapticSettings& s = trench().haptics;
  ScriptDevice script(trench_path(s));
  test::FaultyDevice device(script, nullptr, [](std::int64_t tick) {
    return tick < 200 || (tick >= 800 && tick < 920) || tick >= 1500;
  });
  const io::Scenario& sc = trench().scenario;
  LoopOptions o = test::test_loop_options(5000);
  o.end_after_silence_s = 0.3;
  auto loop = test::make_loop_rig(s, sc, sc.cuts[0].keyframes[0].pose.orientation, device, o);
  loop->run_deterministic();
  EXPECT_TRUE(loop->ended_with_device());
  // The last sample at tick 1499, then 0.3 s of silence: about 1800 ticks.
  EXPECT_NEAR(double(loop->counters().ticks), 1500.0 + 300.0, 2.0);
  // Three trips (the wait at start, the gap, the end); only the gap counts.
  EXPECT_EQ(loop->safety().counters().watchdog_trips, 3);
  EXPECT_EQ(loop->watchdog_trips_while_active(), 1);
  // Without the option the loop runs its ticks.
  ScriptDevice script2(trench_path(s));
  test::FaultyDevice quiet(script2, nullptr, [](std::int64_t tick) { return tick >= 1500; });
  auto full = trench_loop(s, quiet, 2500);
  full->run_deterministic();
  EXPECT_FALSE(full->ended_with_device());
  EXPECT_EQ(full->counters().ticks, 2500);
  EXPECT_EQ(full->watchdog_trips_while_active(), 0);
}

TEST(HapticLoop, DeterministicRunsAreIdentical) {
  for (DeviceKind kind : {DeviceKind::kScript, DeviceKind::kSim}) {
    std::vector<LoopRecord> runs[2];
    for (auto& out : runs) {
      const HapticSettings& s = trench().haptics;
      std::unique_ptr<Device> device;
      if (kind == DeviceKind::kScript)
        device = std::make_unique<ScriptDevice>(trench_path(s));
      else
        device = std::make_unique<SimHandDevice>(
            SimHand(s.hand, s.forces.device.inherent_damping_n_s_per_m, trench_path(s), trench_rate_hz()));
      auto loop = trench_loop(s, *device, 3000);
      loop->run_deterministic();
      out = loop->records();
      for (LoopRecord& r : out) r.compute_s = 0.0;  // the one measured field
    }
    ASSERT_EQ(runs[0].size(), runs[1].size());
    EXPECT_EQ(std::memcmp(runs[0].data(), runs[1].data(), runs[0].size() * sizeof(LoopRecord)), 0)
        << to_string(kind);
  }
}

TEST(HapticLoop, BadSampleIsCountedAndAnsweredWithZeroForce) {
  const HapticSettings& s = trench().haptics;
  ScriptDevice script(trench_path(s));
  // Five NaN positions in the middle of the cut (t = 2.0 s), where the force is up.
  test::FaultyDevice device(
      script, [](std::int64_t tick) { return tick >= 2000 && tick < 2005; }, nullptr);
  const std::int64_t ticks = ticks_of(s);
  auto loop = trench_loop(s, device, ticks);
  loop->run_deterministic();
  const std::vector<LoopRecord> rs = loop->records();
  EXPECT_EQ(loop->counters().ticks, ticks);  // the loop went on
  EXPECT_EQ(loop->counters().bad_samples, 5);
  EXPECT_GT(length(rs[1999].force_device_n), 0.5);
  for (int i = 2000; i < 2005; ++i) {
    EXPECT_TRUE(rs[std::size_t(i)].flags & kFlagBadSample) << i;
    EXPECT_EQ(length(rs[std::size_t(i)].force_device_n), 0.0) << i;
    EXPECT_EQ(rs[std::size_t(i)].contact_length_m, 0.0) << i;
  }
  // The force comes back within the rate limit's build-up time and the
  // velocity estimate's settling: it restarts from zero after the bad
  // samples, and where the low-speed damper caps the soil's force the device
  // renders beta |v|, within 5 % of it after ln 20 of the filter's time constants.
  const double rebuild_s = rs[1999].force_device_n.x / s.safety.max_force_rate_n_per_s;
  const double settle_s = std::log(20.0) / (2.0 * std::numbers::pi * s.velocity_cutoff_hz);
  const std::size_t back = 2005 + std::size_t(std::ceil((rebuild_s + settle_s) * trench_rate_hz())) + 2;
  EXPECT_NEAR(length(rs[back].force_device_n), length(rs[1999].force_device_n),
              0.05 * length(rs[1999].force_device_n));
  EXPECT_EQ(device.commands.size(), std::size_t(ticks));
}

TEST(HapticLoop, SilentDeviceTripsTheWatchdogAndSoftStartsOnReturn) {
  const HapticSettings& s = trench().haptics;
  ScriptDevice script(trench_path(s));
  // Silent for 300 ms from t = 2.0 s (mid-cut).
  test::FaultyDevice device(script, nullptr,
                            [](std::int64_t tick) { return tick >= 2000 && tick < 2300; });
  auto loop = trench_loop(s, device, ticks_of(s));
  loop->run_deterministic();
  const std::vector<LoopRecord> rs = loop->records();
  const double f0 = length(rs[1999].force_device_n);
  ASSERT_GT(f0, 0.5);
  const int timeout = int(std::lround(s.safety.watchdog_timeout_s * trench_rate_hz()));
  const int ramp = int(std::lround(s.safety.watchdog_ramp_s * trench_rate_hz()));
  // Before the timeout the last force is held; after it, ramped to zero.
  EXPECT_FALSE(rs[std::size_t(1999 + timeout)].flags & kFlagWatchdog);
  EXPECT_TRUE(rs[std::size_t(2001 + timeout)].flags & kFlagWatchdog);
  EXPECT_EQ(length(rs[std::size_t(2002 + timeout + ramp)].force_device_n), 0.0);
  for (int i = 2002 + timeout + ramp; i < 2300; ++i)
    EXPECT_EQ(length(rs[std::size_t(i)].force_device_n), 0.0) << i;
  EXPECT_EQ(loop->safety().counters().watchdog_trips, 1);
  // The device is back: a new soft start.
  EXPECT_TRUE(rs[2301].flags & kFlagRamping);
  EXPECT_EQ(loop->counters().silent_ticks, 300);
}

// A bad sample while the watchdog fades the force of a silence out still
// gets zero force (the fade used to go on through it; found by the soak
// test), and the force then comes back no faster than the rate limit.
TEST(HapticLoop, BadSampleDuringTheWatchdogFadeGetsZeroForce) {
  const HapticSettings& s = trench().haptics;
  ScriptDevice script(trench_path(s));
  const int timeout = int(std::lround(s.safety.watchdog_timeout_s * trench_rate_hz()));
  const std::int64_t bad = 2000 + timeout + 10;  // silent from 2000, tripped by now, fading
  test::FaultyDevice device(
      script, [&](std::int64_t tick) { return tick == bad; },
      [&](std::int64_t tick) { return tick >= 2000 && tick < 2300 && tick != bad; });
  auto loop = trench_loop(s, device, ticks_of(s));
  loop->run_deterministic();
  const std::vector<LoopRecord> rs = loop->records();
  ASSERT_GT(length(rs[std::size_t(bad - 1)].force_device_n), 0.1);  // fading, not yet zero
  ASSERT_TRUE(rs[std::size_t(bad - 1)].flags & kFlagWatchdog);
  EXPECT_TRUE(rs[std::size_t(bad)].flags & kFlagBadSample);
  EXPECT_EQ(length(rs[std::size_t(bad)].force_device_n), 0.0);
  const double step_n = s.safety.max_force_rate_n_per_s / trench_rate_hz();
  EXPECT_LE(length(rs[std::size_t(bad + 1)].force_device_n), step_n * (1 + 1e-9));
  EXPECT_EQ(loop->counters().bad_samples, 1);
}

// The closed loop with the simulated hand along the trench: it digs, the
// force stays within the device, and the hand's motion about its target
// stays within what the rendered force can explain (no instability).
TEST(HapticLoop, SimHandTrenchStaysBoundedAndDigs) {
  const HapticSettings& s = trench().haptics;
  SimHandDevice device(
      SimHand(s.hand, s.forces.device.inherent_damping_n_s_per_m, trench_path(s), trench_rate_hz()));
  auto loop = trench_loop(s, device, ticks_of(s));
  loop->run_deterministic();
  const std::vector<LoopRecord> rs = loop->records();

  double max_force = 0.0;
  int cutting_with_force = 0, cutting = 0;
  const double top = soil_top_m(loop->simulation().grid());
  for (const LoopRecord& r : rs) {
    max_force = std::max(max_force, length(r.force_device_n));
    if (r.contact_length_m > 0.2 && r.t_s > 1.8 && r.t_s < 2.6) {
      ++cutting;
      if (r.force_device_n.x > 0.1) ++cutting_with_force;  // resists the push along -x
    }
    if (out_of_soil(r, top)) {
      EXPECT_EQ(length(r.force_device_n), 0.0) << r.t_s;
    }
  }
  EXPECT_LE(max_force, s.safety.max_force_n);
  EXPECT_GT(cutting, 700);
  EXPECT_EQ(cutting_with_force, cutting);
  EXPECT_GT(loop->simulation().removed_volume_m3(), 0.02);

  // Bound on |x - x_t|: e obeys m e'' + (c + b) e' + k e = F - b v_t - m a_t.
  // The bounded input |F - b v_t| <= G moves e by at most G ||h||_1 with
  // ||h||_1 = coth(zeta pi / (2 sqrt(1 - zeta^2))) / k (underdamped impulse
  // response); each keyframe's velocity jump dv adds at most |dv| / omega_d.
  const SimHandParams& h = s.hand;
  const double b = s.forces.device.inherent_damping_n_s_per_m;
  const double wn = std::sqrt(h.stiffness_n_per_m / h.mass_kg);
  const double zeta =
      (h.damping_n_s_per_m + b) / (2.0 * std::sqrt(h.stiffness_n_per_m * h.mass_kg));
  ASSERT_LT(zeta, 1.0);
  const double wd = wn * std::sqrt(1.0 - zeta * zeta);
  const double l1 = 1.0 /
                    std::tanh(zeta * std::numbers::pi / (2.0 * std::sqrt(1.0 - zeta * zeta))) /
                    h.stiffness_n_per_m;
  const DevicePath path = trench_path(s);
  double jumps = 0.0;
  const auto& k = trench_cut().keyframes;
  for (std::size_t i = 0; i < k.size(); ++i) {
    const Vec3 before = i > 0 ? path.velocity_m_per_s(k[i].t_s - 1e-9) : Vec3{};
    const Vec3 after = path.velocity_m_per_s(k[i].t_s);
    jumps += length(after - before);
  }
  const double g = max_force + b * path.max_speed_m_per_s();
  const double bound = g * l1 + jumps / wd;
  const SimHand& hand = device.hand();
  EXPECT_LT(hand.max_tracking_error_m(), bound);
  // The cutting force did slow the hand: it lags by at least the force / k.
  EXPECT_GT(hand.max_tracking_error_m(), 0.5 / h.stiffness_n_per_m);
  // After the path ends (out of the sand, no force) the hand settles onto
  // its target: the error decays at least as exp(-sigma t).
  const double sigma = zeta * wn;
  EXPECT_LT(length(hand.position_m() - hand.target_m()), bound * std::exp(-sigma * s.settle_s));
}

// A hand held still, pulled 2 mm (device) below the rigid floor of an empty
// terrain: total energy (hand kinetic + arm spring + floor spring) never
// rises above its starting value, with the safety limiter in the chain.
double holding_energy(const SimHand& hand, const HapticLoop& loop) {
  const double k_floor = loop.force_model().rendering().surface_stiffness_n_per_m;
  const double ws = loop.settings().workspace.scale;
  const double ground = loop.simulation().grid().spec().origin_m.y;
  const double y = loop.workspace().to_world(hand.position_m()).y;
  const double pen_device = std::max(0.0, ground - y) / ws;
  return hand.tracking_energy_j() + 0.5 * k_floor * pen_device * pen_device;
}

struct HoldResult {
  double start_j = 0.0;
  double max_j = 0.0;
  double end_j = 0.0;
  double max_force_n = 0.0;
};

HoldResult hold_against_floor(HapticSettings s, double floor_stiffness_world) {
  s.forces.surface.stiffness_n_per_m = floor_stiffness_world;
  s.safety.rise_time_s = 0.0;  // a fixed wall (a rising stiffness is not)
  s.hand.start_offset_m = {0.0, 0.0, 0.012};
  // An empty terrain: only the floor.
  io::Scenario sc = trench().scenario;
  sc.generator->plane.height_m = 0.0;
  Motion hold;
  hold.name = "hold";
  hold.keyframes = {{0.0, {{0.0, -0.03, 0.0}, Quat{}}}};  // 2 mm below the floor, on the device
  const DevicePath path(hold, Workspace(s.workspace));
  SimHandDevice device(
      SimHand(s.hand, s.forces.device.inherent_damping_n_s_per_m, path, trench_rate_hz()));
  LoopOptions o;
  o.ticks = 2000;
  o.realtime = false;
  const test::LoopRig rig = test::make_loop_rig(s, sc, Quat{}, device, o);
  HapticLoop& loop = *rig;
  HoldResult r;
  for (std::int64_t i = 0; i < o.ticks; ++i) {
    loop.step1(double(i) / trench_rate_hz());
    const double e = holding_energy(device.hand(), loop);
    if (i == 0) r.start_j = e;
    r.max_j = std::max(r.max_j, e);
    r.end_j = e;
    r.max_force_n = std::max(r.max_force_n, length(loop.step2(0.001, 0.0, false).force_device_n));
  }
  return r;
}

TEST(HapticLoop, HandHeldAgainstTheFloorNeverGainsEnergy) {
  HapticSettings s = trench().haptics;
  const HoldResult r = hold_against_floor(s, s.forces.surface.stiffness_n_per_m);
  EXPECT_GT(r.max_force_n, 0.5);  // the floor pushed back
  EXPECT_LE(r.max_j, r.start_j);
  EXPECT_LT(r.end_j, 0.5 * r.start_j);
}

TEST(HapticLoop, UnsafeStiffnessIsRefusedOrLimited) {
  HapticSettings s = trench().haptics;
  // 2e6 N/m in the world is 75 000 N/m on the device: far above the
  // Falcon's 3000 N/m and the passivity bound 2 (b - |B|) / T = 2400 N/m.
  s.forces.policy = LimitPolicy::kRefuse;
  s.forces.surface.stiffness_n_per_m = 2e6;
  ScriptDevice device(trench_path(s));
  try {
    trench_loop(s, device, 10);
    ADD_FAILURE() << "an unsafe stiffness was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("haptics.forces.surface.stiffness_n_per_m"),
              std::string::npos)
        << e.what();
  }
  // With clamp the stiffness is lowered to the bound, and the closed loop
  // still never gains energy.
  s.forces.policy = LimitPolicy::kClamp;
  auto loop = trench_loop(s, device, 10);
  const RenderingCheck& rc = loop->force_model().rendering();
  EXPECT_TRUE(rc.surface_stiffness_limited);
  EXPECT_LE(rc.surface_stiffness_n_per_m, rc.passive_stiffness_n_per_m);
  const HoldResult r = hold_against_floor(s, 2e6);
  EXPECT_LE(r.max_j, r.start_j);
}

TEST(HapticLoop, StatisticsFromTheTickTimes) {
  const HapticSettings& s = trench().haptics;
  ScriptDevice device(trench_path(s));
  auto loop = trench_loop(s, device, 1000);
  // A fake clock: 989 periods exactly nominal, 10 late by 500 us; compute
  // times 100 us, except one of 700 us; three missed deadlines.
  const double T = 1.0 / trench_rate_hz();
  for (int i = 0; i < 1000; ++i) {
    loop->step1(i * T);
    const double period = i == 0 ? 0.0 : (i % 100 == 50 ? T + 500e-6 : T);
    loop->step2(period, i == 400 ? 700e-6 : 100e-6, i == 10 || i == 20 || i == 30);
  }
  const TimePercentiles j = loop->jitter();
  EXPECT_NEAR(j.p50_us, 0.0, 1e-6);
  // 999 periods, 10 of them late: the 99th percentile (nearest rank 990) is late.
  EXPECT_NEAR(j.p99_us, 500.0, 1e-6);
  EXPECT_NEAR(j.max_us, 500.0, 1e-6);
  EXPECT_NEAR(j.mean_us, 10 * 500.0 / 999, 1e-6);
  const TimePercentiles p = loop->period();
  EXPECT_NEAR(p.p50_us, 1000.0, 1e-6);
  const TimePercentiles c = loop->compute();
  EXPECT_NEAR(c.p50_us, 100.0, 1e-6);
  EXPECT_NEAR(c.p99_us, 100.0, 1e-6);
  EXPECT_NEAR(c.max_us, 700.0, 1e-6);
  EXPECT_EQ(loop->counters().missed_deadlines, 3);
  EXPECT_TRUE(loop->records()[20].flags & kFlagMissedDeadline);
}

// A fake clock for the threaded loop: time moves when the pacer sleeps or
// spins, and when the device below "computes".
class TestClock final : public PacerClock {
 public:
  double now_s() override { return now_s_; }
  void sleep_until(double t_s) override { now_s_ = std::max(now_s_, t_s); }
  void relax() override { now_s_ += 1e-6; }
  void advance(double dt_s) { now_s_ += dt_s; }

 private:
  double now_s_ = 100.0;
};

// A device that takes 200 us of (fake) time per read, and 2.5 ms on tick 50.
class SlowDevice final : public Device {
 public:
  SlowDevice(Device& inner, TestClock& clock) : inner_(inner), clock_(clock) {}
  std::string_view kind() const override { return inner_.kind(); }
  void start(double t_s) override { inner_.start(t_s); }
  bool read(double t_s, DeviceSample& out) noexcept override {
    clock_.advance(reads_++ == 50 ? 2.5e-3 : 200e-6);
    return inner_.read(t_s, out);
  }
  void write(const DeviceCommand& command) noexcept override { inner_.write(command); }

 private:
  Device& inner_;
  TestClock& clock_;
  std::int64_t reads_ = 0;
};

// The threaded loop paced by the Pacer on a fake clock: the overrun of tick
// 50 makes tick 51 start late, counted once, and the compute times are the
// fake ones.
TEST(HapticLoop, PacedLoopStatisticsWithAFakeClock) {
  const HapticSettings& s = trench().haptics;
  ScriptDevice script(trench_path(s));
  auto clock = std::make_shared<TestClock>();
  SlowDevice device(script, *clock);
  const io::Scenario& sc = trench().scenario;
  LoopOptions o;
  o.ticks = 300;
  o.record_capacity = 300;
  o.realtime = false;
  o.clock = clock;
  const test::LoopRig rig = test::make_loop_rig(s, sc, Quat{}, device, o);
  HapticLoop& loop = *rig;
  loop.start();
  loop.join();
  EXPECT_FALSE(loop.running());
  EXPECT_EQ(loop.counters().ticks, 300);
  EXPECT_EQ(loop.counters().missed_deadlines, 1);
  const std::vector<LoopRecord> rs = loop.records();
  EXPECT_TRUE(rs[51].flags & kFlagMissedDeadline);
  EXPECT_FALSE(rs[50].flags & kFlagMissedDeadline);
  // Tick 51 started when tick 50's work ended, 2.5 ms after tick 50 began.
  EXPECT_NEAR(rs[51].t_s - rs[50].t_s, 2.5e-3, 1e-9);
  EXPECT_NEAR(rs[51].period_s, 2.5e-3, 1e-9);
  EXPECT_NEAR(rs[40].period_s, 1e-3, 1e-9);
  EXPECT_NEAR(rs[40].compute_s, 200e-6, 1e-9);
  const LoopStats& ps = loop.pacer_stats();
  EXPECT_EQ(ps.ticks, 299);  // ticks ended by a wait: all but the last
  EXPECT_EQ(ps.missed_deadlines, 1);
  // Histogram percentiles: never below the value, at most 1/64 above it.
  EXPECT_GE(ps.compute.p50_s, 200e-6 - 1e-9);
  EXPECT_LE(ps.compute.p50_s, 200e-6 * (1 + 1.0 / 64) + 1e-9);
  EXPECT_NEAR(ps.compute.max_s, 2.5e-3, 1e-8);
  EXPECT_NEAR(ps.period_jitter.max_s, 1.5e-3, 1e-8);
  EXPECT_LT(ps.period_jitter.p50_s, 2e-6);
}

// A device its user pauses for a while (the viewer's virtual one): paused
// from read 40 for 300 looks, then playing again.
class PausingDevice final : public Device {
 public:
  explicit PausingDevice(Device& inner) : inner_(inner) {}
  std::string_view kind() const override { return inner_.kind(); }
  void start(double t_s) override { inner_.start(t_s); }
  bool read(double t_s, DeviceSample& out) noexcept override {
    ++reads;
    return inner_.read(t_s, out);
  }
  void write(const DeviceCommand& command) noexcept override { inner_.write(command); }
  bool paused() noexcept override {
    if (reads < 40 || looks_paused >= 300) return false;
    ++looks_paused;
    reads_while_paused = reads;
    return true;
  }
  std::int64_t reads = 0, looks_paused = 0, reads_while_paused = -1;

 private:
  Device& inner_;
};

// The threaded loop holds while its device is paused: no tick runs (the
// device is not read), the hold sleeps in steps of kPausePoll_s, and the
// loop's clock leaves the pause out: the tick after it is one period after
// the tick before, with no late tick, jitter or missed deadline counted.
TEST(HapticLoop, APausedDeviceHoldsTheLoopAndItsClock) {
  const HapticSettings& s = trench().haptics;
  ScriptDevice script(trench_path(s));
  PausingDevice device(script);
  auto clock = std::make_shared<TestClock>();
  const io::Scenario& sc = trench().scenario;
  LoopOptions o;
  o.ticks = 100;
  o.record_capacity = 100;
  o.realtime = false;
  o.clock = clock;
  const test::LoopRig rig = test::make_loop_rig(s, sc, Quat{}, device, o);
  HapticLoop& loop = *rig;
  const double start = clock->now_s();
  loop.start();
  loop.join();
  EXPECT_EQ(device.looks_paused, 300);
  EXPECT_EQ(device.reads_while_paused, 40);  // nothing was read while paused
  EXPECT_EQ(loop.counters().ticks, 100);
  // The fake clock moved through the hold: 300 looks, one poll apart.
  EXPECT_GE(clock->now_s() - start, 299 * HapticLoop::kPausePoll_s);
  const std::vector<LoopRecord> rs = loop.records();
  ASSERT_EQ(rs.size(), 100u);
  // Every period is the nominal one, to the fake clock's spin step (1 us),
  // the one after the 1.5 s pause included.
  const double T = 1.0 / trench_rate_hz();
  for (std::size_t i = 1; i < rs.size(); ++i) {
    EXPECT_NEAR(rs[i].t_s - rs[i - 1].t_s, T, 1.5e-6) << "tick " << i;
    EXPECT_NEAR(rs[i].period_s, T, 1.5e-6) << "tick " << i;
  }
  EXPECT_EQ(loop.counters().missed_deadlines, 0);
  EXPECT_EQ(loop.pacer_stats().missed_deadlines, 0);
  EXPECT_LT(loop.pacer_stats().period_jitter.max_s, 1e-4);
}

// A stop asked for while the device is paused ends the held loop.
TEST(HapticLoop, AStopEndsAPausedLoop) {
  class AlwaysPaused final : public Device {
   public:
    explicit AlwaysPaused(Device& inner) : inner_(inner) {}
    std::string_view kind() const override { return inner_.kind(); }
    bool read(double t_s, DeviceSample& out) noexcept override { return inner_.read(t_s, out); }
    void write(const DeviceCommand& command) noexcept override { inner_.write(command); }
    bool paused() noexcept override { return true; }

   private:
    Device& inner_;
  };
  const HapticSettings& s = trench().haptics;
  ScriptDevice script(trench_path(s));
  AlwaysPaused device(script);
  const io::Scenario& sc = trench().scenario;
  LoopOptions o;
  o.ticks = 1000000;
  o.realtime = false;
  const test::LoopRig rig = test::make_loop_rig(s, sc, Quat{}, device, o);
  HapticLoop& loop = *rig;
  loop.start();
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  EXPECT_TRUE(loop.running());
  loop.request_stop();
  loop.join();
  EXPECT_FALSE(loop.running());
  // The counters belong to the loop's thread until it is joined.
  EXPECT_EQ(loop.counters().ticks, 1);  // the first tick, then held
}

TEST(HapticLoop, RecordsKeepTheNewestWhenFull) {
  const HapticSettings& s = trench().haptics;
  ScriptDevice device(trench_path(s));
  const io::Scenario& sc = trench().scenario;
  LoopOptions o;
  o.ticks = 250;
  o.record_capacity = 100;
  o.realtime = false;
  const test::LoopRig rig = test::make_loop_rig(s, sc, Quat{}, device, o);
  HapticLoop& loop = *rig;
  loop.run_deterministic();
  const std::vector<LoopRecord> rs = loop.records();
  ASSERT_EQ(rs.size(), 100u);
  EXPECT_EQ(rs.front().tick, 150);
  EXPECT_EQ(rs.back().tick, 249);
  EXPECT_EQ(loop.counters().records_dropped, 150);
}

TEST(HapticLoop, FeedsTheViewerSnapshot) {
  const HapticSettings& s = trench().haptics;
  ScriptDevice device(trench_path(s));
  const io::Scenario& sc = trench().scenario;
  const Simulation probe(io::sim_params(sc), io::build_initial_heights(sc));
  SnapshotExchange exchange(probe.grid());
  auto loop = trench_loop(s, device, 2200, &exchange);
  loop->run_deterministic();
  const ViewFrame* f = exchange.acquire();
  ASSERT_NE(f, nullptr);
  EXPECT_EQ(f->sequence, 2200u);
  EXPECT_EQ(f->step, loop->simulation().last().step);
  EXPECT_EQ(f->pose.position_m.z, loop->last().tool.position_m.z);
  EXPECT_EQ(f->force_device_n.x, loop->last().force_device_n.x);
  const HeightGrid& g = loop->simulation().grid();
  EXPECT_TRUE(std::equal(f->heights.begin(), f->heights.end(), g.heights()));
}

}  // namespace
}  // namespace terracut::haptics
