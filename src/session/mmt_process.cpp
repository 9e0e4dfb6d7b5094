// Two-process MMT (mmt_process.hpp).
#include "terracut/session/mmt_process.hpp"

#include "mmt_json.hpp"

#include <nlohmann/json.hpp>

#include <chrono>
#include <fstream>
#include <ostream>
#include <thread>

#include "terracut/core/error.hpp"
#include "terracut/core/format.hpp"
#include "terracut/haptics/device_option.hpp"
#include "terracut/net/enet_transport.hpp"
#include "terracut/session/world.hpp"

namespace terracut::session {
namespace {

using Clock = std::chrono::steady_clock;

nlohmann::ordered_json station_json(const StationCounters& c, const net::Endpoint& e,
                                    double duration_s) {
  nlohmann::ordered_json j;
  j["duration_s"] = duration_s;
  j["accepted"] = c.accepted;
  nlohmann::ordered_json r;
  for (std::size_t i = 1; i < net::kRejectReasonCount; ++i)
    r[std::string(net::to_string(net::Reject(i)))] = c.rejected.by_reason[i];
  j["rejected"] = r;
  j["patches"] = c.patches;
  j["estimates"] = c.estimates;
  j["peer_sessions"] = c.sessions;
  j["silent_ticks"] = c.silent_ticks;
  const double d = std::max(duration_s, 1e-9);
  j["traffic"] = {{"sent_packets_per_s", double(e.traffic().sent) / d},
                  {"sent_bytes_per_s", double(e.traffic().sent_bytes) / d},
                  {"received_packets_per_s", double(e.traffic().received) / d},
                  {"received_bytes_per_s", double(e.traffic().received_bytes) / d},
                  {"emulated_losses", e.emulator().counters().lost}};
  return j;
}

void write_json(const std::filesystem::path& p, const nlohmann::ordered_json& j) {
  std::ofstream out(p, std::ios::binary);
  out << j.dump(2) << "\n";
  if (!out) throw InputError(p.string() + ": cannot be written");
}

// Ticks at the rate on the wall clock until done() says so; t = i / rate.
template <class Tick, class Done>
double paced(double rate_hz, Tick&& tick, Done&& done) {
  const auto start = Clock::now();
  std::int64_t i = 0;
  for (;; ++i) {
    const auto deadline = start + std::chrono::duration_cast<Clock::duration>(
                                      std::chrono::duration<double>(double(i) / rate_hz));
    std::this_thread::sleep_until(deadline);
    const double t = double(i) / rate_hz;
    tick(t);
    if (done(t)) break;
  }
  return double(i + 1) / rate_hz;
}

}  // namespace

std::pair<std::string, int> parse_endpoint(const std::string& text, const std::string& option,
                                           const std::string& default_address) {
  std::optional<std::string> address;
  std::optional<int> port;
  haptics::parse_endpoint(text, option, address, port);
  if (!port) throw InputError(option + ": expected ADDR:PORT or PORT (IPv4), got '" + text + "'");
  return {address.value_or(default_address), *port};
}

std::unique_ptr<net::Endpoint> connect_operator_link(const MmtSettings& s,
                                                     const std::string& endpoint,
                                                     const std::string& option, double timeout_s) {
  const auto [address, port] =
      endpoint.empty() ? std::pair{s.address, s.port} : parse_endpoint(endpoint, option, s.address);
  auto link = net::EnetEndpoint::connect(address, port, s.to_remote);
  // Wait for the connection before the loop starts.
  const auto start = Clock::now();
  net::Inbox none;
  while (!link->connected()) {
    if (std::chrono::duration<double>(Clock::now() - start).count() > timeout_s)
      throw InputError(option + ": no remote station answered at " + address + ":" +
                       std::to_string(port) + " within " + format_number(timeout_s) + " s");
    link->receive(0.0, none);
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return link;
}

int run_remote_process(const Scenario& op, const ProcessOptions& o) {
  if (!op.mmt)
    throw InputError(op.base.source_path.string() + ": mmt: the scenario has no mmt: section");
  const MmtSettings s = apply_overrides(*op.mmt, o.overrides);
  const Scenario remote = load_remote_scenario(op);
  const auto [address, port] =
      o.endpoint.empty() ? std::pair{s.address, s.port} : parse_endpoint(o.endpoint, "--listen", s.address);
  const World local(op);  // the operator's initial terrain: what the deadband compares against
  auto link = net::EnetEndpoint::listen(address, port, s.to_operator);
  // The records go to remote.csv as they are made: a live session has no set end.
  RemoteOptions options;
  options.keep_records = false;
  RemoteStation station(remote, s, op.base.soil.material, local.simulation().grid(), *link,
                        std::uint32_t(Clock::now().time_since_epoch().count()), options);
  std::filesystem::create_directories(o.out);
  StationCsv csv = StationCsv::remote_csv(o.out / "remote.csv");
  if (o.log)
    *o.log << "terracut mmt: remote listening on " << address << ":" << link->port() << std::endl;
  const double max_s = o.remote_max_s > 0.0 ? o.remote_max_s : operator_duration_s(op) + 10.0;
  double last_command_s = -1.0;
  std::int64_t accepted = 0;
  const double duration = paced(
      op.haptics.rate_hz,
      [&](double t) {
        station.tick(t);
        csv.add(station.last_record());
      },
      [&](double t) {
        if (station.counters().accepted > accepted) {
          accepted = station.counters().accepted;
          last_command_s = t;
        }
        return t >= max_s || (last_command_s >= 0.0 && t - last_command_s > o.remote_idle_end_s);
      });
  csv.finish();
  nlohmann::ordered_json j = station_json(station.counters(), *link, duration);
  j["role"] = "remote";
  j["connections"] = link->connections();
  j["estimate"] = detail::estimate_json(station.estimate(), &station.true_material());
  j["remote_arm"] = {{"force_limit_n", s.arm_force_limit_n},
                     {"stalled_ticks", station.stalled_ticks()}};
  write_json(o.out / "summary.json", j);
  if (o.log)
    *o.log << "terracut mmt: remote done: " << station.counters().accepted << " commands, "
           << station.counters().patches << " patches sent\n";
  return 0;
}

int run_operator_process(const Scenario& op, const ProcessOptions& o) {
  if (!op.mmt)
    throw InputError(op.base.source_path.string() + ": mmt: the scenario has no mmt: section");
  const MmtSettings s = apply_overrides(*op.mmt, o.overrides);
  const auto [address, port] =
      o.endpoint.empty() ? std::pair{s.address, s.port} : parse_endpoint(o.endpoint, "--connect", s.address);
  std::unique_ptr<net::Endpoint> link =
      connect_operator_link(s, o.endpoint, "--connect", o.connect_timeout_s);
  std::unique_ptr<haptics::Device> device = make_operator_device(op);
  // The records go to operator.csv as they are made: a live session's
  // duration is the user's.
  OperatorOptions options;
  options.keep_records = false;
  OperatorStation station(op, s, *device, *link,
                          std::uint32_t(Clock::now().time_since_epoch().count()), options);
  std::filesystem::create_directories(o.out);
  StationCsv csv = StationCsv::operator_csv(o.out / "operator.csv");
  double passivity = 0.0;
  const double duration_s = o.overrides.duration_s.value_or(
      operator_duration_s(op) + s.to_remote.delay_s + s.to_operator.delay_s + s.blend_s + 0.3);
  if (o.log) *o.log << "terracut mmt: operator connected to " << address << ":" << port << "\n";
  const double ran = paced(
      station.rate_hz(),
      [&](double t) {
        station.tick(t);
        csv.add(station.last_record());
        passivity = std::max(passivity, station.last_record().passivity_j);
      },
      [&](double t) { return t + 0.5 / station.rate_hz() >= duration_s; });
  csv.finish();
  nlohmann::ordered_json j = station_json(station.counters(), *link, ran);
  j["role"] = "operator";
  j["max_force_step_at_update_n"] = station.max_update_step_n();
  j["material_applied"] = detail::material_json(station.simulation().force_material());
  j["estimates_applied"] = station.counters().estimates;
  j["passivity_max_energy_into_hand_j"] = passivity;
  write_json(o.out / "summary.json", j);
  if (o.log)
    *o.log << "terracut mmt: operator done: " << station.counters().accepted
           << " messages accepted, " << station.counters().patches << " patches merged\n";
  return 0;
}

}  // namespace terracut::session
