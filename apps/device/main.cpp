// terracut-device: plays a haptic device over the UDP bridge protocol, so the
// haptic loop (`terracut haptics --device udp`) can be tried without
// hardware, and as a reference for writing a real bridge. The handle follows
// the scenario's cut (--mode script) or is the simulated hand of the `sim`
// device (--mode sim), which feels the forces coming back. At the end it
// prints what went over the wire: poses sent, forces received, rejected
// packets by reason, and round-trip times.
#include <CLI/CLI.hpp>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <exception>
#include <iostream>
#include <optional>
#include <string>
#include <thread>

#include "../exit_codes.hpp"
#include "terracut/core/error.hpp"
#include "terracut/haptics/device_player.hpp"
#include "terracut/haptics/pacer.hpp"
#include "terracut/haptics/device_option.hpp"
#include "terracut/session/scenario.hpp"

namespace {

using namespace terracut;
using namespace terracut::haptics;

std::atomic<bool> g_stop{false};
extern "C" void on_signal(int) { g_stop.store(true); }

using terracut::apps::kExitError;
using terracut::apps::kExitOk;
constexpr int kExitNoAnswer = terracut::apps::kExitPartial;  // ran, but the loop never answered

struct Options {
  std::string scenario;
  std::string mode = "sim";
  std::string connect;
  double rate_hz = 0.0;
  double duration_s = 0.0;
  double start_delay_s = 0.0;
  long long session = -1;
  bool quiet = false;
};

int run(const Options& opt) {
  const session::Scenario input = session::load_scenario(opt.scenario);
  const haptics::HapticSettings& s = input.haptics;
  const io::Scenario& sc = input.base;

  // The cut to follow (as the loop's script and sim devices do).
  int cut = -1;
  if (!s.cut.empty()) {
    cut = sc.find_cut(s.cut);
    if (cut < 0)
      throw InputError(opt.scenario + ": haptics.cut: no cut named '" + s.cut +
                       "' in the scenario");
  } else if (!sc.sequence.empty()) {
    cut = sc.sequence.front();
  } else if (!sc.cuts.empty()) {
    cut = 0;
  }
  if (cut < 0) throw InputError(opt.scenario + ": the scenario has no cut to follow");
  const Motion& motion = sc.cuts[std::size_t(cut)];

  // Where to send.
  std::optional<std::string> address = s.udp.address;
  std::optional<int> port = s.udp.port;
  if (!opt.connect.empty()) parse_endpoint(opt.connect, "--connect", address, port);
  if (!port || *port < 1) throw InputError("--connect: the port must be in [1, 65535]");

  const double rate = opt.rate_hz > 0.0 ? opt.rate_hz : sc.rate_hz;
  const double duration = opt.duration_s > 0.0 ? opt.duration_s : motion.duration_s() + s.settle_s;
  const std::uint32_t session =
      opt.session >= 0 ? std::uint32_t(opt.session)
                       : std::uint32_t(std::chrono::steady_clock::now().time_since_epoch().count());
  const PlayerMode mode = opt.mode == "script" ? PlayerMode::kScript : PlayerMode::kSim;
  DevicePlayer player(*address, *port, session, mode, DevicePath(motion, Workspace(s.workspace)),
                      s.hand, s.forces.device.inherent_damping_n_s_per_m, rate);

  if (!opt.quiet)
    std::cerr << "terracut-device: playing '" << motion.name << "' (" << opt.mode << ") to "
              << *address << ":" << *port << " at " << rate << " Hz for " << duration
              << " s, session " << session << "\n";
  if (opt.start_delay_s > 0.0)
    std::this_thread::sleep_for(std::chrono::duration<double>(opt.start_delay_s));

  // The device's servo loop, paced at the rate.
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  PacerSettings ps;
  ps.rate_hz = rate;
  Pacer pacer(ps);
  Tick tick = pacer.start();
  const double origin = tick.start_s;
  const auto ticks = static_cast<long long>(std::llround(duration * rate));
  for (long long i = 0; i < ticks && !g_stop.load(); ++i) {
    if (i > 0) tick = pacer.wait_next();
    const double t = tick.start_s - origin;
    player.tick(t, static_cast<std::uint64_t>(std::llround(tick.start_s * 1e9)));
  }

  // What went over the wire.
  const PlayerStats st = player.stats();
  const LoopStats ls = pacer.stats();
  std::printf(
      "terracut-device: %lld ticks, %lld poses sent, %lld forces accepted, max force %.3f N\n",
      static_cast<long long>(st.ticks), static_cast<long long>(st.poses_sent),
      static_cast<long long>(st.forces_accepted), st.max_force_n);
  std::printf("  received %lld datagrams, rejected %lld:",
              static_cast<long long>(st.bridge.datagrams_received),
              static_cast<long long>(st.bridge.rejected.total()));
  for (std::size_t r = 1; r < kRejectReasonCount; ++r)
    std::printf(" %s %lld", std::string(to_string(static_cast<Reject>(r))).c_str(),
                static_cast<long long>(st.bridge.rejected.by_reason[r]));
  std::printf("\n  forces lost %lld, loop sessions %lld, send errors %lld\n",
              static_cast<long long>(st.bridge.lost), static_cast<long long>(st.bridge.sessions),
              static_cast<long long>(st.bridge.send_errors));
  if (st.rtt_samples > 0)
    std::printf(
        "  round trip (pose -> force answering it): p50 %.1f us, p99 %.1f us, max %.1f us (%lld)\n",
        st.rtt_p50_us, st.rtt_p99_us, st.rtt_max_us, static_cast<long long>(st.rtt_samples));
  std::printf(
      "  pacing: period jitter p50 %.1f us, p99 %.1f us, max %.1f us; %lld missed deadlines\n",
      ls.period_jitter.p50_s * 1e6, ls.period_jitter.p99_s * 1e6, ls.period_jitter.max_s * 1e6,
      static_cast<long long>(ls.missed_deadlines));
  if (const auto& hand = player.hand())
    std::printf("  hand: max tracking error %.4f m, work done by the force %.4f J\n",
                hand->max_tracking_error_m(), hand->rendered_work_j());
  if (st.forces_accepted == 0) {
    std::cerr << "terracut-device: warning: no force came back from " << *address << ":" << *port
              << " (is `terracut haptics --device udp` running there?)\n";
    return kExitNoAnswer;
  }
  return kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  CLI::App app{
      "terracut-device " TERRACUT_VERSION
      " -- plays a haptic device over terracut's UDP bridge protocol\n"
      "(docs/bridge-protocol.md): the handle follows the scenario's cut, or is a simulated\n"
      "hand that feels the force the haptic loop sends back.",
      "terracut-device"};
  app.add_option("scenario", opt.scenario,
                 "Scenario file with a `haptics:` section: the cut to follow (haptics.cut), the\n"
                 "workspace mapping, the hand (haptics.hand) and the loop's address (haptics.udp)")
      ->required()
      ->type_name("SCENARIO.yaml");
  app.add_option("--mode,-m", opt.mode,
                 "'sim': a simulated hand pulled along the cut, moved by the forces received;\n"
                 "'script': the handle exactly on the cut (forces only counted)")
      ->check(CLI::IsMember({"sim", "script"}))
      ->capture_default_str();
  app.add_option("--connect,-c", opt.connect,
                 "The haptic loop's address: ADDR:PORT, PORT or [IPV6]:PORT. Default haptics.udp")
      ->type_name("ADDR:PORT");
  app.add_option("--rate", opt.rate_hz, "Poses per second. Default the scenario's rate_hz")
      ->type_name("HZ")
      ->check(CLI::Range(1.0, 10000.0));
  app.add_option("--duration", opt.duration_s,
                 "Seconds to play. Default: the cut's duration plus haptics.settle_s")
      ->type_name("S")
      ->check(CLI::Range(1e-3, 86400.0));
  app.add_option("--start-delay", opt.start_delay_s,
                 "Seconds to wait before the first pose (give the loop time to start)")
      ->type_name("S")
      ->check(CLI::Range(0.0, 60.0));
  app.add_option("--session", opt.session,
                 "Session id to send (default: from the clock; a new id is a reconnection)")
      ->type_name("N")
      ->check(CLI::Range(0LL, 4294967295LL));
  app.add_flag("--quiet,-q", opt.quiet, "No start message");
  app.footer(
      std::string(terracut::apps::kExitCodesHelp) +
      "\n\n"
      "Example (two shells):\n"
      "  terracut haptics scenarios/trench_dry_sand.yaml --device udp --duration 8 --out out/udp\n"
      "  terracut-device scenarios/trench_dry_sand.yaml --mode sim --start-delay 0.5");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? kExitOk : terracut::apps::kExitUsage;
  }
  try {
    return run(opt);
  } catch (const std::exception& e) {
    std::cerr << "terracut-device: error: " << e.what() << "\n";
    return kExitError;
  }
}
