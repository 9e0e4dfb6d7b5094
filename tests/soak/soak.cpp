// terracut-soak: the haptic loop at its rate on its own thread, for a long
// run, fed through the UDP bridge by a hostile device process (a thread
// here) while the blade cuts the scenario's terrain. docs/reliability.md.
//
//   terracut-soak [--mode loop|mmt|mmt-enet] [--duration S] [--scenario FILE] [--seed N]
//
// --mode mmt and mmt-enet run the teleoperation stations under a hostile
// peer instead (mmt_soak.cpp); what follows is the loop's soak (the default).
//
// The sender, every few milliseconds, picks one behaviour: ordinary poses
// (random walks through the workspace, the blade in the soil), jumps of
// metres, poses with NaN or +-inf coordinates, bursts of up to 64 packets,
// silences of 0.1-0.4 s, duplicated and reordered packets, stale
// timestamps, a new session (a device process restarting) and malformed
// datagrams of every kind (truncated, overlong, bad magic, version, CRC,
// type). It keeps its own account of what each datagram is; the device
// between the socket and the loop is wrapped by a checker that sees every
// sample the loop reads and every command it writes.
//
// Asserted over the whole run (exit status 1 and a line per broken promise):
//   - |force sent| <= safety.max_force_n on every tick;
//   - the force never moves away from the segment [0, previous force]
//     faster than safety.max_force_rate_n_per_s (it may always shrink);
//   - the force is exactly zero on every tick whose sample is not finite,
//     and, after the last sample of a silence, the watchdog trips at the
//     first tick past watchdog_timeout_s and the force is zero
//     watchdog_ramp_s (+1 tick) after the trip, until the device is heard again;
//   - the loop runs every tick (none lost, the thread never stops early);
//   - resident memory at the end is within 4 MiB of that after the first second;
//   - every datagram is counted under its reason: the device's counts of
//     accepted packets and of each rejection reason equal the sender's
//     account (when the socket lost none), and the loop's count of bad
//     samples equals the non-finite samples the checker saw.
// The figures (ticks, worst force and force rate, watchdog latencies,
// memory) are printed.
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "terracut/core/error.hpp"
#include "terracut/haptics/bridge_protocol.hpp"
#include "terracut/haptics/loop.hpp"
#include "terracut/haptics/settings_yaml.hpp"
#include "terracut/haptics/udp_device.hpp"
#include "terracut/io/scenario.hpp"
#include "checking_device.hpp"
#include "mmt_soak.hpp"

namespace {

using namespace terracut;
using namespace terracut::haptics;
using soak::CheckingDevice;
using soak::rss_bytes;

double now_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// ---------------------------------------------------------------------------
// The hostile sender: a thread that sends datagrams to the loop's device and
// keeps the account of what each one is.

class HostileSender {
 public:
  HostileSender(int port, std::uint32_t seed, double duration_s)
      : client_("127.0.0.1", port, 1), rng_(seed), duration_s_(duration_s) {}

  void run() {
    const double start = now_s();
    bool silent_once = false;  // at least one silence, at the middle of the run
    while (now_s() - start < duration_s_) {
      if (!silent_once && now_s() - start > 0.5 * duration_s_) {
        silent_once = true;
        silence();
      }
      behave();
      std::this_thread::sleep_for(std::chrono::microseconds(500 + rng_() % 1500));
    }
  }

  std::int64_t sent = 0;
  std::int64_t accepted = 0;
  RejectCounts rejected{};
  std::int64_t silences = 0;

 private:
  std::uint64_t ns() const { return std::uint64_t(now_s() * 1e9); }

  PosePayload pose_near(double spread) {
    std::normal_distribution<double> step(0.0, spread);
    position_ = {std::clamp(position_.x + step(rng_), -0.05, 0.05),
                 std::clamp(position_.y + step(rng_), -0.05, 0.05),
                 std::clamp(position_.z + step(rng_), -0.05, 0.01)};
    PosePayload p;
    p.position_m = position_;
    return p;
  }

