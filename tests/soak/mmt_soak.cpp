// terracut-soak --mode mmt | mmt-enet: both teleoperation stations
// (session/mmt.hpp) under a hostile peer. docs/reliability.md.
//
// The stations run in one process, at the loop rate: over the in-memory
// link in simulated time (mmt), or over real loopback UDP through ENet,
// paced by the wall clock (mmt-enet). Between each station and its link sits
// a hostile endpoint that, besides what the peer really sends, hands the
// station datagrams a hostile peer on its port could send: random bytes;
// truncated, oversized, bad-magic, bad-version, bad-CRC and wrong-type
// copies of real messages; valid messages of another link (foreign); NaN and
// inf fields; huge patches (2048 x 2048 samples, and one declaring more than
// the cap) and patches outside the grid; replays (duplicate), older
// sequence numbers (reordered), newer ones with older times (stale);
// forged but valid messages of a new session (far poses, absurd soil
// factors, heights of tens of metres: accepted, as a restarted peer is);
// floods of up to 64 at once; and outages, during which nothing the peer
// sends arrives. In mmt-enet the stations' session is authenticated
// (net/secure.hpp) and a raw UDP socket also sends random bytes to both
// stations' ports: their carriers must drop and count every one.
//
// Asserted over the whole run (exit status 1 and a line per broken promise):
//   - the operator's device force never exceeds safety.max_force_n nor grows
//     faster than safety.max_force_rate_n_per_s (CheckingDevice);
//   - after the last datagram the operator accepted, the force is zero
//     within mmt.timeout_s + watchdog_timeout_s + watchdog_ramp_s (+2 ticks);
//   - no crash, no exception: every tick of both stations runs;
//   - resident memory at the end within 4 MiB (256 under ASan: kRssSlackBytes) of that halfway (past the
//     warm-up: pools, zstd contexts, Bullet and the soil sized on first use);
//     the stations keep no per-tick records, as in `terracut mmt --role`;
//   - every datagram is counted under its reason: each station's counts of
//     each rejection reason equal the hostile endpoint's own account, and
//     its accepted count equals the real datagrams delivered plus the forged
//     valid ones.
#include "mmt_soak.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "../support/peak_memory.hpp"
#include "checking_device.hpp"
#include "terracut/core/error.hpp"
#include "terracut/core/wire.hpp"
#include "terracut/haptics/script_device.hpp"
#include "terracut/haptics/workspace.hpp"
#include "terracut/net/emulated_link.hpp"
#include "terracut/net/enet_transport.hpp"
#include "terracut/net/messages.hpp"
#include "terracut/session/mmt.hpp"
#include "terracut/session/scenario.hpp"

namespace terracut::soak {
namespace {

// How much resident memory may grow from halfway to the end. Under
// AddressSanitizer freed blocks wait in its quarantine (up to 256 MiB by
// default) before they are reused, so resident memory there is no measure
// of a leak: the slack is that quarantine, and LeakSanitizer checks leaks
// at exit instead.
#ifdef TERRACUT_TEST_SANITIZED
constexpr std::int64_t kRssSlackBytes = std::int64_t(256) << 20;
#else
constexpr std::int64_t kRssSlackBytes = std::int64_t(4) << 20;
#endif

double wall_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

using Bytes = std::vector<std::uint8_t>;

// Rewrites a datagram's CRC after its bytes were changed.
void repair_crc(Bytes& d) {
  if (d.size() < net::kHeaderSize + net::kCrcSize) return;
  wire::put_u32(d.data() + d.size() - net::kCrcSize, wire::crc32(d.data(), d.size() - net::kCrcSize));
}

// An outage: nothing either peer sends arrives while it lasts.
struct Outage {
  double until_s = -1.0;
  bool active(double t_s) const { return t_s < until_s; }
};

// The hostile endpoint in front of a station. Passes on what the peer really
// sends (except during an outage), then adds hostile datagrams, keeping the
// account of what the station must make of each.
class HostileEndpoint final : public net::Endpoint {
 public:
  HostileEndpoint(net::Endpoint& inner, bool is_operator, std::uint32_t link_id, GridSpec grid,
                  const Outage& outage, std::uint32_t seed)
      : inner_(inner), operator_(is_operator), link_(link_id), grid_(grid), outage_(outage),
        rng_(seed) {}

