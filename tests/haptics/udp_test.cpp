// The UDP bridge over real sockets on 127.0.0.1: rejections counted by
// reason, forces back to the sender, reconnection, bind errors, and a round
// trip between a device-player thread and the running loop. Every wait is
// bounded (a deadline of seconds) and no assertion depends on timing.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>
#include <vector>

#include "haptics_fixture.hpp"
#include "terracut/core/error.hpp"
#include "terracut/haptics/device_player.hpp"
#include "terracut/haptics/loop.hpp"
#include "terracut/haptics/udp_device.hpp"
#include "terracut/io/scenario.hpp"

namespace terracut::haptics {
namespace {

using Clock = std::chrono::steady_clock;
using Bytes = std::vector<std::uint8_t>;

Bytes pose_bytes(std::uint32_t session, std::uint32_t seq, std::uint64_t ts, Vec3 position = {}) {
  Bytes b(kPosePacketSize);
  PosePayload p;
  p.position_m = position;
  encode_pose({session, seq, ts}, p, b.data());
  return b;
}

// Reads the device until it has seen `datagrams` datagrams or 5 s passed.
bool drain_until(UdpDevice& device, std::int64_t datagrams, DeviceSample& last, int& fresh) {
  const auto deadline = Clock::now() + std::chrono::seconds(5);
  while (device.bridge_stats().datagrams_received < datagrams && Clock::now() < deadline) {
    if (device.read(0.0, last)) ++fresh;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  if (device.read(0.0, last)) ++fresh;
  return device.bridge_stats().datagrams_received >= datagrams;
}

TEST(UdpBridge, MalformedAndOutOfOrderPacketsAreCountedByReason) {
  UdpDevice device("127.0.0.1", 0);
  ASSERT_GT(device.port(), 0);
  BridgeClient client("127.0.0.1", device.port(), 77);
  std::vector<Bytes> packets;
  packets.push_back(pose_bytes(1, 10, 1000, {0.01, 0.0, 0.0}));  // accepted
  Bytes truncated = pose_bytes(1, 11, 1100);
  truncated.resize(50);
  packets.push_back(truncated);  // truncated
  Bytes corrupt = pose_bytes(1, 12, 1200);
  corrupt[40] ^= 0x10;
  packets.push_back(corrupt);                                    // bad_checksum
  packets.push_back(pose_bytes(1, 10, 1000));                    // duplicate
  packets.push_back(pose_bytes(1, 15, 1500, {0.02, 0.0, 0.0}));  // accepted (4 lost)
  packets.push_back(pose_bytes(1, 13, 1300));                    // reordered
  packets.push_back(pose_bytes(1, 16, 1400));                    // stale (older timestamp)
  Bytes magic = pose_bytes(1, 17, 1700);
  magic[0] = 'X';
  packets.push_back(magic);  // bad_magic
  Bytes longer = pose_bytes(1, 18, 1800);
  longer.push_back(0);
  packets.push_back(longer);  // bad_length
  for (const Bytes& b : packets) client.send_raw(b.data(), b.size());

  DeviceSample sample;
  int fresh = 0;
  ASSERT_TRUE(drain_until(device, std::int64_t(packets.size()), sample, fresh))
      << "loopback delivered " << device.bridge_stats().datagrams_received << " of "
      << packets.size();
  const BridgeStats& s = device.bridge_stats();
  EXPECT_EQ(s.accepted, 2);
  EXPECT_EQ(s.rejected[Reject::kTruncated], 1);
  EXPECT_EQ(s.rejected[Reject::kBadChecksum], 1);
  EXPECT_EQ(s.rejected[Reject::kDuplicate], 1);
  EXPECT_EQ(s.rejected[Reject::kReordered], 1);
  EXPECT_EQ(s.rejected[Reject::kStale], 1);
  EXPECT_EQ(s.rejected[Reject::kBadMagic], 1);
  EXPECT_EQ(s.rejected[Reject::kBadLength], 1);
  EXPECT_EQ(s.rejected.total(), 7);
  EXPECT_EQ(s.lost, 4);
  // The newest accepted pose is the sample.
  EXPECT_GE(fresh, 1);
  EXPECT_EQ(sample.position_m.x, 0.02);
}

TEST(UdpBridge, ForcesGoToTheSenderAndEchoThePose) {
  UdpDevice device("127.0.0.1", 0);
  BridgeClient client("127.0.0.1", device.port(), 5);
  PosePayload pose;
  pose.position_m = {0.0, 0.01, 0.0};
  const std::uint32_t seq = client.send_pose(pose, 1);
  DeviceSample sample;
  int fresh = 0;
  ASSERT_TRUE(drain_until(device, 1, sample, fresh));
  DeviceCommand command;
  command.force_n = {1.5, -2.0, 0.25};
  command.flags = kFlagRamping;
  command.t_s = 0.5;
  device.write(command);
  ForcePayload force;
  PacketHeader header;
  bool got = false;
  const auto deadline = Clock::now() + std::chrono::seconds(5);
  while (!got && Clock::now() < deadline) {
    got = client.poll_force(force, header);
    if (!got) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  ASSERT_TRUE(got);
  EXPECT_EQ(force.force_n.x, 1.5);
  EXPECT_EQ(force.force_n.y, -2.0);
  EXPECT_EQ(force.flags, kFlagRamping);
  EXPECT_EQ(force.pose_sequence, seq);
  EXPECT_EQ(header.timestamp_ns, 500000000u);
}

TEST(UdpBridge, ANewSessionIsAReconnection) {
  UdpDevice device("127.0.0.1", 0);
  DeviceSample sample;
  int fresh = 0;
  {
    BridgeClient first("127.0.0.1", device.port(), 1);
    first.send_pose({}, 100);
    ASSERT_TRUE(drain_until(device, 1, sample, fresh));
    EXPECT_FALSE(sample.reconnected);
  }
  // The device process restarts: a new session, sequence and clock from 0.
  BridgeClient second("127.0.0.1", device.port(), 2);
  second.send_pose({}, 0);
  const auto deadline = Clock::now() + std::chrono::seconds(5);
  bool reconnected = false;
  while (!reconnected && Clock::now() < deadline) {
    DeviceSample s;
    if (device.read(0.0, s)) reconnected = s.reconnected;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  EXPECT_TRUE(reconnected);
  EXPECT_EQ(device.bridge_stats().sessions, 2);
  EXPECT_EQ(device.bridge_stats().rejected.total(), 0);
}

TEST(UdpBridge, BindErrorsNameTheSetting) {
  EXPECT_THROW(UdpDevice("not-an-address", 0), InputError);
  UdpDevice first("127.0.0.1", 0);
  try {
    UdpDevice second("127.0.0.1", first.port());
    ADD_FAILURE() << "bound the same port twice";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("cannot bind"), std::string::npos) << e.what();
  }
}

// The running loop (its own thread) and a device-player thread exchanging
// poses and forces over loopback until the loop's ticks are done.
TEST(UdpBridge, RoundTripBetweenAPlayerThreadAndTheLoop) {
  // The bridge's round trip on the paper's soil model: the player follows
  // the path in real time and the checks below need the loop's 300 ticks
  // done before the path leaves the cutting part (1.1 s of wall time);
  // flowing soil's relaxation, much slower under ThreadSanitizer, made
  // the loop miss that window there. The soil is not what this test is about.
  test::HapticScenario in = test::trench();
  in.scenario.soil.model = SoilModel::kVanish;
  HapticSettings s = in.haptics;
  s.device = DeviceKind::kUdp;
  UdpDevice device("127.0.0.1", 0);
  LoopOptions o;
  o.ticks = 300;
  o.record_capacity = 300;
  o.realtime = false;
  const test::LoopRig rig = test::make_loop_rig(
      s, in.scenario, in.scenario.cuts[0].keyframes[0].pose.orientation, device, o);
  HapticLoop& loop = *rig;

  // The player follows the trench from its cutting part (t = 1.6 s on), so
  // the blade is in the sand and forces come back.
  DevicePlayer player("127.0.0.1", device.port(), 42, PlayerMode::kScript,
                      DevicePath(in.scenario.cuts[0], Workspace(s.workspace)), s.hand,
                      s.forces.device.inherent_damping_n_s_per_m, 1000.0);
  std::atomic<bool> done{false};
  std::thread player_thread([&] {
    const auto start = Clock::now();
    const auto deadline = start + std::chrono::seconds(10);
    while (!done.load() && Clock::now() < deadline) {
      const double t = std::chrono::duration<double>(Clock::now() - start).count();
      player.tick(1.6 + t, std::uint64_t(t * 1e9) + 1);
      std::this_thread::sleep_for(std::chrono::microseconds(500));
    }
  });
  loop.start();
  loop.join();
  done.store(true);
  player_thread.join();

  const std::vector<LoopRecord> rs = loop.records();
  ASSERT_EQ(rs.size(), 300u);
  EXPECT_GT(loop.counters().samples, 0);
  EXPECT_EQ(device.bridge_stats().rejected.total(), 0);
  EXPECT_EQ(loop.counters().bad_samples, 0);
  const PlayerStats ps = player.stats();
  EXPECT_GT(ps.forces_accepted, 0);
  EXPECT_EQ(ps.bridge.rejected.total(), 0);
  EXPECT_GT(ps.rtt_samples, 0);
  // Every pose the loop used lies on the trench's cutting path (y = 0.22,
  // x = 0) as the player sent it, mapped back to the world.
  int on_path = 0;
  for (const LoopRecord& r : rs) {
    if (r.contact_length_m > 0.0) {
      ++on_path;
      EXPECT_NEAR(r.tool.position_m.y, 0.22, 1e-9);
      EXPECT_NEAR(r.tool.position_m.x, 0.0, 1e-9);
    }
  }
  EXPECT_GT(on_path, 0);
  // The forces the player received were within the device's limit.
  EXPECT_LE(ps.max_force_n, s.safety.max_force_n);
}

}  // namespace
}  // namespace terracut::haptics
