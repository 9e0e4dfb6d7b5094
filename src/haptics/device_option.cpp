// Parsing --device and --connect values. See device_option.hpp.
#include "terracut/haptics/device_option.hpp"

#include <algorithm>
#include <string>

#include "terracut/core/error.hpp"

namespace terracut::haptics {

void parse_endpoint(std::string_view text, std::string_view option,
                    std::optional<std::string>& address, std::optional<int>& port) {
  const auto fail = [&](const std::string& what) -> void {
    throw InputError(std::string(option) + ": '" + std::string(text) + "': " + what);
  };
  std::string_view port_text = text;
  if (!text.empty() && text.front() == '[') {
    const std::size_t close = text.find(']');
    if (close == std::string_view::npos || close + 1 >= text.size() || text[close + 1] != ':')
      fail("expected [IPV6]:PORT");
    address = std::string(text.substr(1, close - 1));
    port_text = text.substr(close + 2);
  } else if (const std::size_t colon = text.rfind(':'); colon != std::string_view::npos) {
    address = std::string(text.substr(0, colon));
    port_text = text.substr(colon + 1);
    if (address->empty()) fail("the address before ':' is empty");
  }
  if (port_text.empty() || port_text.size() > 5 ||
      !std::all_of(port_text.begin(), port_text.end(), [](char c) { return c >= '0' && c <= '9'; }))
    fail("the port must be a number in [0, 65535]");
  const int p = std::stoi(std::string(port_text));
  if (p > 65535) fail("the port must be a number in [0, 65535]");
  port = p;
}

DeviceOption parse_device_option(std::string_view text) {
  DeviceOption d;
  const std::string_view head = text.substr(0, text.find(':'));
  const std::optional<DeviceKind> kind = parse_enum<DeviceKind>(head);
  if (!kind)
    throw InputError("--device: unknown device '" + std::string(text) +
                     "'; allowed: script, sim, udp, udp:PORT, udp:ADDR:PORT");
  d.kind = *kind;
  if (head.size() == text.size()) return d;
  if (d.kind != DeviceKind::kUdp)
    throw InputError("--device: '" + std::string(text) + "': only udp takes an address");
  parse_endpoint(text.substr(head.size() + 1), "--device", d.address, d.port);
  return d;
}

}  // namespace terracut::haptics
