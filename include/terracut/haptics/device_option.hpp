// The text forms of a device endpoint on the command line: --device of
// `terracut haptics` and --connect of terracut-device.
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "terracut/haptics/settings.hpp"

namespace terracut::haptics {

/// A parsed --device value: "script", "sim", "udp", "udp:PORT",
/// "udp:ADDR:PORT" or "udp:[IPV6]:PORT".
struct DeviceOption {
  DeviceKind kind = DeviceKind::kSim;
  std::optional<std::string> address;  ///< given with udp
  std::optional<int> port;             ///< given with udp, in [0, 65535] (0: any free port)
};
/// Throws InputError naming --device when the text is none of the forms above.
DeviceOption parse_device_option(std::string_view text);

/// Parses "ADDR:PORT", "PORT" or "[IPV6]:PORT" (the part after "udp:"), for
/// --device and terracut-device's --connect. Throws InputError naming option.
void parse_endpoint(std::string_view text, std::string_view option,
                    std::optional<std::string>& address, std::optional<int>& port);

}  // namespace terracut::haptics