  // Sends the datagram and accounts for it the way the device must.
  void send(const std::uint8_t* data, std::size_t size) {
    client_.send_raw(data, size);
    ++sent;
    PacketHeader h;
    PosePayload p;
    const Reject format = decode_pose(data, size, h, p);
    if (format != Reject::kNone) {
      rejected.add(format);
      return;
    }
    const Reject order = model_.check(h);
    if (order != Reject::kNone) {
      rejected.add(order);
      return;
    }
    ++accepted;
  }

  void send_pose(const PosePayload& p, std::uint32_t sequence, std::uint64_t t_ns) {
    std::uint8_t buf[kMaxBridgePacketSize];
    const std::size_t n = encode_pose({session_, sequence, t_ns}, p, buf);
    send(buf, n);
  }
  void next_pose(const PosePayload& p) { send_pose(p, ++sequence_, last_ns_ = std::max(last_ns_, ns())); }

  void silence() {
    ++silences;
    std::this_thread::sleep_for(std::chrono::milliseconds(100 + rng_() % 300));
  }

  void behave() {
    const unsigned what = rng_() % 1000;
    if (what < 3) {  // a silence
      silence();
    } else if (what < 550) {  // ordinary
      next_pose(pose_near(0.002));
    } else if (what < 600) {  // a jump of metres
      PosePayload p;
      std::uniform_real_distribution<double> far(-5.0, 5.0);
      p.position_m = {far(rng_), far(rng_), far(rng_)};
      next_pose(p);
    } else if (what < 650) {  // not finite
      PosePayload p = pose_near(0.0);
      const double bad[] = {std::nan(""), INFINITY, -INFINITY};
      (&p.position_m.x)[rng_() % 3] = bad[rng_() % 3];
      if (rng_() % 2) {
        p.flags = kPoseHasOrientation;
        p.orientation = {bad[rng_() % 3], 0, 0, 0};
        p.position_m = position_;
      }
      next_pose(p);
    } else if (what < 700) {  // a burst
      const int n = 2 + int(rng_() % 63);
      for (int i = 0; i < n; ++i) next_pose(pose_near(0.001));
    } else if (what < 770) {  // a duplicate, then one older
      const PosePayload p = pose_near(0.001);
      next_pose(p);
      send_pose(p, sequence_, last_ns_);
      send_pose(p, sequence_ - 1 - rng_() % 5, last_ns_);
    } else if (what < 800) {  // reordered: the newer first
      const PosePayload p = pose_near(0.001);
      sequence_ += 2;
      last_ns_ = std::max(last_ns_, ns());
      send_pose(p, sequence_, last_ns_);
      send_pose(p, sequence_ - 1, last_ns_);
    } else if (what < 820) {  // stale: a newer number, an older time
      send_pose(pose_near(0.001), ++sequence_, last_ns_ - 1000 - rng_() % 100000);
    } else if (what < 840) {  // a new session (the device process restarts)
      session_ += 1 + rng_() % 1000;
      sequence_ = std::uint32_t(rng_());
      last_ns_ = ns();
      next_pose(pose_near(0.001));
    } else {  // malformed
      std::uint8_t buf[kMaxBridgePacketSize + 8];
      const std::size_t n = encode_pose({session_, ++sequence_, last_ns_}, pose_near(0.001), buf);
      std::size_t size = n;
      switch (rng_() % 7) {
        case 0: size = rng_() % n; break;                      // truncated
        case 1: buf[n] = 0; size = n + 1 + rng_() % 8; break;  // overlong
        case 2: buf[rng_() % 4] ^= 0x5A; break;                // magic
        case 3: buf[4] = 2; break;                             // version (CRC then wrong too)
        case 4: buf[32 + rng_() % 60] ^= 1; break;             // a bit flipped in transit
        case 5: {                                              // the other direction's type
          ForcePayload f;
          size = encode_force({session_, sequence_, last_ns_}, f, buf);
          break;
        }
        default: buf[0] = 'X'; buf[1] = 'Y'; size = 2 + rng_() % 30; break;
      }
      send(buf, size);
    }
  }

