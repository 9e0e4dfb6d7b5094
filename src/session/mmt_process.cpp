// Two-process MMT (mmt_process.hpp).
#include "terracut/session/mmt_process.hpp"

#include <arpa/inet.h>

#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <ostream>
#include <random>
#include <thread>

#include "mmt_json.hpp"
#include "terracut/core/error.hpp"
#include "terracut/core/format.hpp"
#include "terracut/haptics/device_option.hpp"
#include "terracut/io/image.hpp"
#include "terracut/net/emulator.hpp"
#include "terracut/session/world.hpp"

namespace terracut::session {
namespace {

using Clock = std::chrono::steady_clock;

// How a station's session ended (summary.json "ended").
enum class Ended { kCompleted, kOperatorEnded, kDuration, kStopped, kLinkLost, kRemoteEnded };
const char* to_string(Ended e) {
  switch (e) {
    case Ended::kCompleted: return "completed";             // operator: its run length
    case Ended::kOperatorEnded: return "operator_ended";    // remote: its operator ended it
    case Ended::kDuration: return "duration";               // remote: --duration
    case Ended::kStopped: return "stopped";                 // a stop request (SIGINT, SIGTERM)
    case Ended::kLinkLost: return "link_lost";              // operator: nothing heard for link_lost_s
    case Ended::kRemoteEnded: return "remote_ended";        // operator: the remote ended it first
  }
  return "unknown";
}

nlohmann::ordered_json udp_json(const net::EnetEndpoint& carrier, const net::LinkKey& key) {
  const net::EnetCounters& c = carrier.counters();
  nlohmann::ordered_json refused;
  for (std::size_t i = 1; i < net::kRefusalCount; ++i)
    refused[std::string(net::to_string(net::Refusal(i)))] = c.refused[i];
  nlohmann::ordered_json rejected;
  for (std::size_t i = 1; i < net::kAuthRejectCount; ++i)
    rejected[std::string(net::to_string(net::AuthReject(i)))] = c.rejected[i];
  return {{"authenticated", !key.insecure},
          {"key_fingerprint", key.insecure ? std::string("insecure") : net::fingerprint(key)},
          {"connections", c.connections},
          {"sessions", c.sessions},
          {"resumed", c.resumed},
          {"peers_refused", refused},
          {"sealed_rejected", rejected},
          {"unauthenticated_packets", c.unauthenticated_packets},
          {"datagrams_read", c.datagrams},
          {"dropped_unknown_source", c.dropped_unknown_source},
          {"dropped_oversize", c.dropped_oversize},
          {"connection_requests", c.connection_requests},
          {"to_half_open_connections", c.to_half_open},
          {"to_unauthenticated_peers", c.to_unauthenticated},
          {"dropped_by_kernel", c.kernel_dropped},
          {"receive_errors", c.receive_errors},
          {"receive_budget_stops", c.budget_stops},
          {"dropped_unconnected", c.dropped_unconnected},
          {"receive_buffer_bytes", c.receive_buffer_bytes}};
}

nlohmann::ordered_json station_json(const StationCounters& c, const net::EmulatedEndpoint& e,
                                    double duration_s) {
  nlohmann::ordered_json j;
  j["duration_s"] = duration_s;
  j["accepted"] = c.accepted;
  j["rejected"] = rejected_json(c.rejected);
  j["patches"] = c.patches;
  j["estimates"] = c.estimates;
  j["peer_sessions"] = c.sessions;
  j["silent_ticks"] = c.silent_ticks;
  const double d = std::max(duration_s, 1e-9);
  j["traffic"] = {{"sent_packets_per_s", double(e.traffic().sent) / d},
                  {"sent_bytes_per_s", double(e.traffic().sent_bytes) / d},
                  {"received_packets_per_s", double(e.traffic().received) / d},
                  {"received_bytes_per_s", double(e.traffic().received_bytes) / d},
                  {"sent", e.traffic().sent},
                  {"emulated_losses", e.emulator().counters().lost}};
  return j;
}

nlohmann::ordered_json rect_json(const Rect& r) { return {r.c0, r.r0, r.c1, r.r1}; }

void write_json(const std::filesystem::path& p, const nlohmann::ordered_json& j) {
  std::ofstream out(p, std::ios::binary);
  out << j.dump(2) << "\n";
  if (!out) throw InputError(p.string() + ": cannot be written");
}

// Ticks at the rate on the wall clock until done(t) says so: tick i at t =
// i / rate (a fixed step: the loop's physics and the arm's servo step per
// tick), due at that time after the start. A late station catches up; more
// than 10 periods late it skips the ticks it missed, so its time stays
// within 10 periods of the wall clock's (the delays it emulates are real
// ones; the operator measures its round trips on the wall clock,
// OperatorOptions::wall_clock). Returns the time run, s.
template <class Tick, class Done>
double paced(double rate_hz, Tick&& tick, Done&& done) {
  const auto start = Clock::now();
  std::int64_t i = 0;
  for (;; ++i) {
    const double now_s = std::chrono::duration<double>(Clock::now() - start).count();
    if (now_s > double(i + 10) / rate_hz)
      i = std::int64_t(now_s * rate_hz);
    else
      std::this_thread::sleep_until(start + std::chrono::duration_cast<Clock::duration>(
                                                std::chrono::duration<double>(double(i) / rate_hz)));
    const double t = double(i) / rate_hz;
    tick(t);
    if (done(t)) break;
  }
  return double(i + 1) / rate_hz;
}

// A time in the messages: to the millisecond.
std::string ms_text(double t_s) { return format_number(std::round(t_s * 1000.0) / 1000.0); }

bool stopping(const ProcessOptions& o) { return o.stop && o.stop->load(std::memory_order_relaxed); }

std::pair<std::string, int> address_of(const MmtSettings& s, const std::string& endpoint,
                                       const std::string& option) {
  return endpoint.empty() ? std::pair{s.address, s.port} : parse_endpoint(endpoint, option, s.address);
}

void check_insecure(const net::LinkKey& key, const std::string& address, const std::string& option) {
  if (key.insecure && !is_loopback(address))
    throw InputError(option + ": --insecure-loopback runs the link without authentication, only on "
                     "a loopback address (127.x.x.x), not on '" + address +
                     "'; give both stations a key (`terracut key --out FILE`, --key FILE)");
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

bool is_loopback(const std::string& address) {
  in_addr a{};
  return ::inet_pton(AF_INET, address.c_str(), &a) == 1 && (ntohl(a.s_addr) >> 24) == 127;
}

net::LinkKey link_key(const std::string& key_file, bool insecure_loopback) {
  const char* env = std::getenv(net::kKeyEnvironmentVariable);
  if (insecure_loopback && !key_file.empty())
    throw InputError("--insecure-loopback: not with --key " + key_file + " (one or the other)");
  if (!key_file.empty()) return net::read_key_file(key_file);
  if (insecure_loopback) return net::insecure_key();
  if (env && *env) return net::parse_key(env, net::kKeyEnvironmentVariable);
  throw InputError(std::string("--key: the link between the stations is authenticated: give both "
                               "the same key, --key FILE (make one with `terracut key --out FILE`) "
                               "or the environment variable ") +
                   net::kKeyEnvironmentVariable +
                   " (64 hex digits); --insecure-loopback runs a demo without one on 127.0.0.1");
}

std::uint32_t new_station_id() {
  std::random_device rd;
  std::uint32_t id = 0;
  while (id == 0) id = rd();
  return id;
}

net::EnetOptions udp_options(const MmtSettings& s, const net::LinkKey& key, std::uint32_t station_id) {
  net::EnetOptions o;
  o.key = key;
  o.station_id = station_id;
  o.takeover_silence_s = s.link_lost_s;
  // ENet gives up a peer after at most peer_timeout_s; the operator then
  // connects again, well inside link_lost_s.
  o.peer_timeout_s = std::clamp(0.4 * s.link_lost_s, 1.0, 10.0);
  return o;
}

UdpLink connect_operator_link(const MmtSettings& s, const std::string& endpoint,
                              const std::string& option, double timeout_s,
                              const net::LinkKey& key, std::uint32_t station_id) {
  const auto [address, port] = address_of(s, endpoint, option);
  check_insecure(key, address, option);
  UdpLink udp;
  udp.carrier = net::EnetEndpoint::connect(address, port, udp_options(s, key, station_id));
  net::EnetEndpoint& link = *udp.carrier;
  // Wait for the authenticated session before the loop starts.
  const auto start = Clock::now();
  net::Inbox none;
  while (!link.connected()) {
    if (const auto why = link.refused_by_peer()) {
      std::string what = std::string(net::to_string(*why));
      if (*why == net::Refusal::kBadKey)
        what += ": the two stations hold different keys (compare `terracut key --fingerprint FILE` "
                "on both machines)";
      else if (*why == net::Refusal::kInsecureMismatch)
        what += ": one station runs --insecure-loopback, the other has a key";
      else if (*why == net::Refusal::kBusy)
        what += ": it serves another operator's session";
      throw InputError(option + ": the remote station at " + address + ":" + std::to_string(port) +
                       " refused this operator (" + what + ")");
    }
    if (std::chrono::duration<double>(Clock::now() - start).count() > timeout_s)
      throw InputError(option + ": no remote station answered at " + address + ":" +
                       std::to_string(port) + " within " + format_number(timeout_s) +
                       " s (or it did not prove the key)");
    link.receive(0.0, none);
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  udp.endpoint = std::make_unique<net::EmulatedEndpoint>(*udp.carrier, s.to_remote, net::EmulatorClock::kWall);
  return udp;
}

int run_remote_process(const Scenario& op, const ProcessOptions& o) {
  if (!op.mmt) throw InputError(no_mmt_section(op));
  const MmtSettings s = apply_overrides(*op.mmt, o.overrides);
  const Scenario remote = load_remote_scenario(op);
  const auto [address, port] = address_of(s, o.endpoint, "--listen");
  check_insecure(o.key, address, "--listen");
  if (o.overrides.duration_s && !(*o.overrides.duration_s > 0.0))
    throw InputError(must_be("--duration", "> 0", *o.overrides.duration_s));
  const World local(op);  // the operator's initial terrain: what the deadband compares against
  const std::uint32_t id = new_station_id();
  auto carrier = net::EnetEndpoint::listen(address, port, udp_options(s, o.key, id));
  net::EmulatedEndpoint link(*carrier, s.to_operator, net::EmulatorClock::kWall);
  // The records go to remote.csv as they are made: a live session has no set end.
  RemoteOptions options;
  options.keep_records = false;
  RemoteStation station(remote, s, op.base.soil.material, local.simulation().grid(), link, id, options);
  std::filesystem::create_directories(o.out);
  StationCsv csv = StationCsv::remote_csv(o.out / "remote.csv");
  if (o.log)
    *o.log << "terracut mmt: remote listening on " << address << ":" << carrier->port()
           << (o.key.insecure ? " (NOT authenticated: --insecure-loopback)"
                              : " (key " + net::fingerprint(o.key) + ")")
           << std::endl;
  // Until the operator ends the session, --duration, or a stop request.
  Ended ended = Ended::kStopped;
  double operator_lost_at_s = -1.0;
  const double duration = paced(
      op.base.rate_hz,
      [&](double t) {
        station.tick(t);
        csv.add(station.last_record());
      },
      [&](double t) {
        // The session's operator is lost once unheard for link_lost_s.
        const bool lost = carrier->counters().sessions > 0 && !carrier->peer_ended() &&
                          station.last_record().holding &&
                          t - station.last_command_s() > s.link_lost_s;
        if (lost && operator_lost_at_s < 0.0) {
          operator_lost_at_s = t;
          if (o.warn)
            *o.warn << "terracut mmt: remote: the operator has been unheard for "
                    << format_number(s.link_lost_s) << " s (t = " << ms_text(t)
                    << " s); waiting for it to come back\n";
        }
        if (!lost) operator_lost_at_s = -1.0;
        if (carrier->peer_ended()) return ended = Ended::kOperatorEnded, true;
        if (o.overrides.duration_s && t + 0.5 / op.base.rate_hz >= *o.overrides.duration_s)
          return ended = Ended::kDuration, true;
        if (stopping(o)) return ended = Ended::kStopped, true;
        return false;
      });
  // The operator, if still there, hears that the session is over.
  if (ended != Ended::kOperatorEnded) carrier->end_session(0.5);
  csv.finish();
  const std::int64_t sessions = carrier->counters().sessions;
  const char* operator_state = sessions == 0                 ? "never_connected"
                               : ended == Ended::kOperatorEnded ? "ended_the_session"
                               : operator_lost_at_s >= 0.0   ? "lost"
                                                             : "connected";
  const bool lost = sessions > 0 && operator_lost_at_s >= 0.0 && ended != Ended::kOperatorEnded;
  nlohmann::ordered_json j = station_json(station.counters(), link, duration);
  j["role"] = "remote";
  j["ended"] = {{"how", to_string(ended)}, {"t_s", duration}};
  j["operator"] = {{"state_at_end", operator_state},
                   {"lost_at_s", lost ? nlohmann::ordered_json(operator_lost_at_s) : nlohmann::ordered_json()},
                   {"id", carrier->peer_id()},
                   {"commands_received", station.commands_received()},
                   {"commands_missed", station.commands_missed()},
                   {"round_trip_s", station.round_trip_s()}};
  j["link"] = link_json(s.to_operator);
  j["udp"] = udp_json(*carrier, o.key);
  j["connections"] = carrier->counters().connections;
  j["estimate"] = detail::estimate_json(station.estimate(), &station.true_material());
  j["remote_arm"] = {{"force_limit_n", s.arm_force_limit_n},
                     {"follower_time_constant_s", s.follower_time_constant_s},
                     {"stalled_ticks", station.stalled_ticks()}};
  j["worked"] = rect_json(station.worked());
  write_json(o.out / "summary.json", j);
  // What the remote's camera sees at the end: the report's terrain error.
  const GridSpec& g = station.simulation().grid().spec();
  std::vector<float> surface(std::size_t(g.sample_count()));
  station.rig().world().sense_heights({0, 0, g.cols, g.rows}, surface);
  io::write_npy(o.out / "surface.npy", surface.data(), g.rows, g.cols);
  if (o.log)
    *o.log << "terracut mmt: remote done (" << to_string(ended) << "): "
           << station.counters().accepted << " commands, " << station.counters().patches
           << " patches sent, " << carrier->counters().refused_total() << " peers refused\n";
  if (lost && o.warn)
    *o.warn << "terracut mmt: remote: the session's operator was lost at t = "
            << ms_text(operator_lost_at_s) << " s and did not come back; exit code "
            << kExitLinkLost << "\n";
  return lost ? kExitLinkLost : 0;
}

int run_operator_process(const Scenario& op, const ProcessOptions& o) {
  if (!op.mmt) throw InputError(no_mmt_section(op));
  const MmtSettings s = apply_overrides(*op.mmt, o.overrides);
  const auto [address, port] = address_of(s, o.endpoint, "--connect");
  if (o.overrides.duration_s && !(*o.overrides.duration_s > 0.0))
    throw InputError(must_be("--duration", "> 0", *o.overrides.duration_s));
  if (o.repeat && !o.overrides.duration_s)
    throw InputError("--repeat: give the session's length with --duration (the cut repeats until then)");
  const std::uint32_t id = new_station_id();
  UdpLink udp = connect_operator_link(s, o.endpoint, "--connect", o.connect_timeout_s, o.key, id);
  net::EnetEndpoint& carrier = *udp.carrier;
  std::unique_ptr<haptics::Device> device = make_operator_device(op, o.repeat);
  // The records go to operator.csv as they are made: a live session's
  // duration is the user's.
  OperatorOptions options;
  options.keep_records = false;
  options.wall_clock = true;
  OperatorStation station(op, s, *device, *udp.endpoint, id, options);
  std::filesystem::create_directories(o.out);
  StationCsv csv = StationCsv::operator_csv(o.out / "operator.csv");
  double passivity = 0.0, worst_loss = 0.0;
  // The run: the path, then a measured round trip, a sensing period and a
  // blend for the last updates to land (or --duration).
  const double path_s = operator_duration_s(op);
  auto run_length_s = [&] {
    const double round_trip_s = station.round_trip_bound_s();
    return o.overrides.duration_s.value_or(mmt_run_length_s(
        s, path_s, round_trip_s, net::retransmit_timeout_s(s.to_operator, round_trip_s)));
  };
  if (o.log)
    *o.log << "terracut mmt: operator connected to " << address << ":" << port
           << (o.key.insecure ? " (NOT authenticated: --insecure-loopback)" : " (authenticated)")
           << "\n";
  const double emulated_loss = s.to_remote.loss;
  bool warned_loss = false;
  Ended ended = Ended::kCompleted;
  const double ran = paced(
      station.rate_hz(),
      [&](double t) {
        station.tick(t);
        const OperatorRecord& r = station.last_record();
        csv.add(r);
        passivity = std::max(passivity, r.passivity_j);
        worst_loss = std::max(worst_loss, r.command_loss);
        // Commands lost beyond what the emulator loses: said once, live.
        if (!warned_loss && r.command_loss > emulated_loss + 0.05 && o.warn) {
          warned_loss = true;
          *o.warn << "terracut mmt: operator: the remote received "
                  << format_number(std::round((1.0 - r.command_loss) * 1000.0) / 10.0)
                  << " % of the commands over the last second (emulated loss "
                  << format_number(emulated_loss * 100.0) << " %); summary.json has the counts\n";
        }
      },
      [&](double t) {
        if (station.heard() && t - station.last_heard_s() > s.link_lost_s)
          return ended = Ended::kLinkLost, true;
        if (carrier.peer_ended()) return ended = Ended::kRemoteEnded, true;
        if (stopping(o)) return ended = Ended::kStopped, true;
        return t + 0.5 / station.rate_hz() >= run_length_s();
      });
  if (ended == Ended::kCompleted || ended == Ended::kStopped) carrier.end_session(1.0);
  csv.finish();
  nlohmann::ordered_json j = station_json(station.counters(), *udp.endpoint, ran);
  j["role"] = "operator";
  j["rate_hz"] = station.rate_hz();
  j["models_arm"] = s.models_arm;
  j["ended"] = {{"how", to_string(ended)}, {"t_s", ran}};
  j["link"] = link_json(s.to_remote);
  j["round_trip"] = {{"measured_s", station.rtt_s()},
                     {"bound_s", station.round_trip_bound_s()},
                     {"emulated_s", s.to_remote.delay_s + s.to_operator.delay_s}};
  j["silences"] = {{"count", station.silences()},
                   {"longest_s", station.longest_silence_s()},
                   {"silent_ticks", station.counters().silent_ticks}};
  j["commands"] = {{"sent", station.commands_sent()},
                   {"followed", station.commands_followed()},
                   {"received_by_remote", station.commands_received_by_remote()},
                   {"loss", station.command_loss()},
                   {"loss_emulated", emulated_loss},
                   {"worst_loss_over_a_second", worst_loss}};
  j["udp"] = udp_json(carrier, o.key);
  j["max_force_step_at_update_n"] = station.max_update_step_n();
  j["max_force_step_while_updating_n"] = station.max_step_while_updating_n();
  j["material_applied"] = detail::material_json(station.simulation().force_material());
  j["passivity_max_energy_into_hand_j"] = passivity;
  j["worked"] = rect_json(station.worked());
  write_json(o.out / "summary.json", j);
  const HeightGrid& grid = station.simulation().grid();
  io::write_npy(o.out / "heights.npy", grid.heights(), grid.rows(), grid.cols());
  if (o.log)
    *o.log << "terracut mmt: operator done (" << to_string(ended) << "): "
           << station.counters().accepted << " messages accepted, "
           << station.counters().patches << " patches merged; the remote received "
           << format_number(std::round((1.0 - station.command_loss()) * 1000.0) / 10.0)
           << " % of the commands\n";
  if (ended == Ended::kLinkLost || ended == Ended::kRemoteEnded) {
    if (o.warn) {
      if (ended == Ended::kLinkLost)
        *o.warn << "terracut mmt: operator: the link to the remote died: nothing heard since t = "
                << ms_text(station.last_heard_s()) << " s (" << format_number(s.link_lost_s)
                << " s, mmt.link_lost_s); the force faded out after "
                << format_number(s.timeout_s) << " s; exit code " << kExitLinkLost << "\n";
      else
        *o.warn << "terracut mmt: operator: the remote ended the session at t = "
                << ms_text(ran) << " s, before the operator's run was done; exit code "
                << kExitLinkLost << "\n";
    }
    return kExitLinkLost;
  }
  return 0;
}

}  // namespace terracut::session
