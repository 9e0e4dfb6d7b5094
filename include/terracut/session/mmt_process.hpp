// Two-process model-mediated teleoperation: one station per process, over
// UDP (net/enet_transport.hpp: authenticated sessions), paced by the wall
// clock at the loop rate. The remote listens on mmt.udp (or ADDR:PORT
// given), the operator connects; both apply the scenario's link conditions
// at their sender (net/emulated_link.hpp). Each writes its own per-tick CSV,
// its final terrain and a summary.json into its folder; the report
// (write_two_process_report) compares the two stations' records as the
// single-process run does.
//
// Lifetimes (docs/teleoperation.md, "Lifetimes and exit codes"):
//  - the remote runs until its operator ends the session, --duration, or a
//    stop request (SIGINT, SIGTERM); it waits for an operator that connects
//    late, and for one that lost its link to come back;
//  - the operator runs its path, then a measured round trip, a sensing
//    period and a blend for the last updates to land (or --duration), and
//    ends the session; when nothing is heard for mmt.link_lost_s it ends
//    early (the force has faded out) with kExitLinkLost;
//  - both summaries say how the session ended.
#pragma once

#include <atomic>
#include <filesystem>
#include <iosfwd>
#include <memory>
#include <string>

#include "terracut/net/emulated_link.hpp"
#include "terracut/net/enet_transport.hpp"
#include "terracut/net/secure.hpp"
#include "terracut/session/mmt.hpp"

namespace terracut::session {

/// Exit code of a station whose link died: nothing heard for
/// mmt.link_lost_s (operator), the session's operator lost and never back
/// (remote), or the session ended by the other side before its time
/// (operator). The outputs are written.
inline constexpr int kExitLinkLost = 4;

struct ProcessOptions {
  MmtOverrides overrides;  ///< duration_s: the remote's lifetime, the operator's run length
  /// "ADDR:PORT" or "PORT" (IPv4); empty: mmt.udp.
  std::string endpoint;
  std::filesystem::path out;     ///< output folder (created)
  std::ostream* log = nullptr;   ///< one-line progress messages, or null
  std::ostream* warn = nullptr;  ///< warnings and how the link ended (stderr), or null
  /// The pre-shared key; net::insecure_key() for --insecure-loopback.
  net::LinkKey key;
  /// Operator: the script device replays its cut over and over (a soak;
  /// with overrides.duration_s).
  bool repeat = false;
  /// How long the operator waits for the remote to accept it, s.
  double connect_timeout_s = 5.0;
  /// Set (by a signal handler) to end the station at its next tick; may be null.
  const std::atomic<bool>* stop = nullptr;
};

/// "ADDR:PORT" or "PORT" (then default_address), as --device udp: reads it
/// (haptics/device_option.hpp). Throws InputError naming option on bad text.
std::pair<std::string, int> parse_endpoint(const std::string& text, const std::string& option,
                                           const std::string& default_address);

/// Whether an IPv4 address (text) is a loopback one (127.0.0.0/8), where
/// --insecure-loopback is allowed.
bool is_loopback(const std::string& address);

/// A station's UDP link: the ENet carrier, and the emulator of the
/// scenario's conditions in front of it (what the station sends through).
struct UdpLink {
  std::unique_ptr<net::EnetEndpoint> carrier;
  std::unique_ptr<net::EmulatedEndpoint> endpoint;
};

/// The carrier's options for a station of these settings: the key, the
/// station's id, and the silence after which another operator may open a
/// session (mmt.link_lost_s).
net::EnetOptions udp_options(const MmtSettings& s, const net::LinkKey& key, std::uint32_t station_id);

/// The operator's UDP link: connects to the remote station at endpoint
/// ("ADDR:PORT" or "PORT"; empty: mmt.udp) with the to_remote conditions at
/// the sender, and waits up to timeout_s for the authenticated session.
/// option names the command-line option in errors. Throws InputError (bad
/// text, an insecure key off loopback, refused by the remote and why, no
/// answer in time).
UdpLink connect_operator_link(const MmtSettings& s, const std::string& endpoint,
                              const std::string& option, double timeout_s,
                              const net::LinkKey& key, std::uint32_t station_id);

/// The link's key from the command line: the key file (--key), else the
/// environment variable TERRACUT_MMT_KEY, else net::insecure_key() when
/// insecure_loopback (--insecure-loopback) says so. Throws InputError naming
/// what to give when there is none, or both a key and the flag.
net::LinkKey link_key(const std::string& key_file, bool insecure_loopback);

/// A fresh station id (the operator's is also its message session).
std::uint32_t new_station_id();

/// Runs the remote station; returns 0, or kExitLinkLost when the session's
/// operator was lost and had not come back at the end. Throws InputError.
int run_remote_process(const Scenario& op, const ProcessOptions& options);
/// Runs the operator station; returns 0, or kExitLinkLost when its link
/// died. Throws InputError (e.g. no session within connect_timeout_s).
int run_operator_process(const Scenario& op, const ProcessOptions& options);

/// The comparison of a two-process session from the two stations' folders
/// (operator.csv, remote.csv, heights.npy / surface.npy and their
/// summary.json): summary.json with the single-process run's figures,
/// operator.csv, remote.csv and terrain_error.csv into out. Throws
/// InputError naming the file that is missing or malformed.
MmtSummary write_two_process_report(const std::filesystem::path& operator_dir,
                                    const std::filesystem::path& remote_dir,
                                    const std::filesystem::path& out);

}  // namespace terracut::session