  BridgeClient client_;
  std::mt19937 rng_;
  double duration_s_;
  SequenceFilter model_;
  std::uint32_t session_ = 1;
  std::uint32_t sequence_ = 0;
  std::uint64_t last_ns_ = 0;
  Vec3 position_{};
};

[[noreturn]] void usage(const char* why) {
  std::fprintf(stderr, "terracut-soak: %s\nusage: terracut-soak [--mode loop|mmt|mmt-enet] [--duration S] [--scenario FILE] [--seed N]\n", why);
  std::exit(2);
}

int run(int argc, char** argv) {
  double duration_s = 10.0;
  std::filesystem::path scenario_path;
  std::string mode = "loop";
  std::uint32_t seed = 1;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (i + 1 >= argc) usage(("missing value after " + a).c_str());
    const std::string v = argv[++i];
    char* end = nullptr;
    if (a == "--duration") {
      duration_s = std::strtod(v.c_str(), &end);
      if (*end != '\0' || !(duration_s >= 1.0 && duration_s <= 1e6)) usage("--duration must be a number of seconds in [1, 1e6]");
    } else if (a == "--mode") {
      if (v != "loop" && v != "mmt" && v != "mmt-enet") usage("--mode must be loop, mmt or mmt-enet");
      mode = v;
    } else if (a == "--scenario") {
      scenario_path = v;
    } else if (a == "--seed") {
      seed = std::uint32_t(std::strtoul(v.c_str(), &end, 10));
      if (*end != '\0') usage("--seed must be a whole number");
    } else {
      usage(("unknown option " + a).c_str());
    }
  }

  const std::filesystem::path scenarios = std::filesystem::path(TERRACUT_SOURCE_DIR) / "scenarios";
  if (mode != "loop") {
    soak::MmtSoakOptions o;
    o.duration_s = duration_s;
    o.scenario = scenario_path.empty() ? scenarios / "mmt_trench_clay.yaml" : scenario_path;
    o.seed = seed;
    o.enet = mode == "mmt-enet";
    return soak::run_mmt_soak(o);
  }
  if (scenario_path.empty()) scenario_path = scenarios / "trench_dry_sand.yaml";
  SettingsReader reader;
  io::SectionReader* const sections[] = {&reader};
  const io::Scenario sc = io::load_scenario(scenario_path, sections);
  HapticSettings settings = reader.settings;
  settings.device = DeviceKind::kUdp;
  settings.safety.rise_time_s = std::min(settings.safety.rise_time_s, 0.2);  // reach full force often
  const LoopParams params(settings, sc.blade, sc.rate_hz);
  Simulation sim(io::sim_params(sc, params.rate_hz()), io::build_initial_heights(sc));

  UdpDevice udp("127.0.0.1", 0);
  CheckingDevice device(udp, settings.safety, params.rate_hz());
  LoopOptions options;
  options.ticks = std::int64_t(std::llround(duration_s * params.rate_hz()));
  options.record_capacity = 0;
  options.realtime = false;
  HapticLoop loop(params, sim, Quat{}, device, options);

  // The sender stops 0.5 s before the loop (the last silence, and every
  // datagram drained before the counts are compared).
  HostileSender sender(udp.port(), seed, std::max(0.5, duration_s - 0.5));
  loop.start();
  std::thread hostile([&] { sender.run(); });
  std::this_thread::sleep_for(std::chrono::milliseconds(std::min<int>(1000, int(duration_s * 200))));
  const std::int64_t rss_start = rss_bytes();
  hostile.join();
  loop.join();
  const std::int64_t rss_end = rss_bytes();

