// terracut-netprobe: an attacker on the same machine, for the two-process
// teleoperation tests and the soak (tests/session/mmt_flood_test.sh,
// scripts/soak_mmt.sh): a junk flood from a port of its own and an intruder
// that is a real ENet client (tests/support/hostile_udp.hpp), against a
// station's UDP port on 127.0.0.1, until --duration or SIGINT/SIGTERM. At
// the end it writes what it sent and what it heard as JSON (--out, or stdout).
//
//   terracut-netprobe --port 47100 --flood-rate 50000 --intruder --duration 60 --out probe.json
#include <CLI/CLI.hpp>

#include <atomic>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <thread>

#include "../support/hostile_udp.hpp"

namespace {
std::atomic<bool> g_stop{false};
extern "C" void on_signal(int) { g_stop.store(true); }
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"An attacker on this machine against a terracut mmt station's UDP port (tests, soak)",
               "terracut-netprobe"};
  int port = 0;
  double rate_hz = 0.0, duration_s = 1e9;
  bool intrude = false;
  unsigned seed = 1;
  std::string out;
  app.add_option("--port", port, "the station's UDP port on 127.0.0.1")->required()->check(CLI::Range(1, 65535));
  app.add_option("--flood-rate", rate_hz, "junk datagrams per second (0: no flood)")->check(CLI::Range(0.0, 1e6));
  app.add_flag("--intruder", intrude, "also try to take the session over as an ENet client");
  app.add_option("--duration", duration_s, "seconds (default: until SIGINT/SIGTERM)")->check(CLI::PositiveNumber);
  app.add_option("--seed", seed, "random seed");
  app.add_option("--out", out, "where to write the counts (JSON; default stdout)");
  CLI11_PARSE(app, argc, argv);
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);

  terracut::test::JunkFlood flood(seed);
  terracut::test::Intruder intruder(seed + 1);
  std::thread flooder;
  if (rate_hz > 0.0) flooder = std::thread([&] { flood.run(port, rate_hz, duration_s, g_stop); });
  if (intrude) intruder.run(port, duration_s, g_stop);
  if (flooder.joinable()) flooder.join();

  const auto& f = flood.counts();
  const auto& i = intruder.counts();
  char text[1024];
  std::snprintf(text, sizeof text,
                "{\n  \"flood\": {\"sent\": %lld, \"random\": %lld, \"empty\": %lld, \"truncated\": %lld, "
                "\"connection_requests\": %lld, \"enet_like\": %lld, \"oversize\": %lld, \"send_failed\": %lld},\n"
                "  \"intruder\": {\"attempts\": %lld, \"connected\": %lld, \"refused\": %lld, \"silent\": %lld, "
                "\"refusal_codes\": [%lld, %lld, %lld, %lld, %lld, %lld]}\n}\n",
                static_cast<long long>(f.sent), static_cast<long long>(f.random), static_cast<long long>(f.empty),
                static_cast<long long>(f.truncated), static_cast<long long>(f.connects),
                static_cast<long long>(f.enet_like), static_cast<long long>(f.oversize),
                static_cast<long long>(f.failed), static_cast<long long>(i.attempts),
                static_cast<long long>(i.connected), static_cast<long long>(i.refused),
                static_cast<long long>(i.silent), static_cast<long long>(i.refusal_codes[0]),
                static_cast<long long>(i.refusal_codes[1]), static_cast<long long>(i.refusal_codes[2]),
                static_cast<long long>(i.refusal_codes[3]), static_cast<long long>(i.refusal_codes[4]),
                static_cast<long long>(i.refusal_codes[5]));
  if (out.empty()) {
    std::fputs(text, stdout);
  } else {
    std::ofstream(out) << text;
  }
  return 0;
}