  void send(net::Channel channel, const std::uint8_t* data, std::size_t size, double now_s) override {
    inner_.send(channel, data, size, now_s);
  }

  using net::Endpoint::receive;
  void receive(double now_s, net::Inbox& out) override {
    real_.clear();
    inner_.receive(now_s, real_);
    const bool outage = outage_.active(now_s);
    for (auto& d : real_) {
      if (outage) {
        ++dropped;
        continue;
      }
      ++delivered;
      judge_real(d);
      out.push(d.data(), d.size());
    }
    if (uniform() < 0.3) {
      const int n = uniform() < 0.05 ? 1 + int(uniform() * 64) : 1;  // a flood, now and then
      for (int i = 0; i < n; ++i) attack(now_s, outage, out);
    }
  }

  net::RejectCounts expected{};  // the account: what the station must reject, by reason
  std::int64_t delivered = 0;    // real datagrams handed on
  // Real datagrams the transport handed on that the station must reject: a
  // copy, one out of order, or not a datagram of its peer at all (over
  // ENet: bytes of the raw flood taken for one of the peer's packets). The
  // in-memory link never makes one; `real_order` and `real_framing` are
  // their reasons' counts (also in `expected`).
  std::int64_t real_order = 0, real_framing = 0;
  std::string first_anomaly;  // the first of them, described
  std::int64_t forged = 0;       // forged valid ones (must be accepted)
  std::int64_t dropped = 0;      // real ones lost to outages
  std::int64_t hostile = 0;      // hostile datagrams in all

 private:
  double uniform() { return std::uniform_real_distribution<double>(0.0, 1.0)(rng_); }
  int pick(int n) { return std::uniform_int_distribution<int>(0, n - 1)(rng_); }

  // The newest accepted datagram of each type: what the station's sequence
  // filters hold (only delivered real and forged datagrams are accepted).
  struct Last {
    Bytes bytes;
    net::Header header;
  };
  void remember(const net::Header& h, const Bytes& d) {
    Last& l = last_[std::size_t(h.type)];
    l.bytes = d;
    l.header = h;
  }
  // The verdict on a real datagram, from the rule of docs/teleoperation.md
  // restated (a new session is accepted; in the same one a repeated
  // sequence number is a duplicate, an older one reordered, a newer one
  // with an older time stale) against the last accepted datagram of its
  // type; then adds it to the account, or remembers it as accepted.
  void judge_real(const Bytes& d) {
    net::Header h;
    net::Reject verdict = net::decode_header(d.data(), d.size(), link_, h);
    if (verdict == net::Reject::kNone && !received_type(h.type)) verdict = net::Reject::kBadType;
    if (verdict == net::Reject::kNone) {
      const Last& l = last_[std::size_t(h.type)];
      if (!l.bytes.empty() && l.header.session == h.session) {
        const auto ahead = static_cast<std::int32_t>(h.sequence - l.header.sequence);
        if (ahead == 0)
          verdict = net::Reject::kDuplicate;
        else if (ahead < 0)
          verdict = net::Reject::kReordered;
        else if (h.timestamp_ns < l.header.timestamp_ns)
          verdict = net::Reject::kStale;
      }
      if (verdict == net::Reject::kNone) {
        remember(h, d);
        return;
      }
      ++real_order;
    } else {
      ++real_framing;
    }
    expected.add(verdict);
    if (first_anomaly.empty())
      first_anomaly = std::string(net::to_string(verdict)) + " (a real datagram of " + std::to_string(d.size()) +
                      " bytes, sequence " + std::to_string(h.sequence) + ", session " + std::to_string(h.session) +
                      ")";
  }
  bool received_type(net::MessageType t) const {
    return operator_ ? t != net::MessageType::kCommand : t == net::MessageType::kCommand;
  }