  const LoopCounters& n = loop.counters();
  const BridgeStats& b = udp.bridge_stats();
  int failures = int(device.failures);
  auto require = [&](bool ok, const std::string& what) {
    if (!ok) {
      std::fprintf(stderr, "terracut-soak: %s\n", what.c_str());
      ++failures;
    }
  };
  require(n.ticks == options.ticks, "the loop ran " + std::to_string(n.ticks) + " of " + std::to_string(options.ticks) + " ticks");
  require(device.writes == options.ticks, "the device got " + std::to_string(device.writes) + " commands");
  require(rss_end - rss_start <= (std::int64_t(4) << 20), "resident memory grew by " + std::to_string(rss_end - rss_start) + " bytes");
  require(n.bad_samples == device.bad_samples, "the loop counted " + std::to_string(n.bad_samples) + " bad samples, the checker saw " + std::to_string(device.bad_samples));
  require(b.accepted + b.rejected.total() == b.datagrams_received, "datagrams received = accepted + rejected");
  const bool lossless = b.datagrams_received == sender.sent;
  if (lossless) {
    require(b.accepted == sender.accepted, "accepted " + std::to_string(b.accepted) + ", sender's account " + std::to_string(sender.accepted));
    for (std::size_t r = 1; r < kRejectReasonCount; ++r)
      require(b.rejected.by_reason[r] == sender.rejected.by_reason[r],
              "rejected as " + std::string(to_string(Reject(r))) + ": " + std::to_string(b.rejected.by_reason[r]) +
                  ", sender's account " + std::to_string(sender.rejected.by_reason[r]));
  } else {
    std::printf("note: the socket lost %lld of %lld datagrams; per-reason counts not compared\n",
                static_cast<long long>(sender.sent - b.datagrams_received), static_cast<long long>(sender.sent));
  }
  require(device.trips > 0, "no watchdog trip was seen (the silences did not reach the loop)");

  std::sort(device.latencies_s.begin(), device.latencies_s.end());
  const double worst_latency = device.latencies_s.empty() ? 0.0 : device.latencies_s.back();
  const double median_latency = device.latencies_s.empty() ? 0.0 : device.latencies_s[device.latencies_s.size() / 2];
  std::printf("terracut-soak: %.0f s, seed %u, scenario %s\n", duration_s, seed, scenario_path.filename().c_str());
  std::printf("  ticks %lld (missed deadlines %lld, silent ticks %lld), removed volume %.4g m^3\n",
              static_cast<long long>(n.ticks), static_cast<long long>(n.missed_deadlines),
              static_cast<long long>(n.silent_ticks), sim.removed_volume_m3());
  std::printf("  worst force %.4f N (limit %.4g N)\n", device.worst_force_n, settings.safety.max_force_n);
  std::printf("  worst force rate %.1f N/s away from [0, previous] (limit %.4g N/s); worst |change| %.1f N/s\n",
              device.worst_rate_n_per_s, settings.safety.max_force_rate_n_per_s, device.worst_change_n_per_s);
  std::printf("  watchdog trips %lld, %zu with a force to cut: last sample to zero force median %.1f ms, worst %.1f ms "
              "(timeout + ramp %.0f ms)\n",
              static_cast<long long>(device.trips), device.latencies_s.size(), median_latency * 1e3, worst_latency * 1e3,
              (settings.safety.watchdog_timeout_s + settings.safety.watchdog_ramp_s) * 1e3);
  std::printf("  latest trip %.1f ms after watchdog_timeout_s (the loop's own late ticks)\n", device.worst_trip_delay_s * 1e3);
  std::printf("  resident memory after 1 s %.2f MiB, at the end %.2f MiB\n", double(rss_start) / (1 << 20),
              double(rss_end) / (1 << 20));
  std::printf("  datagrams sent %lld, received %lld, accepted %lld; bad samples %lld, reconnects %lld\n",
              static_cast<long long>(sender.sent), static_cast<long long>(b.datagrams_received),
              static_cast<long long>(b.accepted), static_cast<long long>(n.bad_samples),
              static_cast<long long>(n.reconnects));
  std::printf("  rejected:");
  for (std::size_t r = 1; r < kRejectReasonCount; ++r)
    std::printf(" %s %lld", std::string(to_string(Reject(r))).c_str(), static_cast<long long>(b.rejected.by_reason[r]));
  std::printf("\n  %s\n", failures == 0 ? "all promises kept" : "PROMISES BROKEN");
  return failures == 0 ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "terracut-soak: %s\n", e.what());
    return 1;
  }
}
