// Two-process model-mediated teleoperation: one station per process, over
// UDP (net/enet_transport.hpp), paced by the wall clock at the loop rate.
// The remote listens on mmt.udp (or ADDR:PORT given), the operator
// connects; both apply the scenario's link conditions at their sender.
// Each writes its own per-tick CSV and a summary.json into its folder.
#pragma once

#include <atomic>
#include <filesystem>
#include <iosfwd>
#include <memory>
#include <string>

#include "terracut/net/emulated_link.hpp"
#include "terracut/net/enet_transport.hpp"
#include "terracut/session/mmt.hpp"

namespace terracut::session {

struct ProcessOptions {
  MmtOverrides overrides;
  /// "ADDR:PORT" or "PORT" (IPv4); empty: mmt.udp.
  std::string endpoint;
  std::filesystem::path out;     ///< output folder (created)
  std::ostream* log = nullptr;   ///< one-line messages, or null
  /// The remote ends after this long without commands once it had some, s.
  double remote_idle_end_s = 1.0;
  /// The remote ends after this long in any case, s (0: the operator's
  /// duration + 10 s).
  double remote_max_s = 0.0;
  /// How long the operator waits for the connection, s.
  double connect_timeout_s = 5.0;
};

/// "ADDR:PORT" or "PORT" (then default_address), as --device udp: reads it
/// (haptics/device_option.hpp). Throws InputError naming option on bad text.
std::pair<std::string, int> parse_endpoint(const std::string& text, const std::string& option,
                                           const std::string& default_address);

/// A station's UDP link: the ENet carrier, and the emulator of the
/// scenario's conditions in front of it (what the station sends through).
struct UdpLink {
  std::unique_ptr<net::EnetEndpoint> carrier;
  std::unique_ptr<net::EmulatedEndpoint> endpoint;
};

/// The operator's UDP link: connects to the remote station at endpoint
/// ("ADDR:PORT" or "PORT"; empty: mmt.udp) with the to_remote conditions at
/// the sender, and waits up to timeout_s for the connection. option names
/// the command-line option in errors. Throws InputError (bad text, no
/// answer in time).
UdpLink connect_operator_link(const MmtSettings& s, const std::string& endpoint,
                              const std::string& option, double timeout_s);

/// Runs the remote station (returns the exit code, 0). Throws InputError.
int run_remote_process(const Scenario& op, const ProcessOptions& options);
/// Runs the operator station for its duration. Throws InputError (e.g. no
/// connection within connect_timeout_s).
int run_operator_process(const Scenario& op, const ProcessOptions& options);

}  // namespace terracut::session