  // A valid datagram of type t with the given header fields: forged values.
  Bytes forge(net::MessageType t, net::Header h, bool nan) {
    Bytes d(net::kHeaderSize + 160 + net::kCrcSize);
    const double bad = nan ? (pick(2) ? std::numeric_limits<double>::quiet_NaN()
                                      : std::numeric_limits<double>::infinity())
                           : 0.0;
    switch (t) {
      case net::MessageType::kCommand: {
        net::Command c;
        c.t_s = h.timestamp_ns * 1e-9;
        const double far = uniform() < 0.2 ? 1e6 : 1.0;
        c.pose.position_m = {(uniform() - 0.5) * 3 * far, uniform() * far, (uniform() - 0.5) * 3 * far};
        if (nan) c.pose.position_m.y = bad;
        c.flags = std::uint32_t(pick(2));
        d.resize(net::encode_command(h, c, d.data()));
        break;
      }
      case net::MessageType::kMeasurement: {
        net::Measurement m;
        m.t_s = h.timestamp_ns * 1e-9;
        m.force_world_n = {(uniform() - 0.5) * 1e6, uniform() * 1e6, 0.0};
        m.contact_length_m = uniform();
        if (nan) m.force_world_n.x = bad;
        d.resize(net::encode_measurement(h, m, d.data()));
        break;
      }
      case net::MessageType::kEstimate: {
        net::Estimate e;
        e.t_s = h.timestamp_ns * 1e-9;
        const double scales[] = {1e-6, 0.1, 3.0, 1e3, 1e9};
        e.force_scale = nan ? bad : scales[pick(5)];
        e.samples = 10;
        d.resize(net::encode_estimate(h, e, d.data()));
        break;
      }
      case net::MessageType::kPatch: {
        net::Patch p;
        p.t_s = h.timestamp_ns * 1e-9;
        const int w = 1 + pick(std::min(grid_.cols, 12)), ht = 1 + pick(std::min(grid_.rows, 12));
        const int c0 = pick(grid_.cols - w + 1), r0 = pick(grid_.rows - ht + 1);
        p.rect = {c0, r0, c0 + w, r0 + ht};
        p.heights.resize(std::size_t(w * ht));
        for (float& v : p.heights) v = float((uniform() - 0.3) * 40.0);  // -12 to 28 m
        if (nan) p.heights[std::size_t(pick(w * ht))] = float(bad);
        net::encode_patch(h, p, d);
        break;
      }
    }
    return d;
  }

  // A header of this station's peer: a new session, or the last accepted one's.
  net::Header fresh_header(net::MessageType t, double now_s) {
    net::Header h;
    h.type = t;
    h.link = link_;
    h.session = 0x70000000u + std::uint32_t(pick(1 << 20));
    h.sequence = std::uint32_t(pick(1000));
    h.timestamp_ns = std::uint64_t(std::max(0.0, now_s) * 1e9);
    return h;
  }

  net::MessageType received_kind() {
    if (!operator_) return net::MessageType::kCommand;
    const net::MessageType kinds[] = {net::MessageType::kMeasurement, net::MessageType::kPatch,
                                      net::MessageType::kEstimate};
    return kinds[pick(3)];
  }

  void inject(Bytes d, net::Reject expect, net::Inbox& out) {
    ++hostile;
    if (expect == net::Reject::kNone)
      ++forged;
    else
      expected.add(expect);
    out.push(d.data(), d.size());
  }

  void attack(double now_s, bool outage, net::Inbox& out) {
    const net::MessageType t = received_kind();
    const Last& last = last_[std::size_t(t)];
    // A valid datagram to damage: the last accepted one, or a forged one.
    Bytes base = last.bytes.empty() ? forge(t, fresh_header(t, now_s), false) : last.bytes;
    switch (pick(17)) {
      case 0: {  // random bytes (never starting with the magic)
        Bytes d(std::size_t(pick(200)));
        for (auto& b : d) b = std::uint8_t(pick(256));
        if (d.size() >= 4 && wire::get_u32(d.data()) == net::kMagic) d[0] ^= 1;
        const net::Reject expect = d.size() < 4 ? net::Reject::kTruncated : net::Reject::kBadMagic;
        inject(std::move(d), expect, out);
        break;
      }
      case 1:  // truncated
        base.resize(std::size_t(pick(int(base.size()))));
        inject(std::move(base), net::Reject::kTruncated, out);
        break;
      case 2:  // oversized
        base.resize(base.size() + 1 + std::size_t(pick(3000)), 0xAB);
        inject(std::move(base), net::Reject::kBadLength, out);
        break;
      case 3:
        base[0] ^= 0x5A;
        inject(std::move(base), net::Reject::kBadMagic, out);
        break;
      case 4:
        wire::put_u16(base.data() + 4, std::uint16_t(net::kVersion + 1 + pick(100)));
        repair_crc(base);
        inject(std::move(base), net::Reject::kBadVersion, out);
        break;
      case 5:
        base[net::kHeaderSize + std::size_t(pick(int(base.size() - net::kHeaderSize - net::kCrcSize)))] ^= 0x10;
        inject(std::move(base), net::Reject::kBadChecksum, out);
        break;
      case 6: {  // an unknown type, or a type this station does not receive
        net::MessageType other = operator_ ? net::MessageType::kCommand : net::MessageType::kMeasurement;
        Bytes d = forge(other, fresh_header(other, now_s), false);
        if (pick(2)) {
          wire::put_u16(d.data() + 6, std::uint16_t(5 + pick(1000)));
          repair_crc(d);
        }
        inject(std::move(d), net::Reject::kBadType, out);
        break;
      }
      case 7: {  // foreign: a valid datagram of another link
        wire::put_u32(base.data() + 8, link_ + 1 + std::uint32_t(pick(1000)));
        repair_crc(base);
        inject(std::move(base), net::Reject::kForeign, out);
        break;
      }
      case 8:  // NaN or inf in a field
        inject(forge(t, fresh_header(t, now_s), true), net::Reject::kBadPayload, out);
        break;
      case 9: {  // patches the operator must refuse: huge, over the cap, outside the grid
        if (!operator_) {
          inject(forge(net::MessageType::kPatch, fresh_header(net::MessageType::kPatch, now_s), false),
                 net::Reject::kBadType, out);
          break;
        }
        net::Patch p;
        const int kind = pick(3);
        if (kind == 0 && uniform() < 0.1) {  // 2048 x 2048 zeros: 16 MiB inflated, outside the grid
          p.rect = {0, 0, 2048, 2048};
        } else {  // across the grid's far edge
          p.rect = {grid_.cols - 2, pick(grid_.rows), grid_.cols + 3, 0};
          p.rect.r1 = p.rect.r0 + 1;
        }
        p.heights.assign(std::size_t(p.rect.area()), 0.1f);
        Bytes d;
        net::encode_patch(fresh_header(net::MessageType::kPatch, now_s), p, d);
        if (kind == 1) {  // declares 4096 x 2048 samples: over kMaxPatchSamples
          const std::size_t at = net::kHeaderSize + 8;
          wire::put_u32(d.data() + at, 0);
          wire::put_u32(d.data() + at + 8, 4096);
          wire::put_u32(d.data() + at + 12, 2048);
          wire::put_u32(d.data() + at + 16, 4096u * 2048u * 4u);
          repair_crc(d);
        }
        inject(std::move(d), net::Reject::kBadPayload, out);
        break;
      }
      case 10:  // a replay of the last accepted datagram
        if (!last.bytes.empty()) inject(last.bytes, net::Reject::kDuplicate, out);
        break;
      case 11:
      case 12:  // older sequence number (reordered); newer one, older time (stale)
        if (!last.bytes.empty()) {
          Bytes d = last.bytes;
          const bool reordered = last.header.timestamp_ns < 1000 || pick(2);
          wire::put_u32(d.data() + 16, last.header.sequence + (reordered ? std::uint32_t(-1 - pick(100)) : 1u));
          if (!reordered) wire::put_u64(d.data() + 24, last.header.timestamp_ns - 1000);
          repair_crc(d);
          inject(std::move(d), reordered ? net::Reject::kReordered : net::Reject::kStale, out);
        }
        break;
      case 13:
      case 14:  // forged but valid, of a new session (not during an outage: it would be heard)
        if (!outage) {
          net::Header h = fresh_header(t, now_s);
          Bytes d = forge(t, h, false);
          remember(h, d);
          inject(std::move(d), net::Reject::kNone, out);
        }
        break;
      default:  // a burst of copies of one damaged datagram (bad CRC)
        for (int i = 0, n = 1 + pick(8); i < n; ++i) {
          Bytes d = base;
          d[d.size() - 1] ^= std::uint8_t(1 + pick(255));
          inject(std::move(d), net::Reject::kBadChecksum, out);
        }
        break;
    }
  }

  net::Endpoint& inner_;
  bool operator_;
  std::uint32_t link_;
  GridSpec grid_;
  const Outage& outage_;
  std::mt19937 rng_;
  std::vector<std::vector<std::uint8_t>> real_;
  Last last_[net::kMessageTypeCount];
};

// Random bytes to a UDP port (ENet must drop them before they reach a station).
class RawUdpSender {
 public:
  RawUdpSender() : fd_(::socket(AF_INET, SOCK_DGRAM, 0)) {}
  ~RawUdpSender() {
    if (fd_ >= 0) ::close(fd_);
  }
  void send(int port, std::mt19937& rng) {
    sockaddr_in to{};
    to.sin_family = AF_INET;
    to.sin_port = htons(std::uint16_t(port));
    to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    std::uint8_t d[600];
    const std::size_t n = std::uniform_int_distribution<std::size_t>(0, sizeof d)(rng);
    for (std::size_t i = 0; i < n; ++i) d[i] = std::uint8_t(rng());
    if (::sendto(fd_, d, n, 0, reinterpret_cast<const sockaddr*>(&to), sizeof to) >= 0) ++sent;
  }
  std::int64_t sent = 0;

 private:
  int fd_;
};

}  // namespace

int run_mmt_soak(const MmtSoakOptions& o) {
  const bool enet = o.enet;
  session::Scenario op = session::load_scenario(o.scenario);
  if (!op.mmt) throw InputError(o.scenario.string() + ": mmt: the soak needs a scenario with an mmt: section");
  // The link itself loses and reorders nothing (its delay stays): every
  // rejection then comes from the hostile endpoint, and is accounted for.
  session::MmtSettings s = *op.mmt;
  for (net::LinkConditions* c : {&s.to_remote, &s.to_operator}) {
    c->jitter_s = c->loss = c->reorder = 0.0;
    c->burst = {};
  }
  op.haptics.safety.rise_time_s = std::min(op.haptics.safety.rise_time_s, 0.2);
  const session::Scenario remote_scn = session::load_remote_scenario(op);

  const io::Scenario& b = op.base;
  // The operator's hand: the scenario's cut, over and over.
  const std::unique_ptr<haptics::Device> hand = session::make_operator_device(op, true);
  const double rate_hz = op.base.rate_hz;
  CheckingDevice checker(*hand, op.haptics.safety, rate_hz);

  std::unique_ptr<net::EmulatedLink> memory;
  std::unique_ptr<net::EnetEndpoint> enet_remote, enet_operator;
  std::unique_ptr<net::EmulatedEndpoint> emulated_remote, emulated_operator;
  net::Endpoint* op_link = nullptr;
  net::Endpoint* remote_link = nullptr;
  if (enet) {
    // An authenticated session (secure.hpp) under a key of the seed's.
    net::EnetOptions eo;
    std::mt19937 key_rng(o.seed);
    for (auto& b : eo.key.bytes) b = std::uint8_t(key_rng());
    eo.station_id = 2u;
    enet_remote = net::EnetEndpoint::listen("127.0.0.1", 0, eo);
    eo.station_id = 1u;
    enet_operator = net::EnetEndpoint::connect("127.0.0.1", enet_remote->port(), eo);
    std::vector<std::vector<std::uint8_t>> none;
    const double start = wall_s();
    while (!enet_operator->connected() || !enet_remote->connected()) {
      if (wall_s() - start > 5.0) throw InputError("the ENet stations did not connect on loopback within 5 s");
      enet_operator->receive(0.0, none);
      enet_remote->receive(0.0, none);
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    emulated_remote = std::make_unique<net::EmulatedEndpoint>(*enet_remote, s.to_operator);
    emulated_operator = std::make_unique<net::EmulatedEndpoint>(*enet_operator, s.to_remote);
    op_link = emulated_operator.get();
    remote_link = emulated_remote.get();
  } else {
    memory = std::make_unique<net::EmulatedLink>(s.to_remote, s.to_operator);
    op_link = &memory->a();
    remote_link = &memory->b();
  }
  Outage outage;
  const GridSpec grid = io::grid_spec(b);
  HostileEndpoint op_side(*op_link, true, s.link_id, grid, outage, o.seed);
  HostileEndpoint remote_side(*remote_link, false, s.link_id, grid, outage, o.seed + 7);
  // No per-tick records, as the live stations of `terracut mmt --role`
  // (they stream theirs to a file): memory must not grow at all.
  session::OperatorOptions op_options;
  op_options.keep_records = false;
  session::RemoteOptions remote_options;
  remote_options.keep_records = false;
  session::OperatorStation operator_station(op, s, checker, op_side, 1u, op_options);
  session::RemoteStation remote_station(remote_scn, s, op.base.soil.material,
                                        operator_station.simulation().grid(), remote_side, 2u,
                                        remote_options);

  std::mt19937 rng(o.seed + 13);
  RawUdpSender raw;
  const std::int64_t ticks = std::llround(o.duration_s * rate_hz);
  const double tick_s = 1.0 / rate_hz;
  const SafetyParams& safety = op.haptics.safety;
  int failures = 0;
  auto fail = [&](const std::string& what) {
    if (++failures <= 10) std::fprintf(stderr, "terracut-soak: %s\n", what.c_str());
  };

  double heard_s = 0.0;
  bool accepted_ever = false;
  double last_sample_s = 0.0, trip_s = 0.0, worst_late_trip_s = 0.0;
  std::int64_t trip_tick = 0;
  bool tripped = false;
  std::int64_t trips = 0;
  std::int64_t accepted_before = 0;
  bool waiting_zero = false;  // a silence with a force to cut
  std::vector<double> latencies_s;
  std::int64_t outages = 0;
  double next_outage_s = 0.5 + std::uniform_real_distribution<double>(0.0, 1.0)(rng);
  std::int64_t rss_start = 0;
  double last_tick_s = -1.0;
  const double start = wall_s();
  for (std::int64_t i = 0; i < ticks; ++i) {
    const double t = enet ? wall_s() - start : double(i) * tick_s;
    if (t >= next_outage_s) {  // 0.3-0.8 s of nothing, every 1-3 s
      outage.until_s = t + 0.3 + 0.5 * std::uniform_real_distribution<double>(0.0, 1.0)(rng);
      next_outage_s = outage.until_s + 1.0 + 2.0 * std::uniform_real_distribution<double>(0.0, 1.0)(rng);
      ++outages;
    }
    if (enet && i % 4 == 0) {
      raw.send(enet_remote->port(), rng);
      raw.send(enet_operator->port(), rng);
    }
    if (memory) memory->release(t);
    operator_station.tick(t);
    remote_station.tick(t);
    last_tick_s = t;

    // The watchdog across the link. The operator's device is silent to its
    // loop once the link has been silent for more than timeout_s; the loop's
    // watchdog trips at the first tick more than watchdog_timeout_s after
    // its last sample (later when the ticks themselves run late: counted)
    // and the force must be zero watchdog_ramp_s (+2 ticks) after the trip.
    const std::int64_t accepted = operator_station.counters().accepted;
    const Vec3 f = checker.last_force();
    const bool zero = f.x == 0 && f.y == 0 && f.z == 0;
    if (accepted != accepted_before) {
      heard_s = t;
      waiting_zero = false;
    } else if (t - heard_s > tick_s * 1.5) {
      if (!waiting_zero && !zero && t - heard_s < s.timeout_s) waiting_zero = true;
      if (waiting_zero && zero) {
        latencies_s.push_back(t - heard_s);
        waiting_zero = false;
      }
    }
    if (accepted_ever && t - heard_s > s.timeout_s) {
      if (!tripped && t - last_sample_s > safety.watchdog_timeout_s) {
        tripped = true;
        ++trips;
        trip_s = t;
        trip_tick = i;
        worst_late_trip_s = std::max(worst_late_trip_s, t - last_sample_s - safety.watchdog_timeout_s);
      }
      if (tripped && !zero && t - trip_s > safety.watchdog_ramp_s + 2 * tick_s &&
          double(i - trip_tick) > safety.watchdog_ramp_s * rate_hz + 2) {
        char what[200];
        std::snprintf(what, sizeof what, "t = %.3f s: force %.3g N %.1f ms after the operator last heard the link, "
                      "%.1f ms after the watchdog's trip", t, length(f), (t - heard_s) * 1e3, (t - trip_s) * 1e3);
        fail(what);
      }
    } else {
      last_sample_s = t;
      tripped = false;
    }
    accepted_ever = accepted_ever || accepted > 0;
    accepted_before = accepted;
    if (i == ticks / 2) rss_start = rss_bytes();  // past the warm-up (pools, zstd, Bullet)
    if (enet) {  // paced by the wall clock
      const double next = start + double(i + 1) * tick_s;
      const double wait = next - wall_s();
      if (wait > 0) std::this_thread::sleep_for(std::chrono::duration<double>(wait));
    }
  }
  const std::int64_t rss_end = rss_bytes();
  const double rss_fraction = double(ticks / 2) / double(ticks);

  failures += int(checker.failures);
  auto require = [&](bool ok, const std::string& what) {
    if (!ok) fail(what);
  };
  require(checker.writes == ticks, "the operator's device got " + std::to_string(checker.writes) + " of " +
                                       std::to_string(ticks) + " commands");
  // Both stations ran to the last tick (its record is the newest).
  require(remote_station.last_record().t_s == last_tick_s &&
              operator_station.last_record().t_s == last_tick_s,
          "the stations' last records are not the last tick's (" + std::to_string(last_tick_s) + " s)");
  require(operator_station.records().empty() && remote_station.records().empty(),
          "the stations kept per-tick records");
  require(rss_end - rss_start <= kRssSlackBytes,
          "resident memory grew by " + std::to_string(rss_end - rss_start) + " bytes");
  require(outages > 0 && trips > 0, "no watchdog trip (the outages did not reach the loop)");
  struct Side {
    const char* name;
    const session::StationCounters& counters;
    const HostileEndpoint& hostile;
  };
  const Side sides[] = {{"operator", operator_station.counters(), op_side},
                        {"remote", remote_station.counters(), remote_side}};
  for (const Side& side : sides) {
    for (std::size_t r = 1; r < net::kRejectReasonCount; ++r)
      require(side.counters.rejected.by_reason[r] == side.hostile.expected.by_reason[r],
              std::string(side.name) + " rejected as " + std::string(net::to_string(net::Reject(r))) + ": " +
                  std::to_string(side.counters.rejected.by_reason[r]) + ", the hostile account " +
                  std::to_string(side.hostile.expected.by_reason[r]));
    const std::int64_t real_rejected = side.hostile.real_order + side.hostile.real_framing;
    require(side.counters.accepted == side.hostile.delivered - real_rejected + side.hostile.forged,
            std::string(side.name) + " accepted " + std::to_string(side.counters.accepted) + ", real delivered " +
                std::to_string(side.hostile.delivered) + " - real rejected " + std::to_string(real_rejected) +
                " + forged " + std::to_string(side.hostile.forged));
    // The in-memory link delivers what was sent, once and in order.
    if (!enet)
      require(real_rejected == 0, std::string(side.name) + ": the in-memory link delivered a datagram to reject: " +
                                      side.hostile.first_anomaly);
  }

  std::sort(latencies_s.begin(), latencies_s.end());
  std::printf("terracut-soak --mode %s: %.0f s, seed %u, scenario %s\n", enet ? "mmt-enet" : "mmt", o.duration_s,
              o.seed, o.scenario.filename().c_str());
  std::printf("  ticks %lld of each station (%s), outages %lld\n", static_cast<long long>(ticks),
              enet ? "wall clock, loopback UDP through ENet" : "simulated time, in-memory link",
              static_cast<long long>(outages));
  std::printf("  worst force %.4f N (limit %.4g N)\n", checker.worst_force_n, safety.max_force_n);
  std::printf("  worst force rate %.1f N/s away from [0, previous] (limit %.4g N/s); worst |change| %.1f N/s\n",
              checker.worst_rate_n_per_s, safety.max_force_rate_n_per_s, checker.worst_change_n_per_s);
  std::printf("  watchdog trips %lld; last accepted datagram to zero force: %zu silences with a force, median %.1f ms, worst %.1f ms "
              "(bound: timeout %.0f + watchdog %.0f + ramp %.0f ms)\n",
              static_cast<long long>(trips), latencies_s.size(), latencies_s.empty() ? 0.0 : latencies_s[latencies_s.size() / 2] * 1e3,
              latencies_s.empty() ? 0.0 : latencies_s.back() * 1e3, s.timeout_s * 1e3,
              safety.watchdog_timeout_s * 1e3, safety.watchdog_ramp_s * 1e3);
  std::printf("  latest watchdog trip %.1f ms after timeout_s + watchdog_timeout_s (the ticks' own lateness)\n",
              worst_late_trip_s * 1e3);
  std::printf("  resident memory after %.1f s %.2f MiB, at the end %.2f MiB\n",
              rss_fraction * o.duration_s, double(rss_start) / (1 << 20), double(rss_end) / (1 << 20));
  for (const Side& side : sides) {
    std::printf("  %s: real datagrams delivered %lld (lost to outages %lld), hostile %lld, forged valid %lld, accepted %lld; rejected:",
                side.name, static_cast<long long>(side.hostile.delivered), static_cast<long long>(side.hostile.dropped),
                static_cast<long long>(side.hostile.hostile), static_cast<long long>(side.hostile.forged),
                static_cast<long long>(side.counters.accepted));
    for (std::size_t r = 1; r < net::kRejectReasonCount; ++r)
      std::printf(" %s %lld", std::string(net::to_string(net::Reject(r))).c_str(),
                  static_cast<long long>(side.counters.rejected.by_reason[r]));
    std::printf("\n    real datagrams to reject: out of order or repeated %lld, not the peer's %lld%s%s\n",
                static_cast<long long>(side.hostile.real_order), static_cast<long long>(side.hostile.real_framing),
                side.hostile.first_anomaly.empty() ? "" : "; the first: ", side.hostile.first_anomaly.c_str());
  }
  if (enet) {
    // Every raw datagram counted by the carrier it reached, before a station
    // saw it (the random bytes of one may read as a connection request).
    std::printf("  raw UDP datagrams to the ENet ports: %lld;", static_cast<long long>(raw.sent));
    std::int64_t counted_all = 0;
    for (const net::EnetEndpoint* e : {enet_remote.get(), enet_operator.get()}) {
      const net::EnetCounters& c = e->counters();
      const std::int64_t counted = c.dropped_unknown_source + c.dropped_oversize + c.kernel_dropped +
                                   c.connection_requests;
      counted_all += counted;
      std::printf(" %s counted %lld (no peer's %lld, kernel %lld)", e == enet_remote.get() ? "remote" : "operator",
                  static_cast<long long>(counted), static_cast<long long>(c.dropped_unknown_source),
                  static_cast<long long>(c.kernel_dropped));
    }
    std::printf("\n");
    require(counted_all >= raw.sent, "the carriers counted " + std::to_string(counted_all) + " of " +
                                         std::to_string(raw.sent) + " raw datagrams");
  }
  std::printf("  %s\n", failures == 0 ? "all promises kept" : "PROMISES BROKEN");
  return failures == 0 ? 0 : 1;
}

}  // namespace terracut::soak
