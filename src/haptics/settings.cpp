// The haptic session's settings: names and checks. See settings.hpp.
#include "terracut/haptics/settings.hpp"

#include <cmath>

#include "terracut/core/format.hpp"

namespace terracut::haptics {

std::string_view to_string(DeviceKind kind) {
  switch (kind) {
    case DeviceKind::kScript:
      return "script";
    case DeviceKind::kSim:
      return "sim";
    case DeviceKind::kUdp:
      return "udp";
  }
  return "unknown";
}

std::optional<DeviceKind> parse_device_kind(std::string_view name) {
  if (name == "script") return DeviceKind::kScript;
  if (name == "sim") return DeviceKind::kSim;
  if (name == "udp") return DeviceKind::kUdp;
  return std::nullopt;
}

std::string_view to_string(SurfaceReference reference) {
  return reference == SurfaceReference::kGround ? "ground" : "terrain";
}

std::optional<SurfaceReference> parse_surface_reference(std::string_view name) {
  if (name == "ground") return SurfaceReference::kGround;
  if (name == "terrain") return SurfaceReference::kTerrain;
  return std::nullopt;
}

std::string_view to_string(CutDepthMeasure measure) {
  return measure == CutDepthMeasure::kAhead ? "ahead" : "section";
}

std::optional<CutDepthMeasure> parse_cut_depth_measure(std::string_view name) {
  if (name == "ahead") return CutDepthMeasure::kAhead;
  if (name == "section") return CutDepthMeasure::kSection;
  return std::nullopt;
}

namespace {
// "FIELD must be WHAT, got VALUE" when ok is false, else "".
template <MessageNumber T>
std::string haptic_check(bool ok, const char* field, const char* what, T value) {
  if (ok) return {};
  return must_be(field, what, value);
}
}  // namespace

std::string validate(const HapticSettings& s) {
  const auto finite = [](double v) { return std::isfinite(v); };
  std::string m;
  if (!(m = haptic_check(finite(s.rate_hz) && s.rate_hz >= 10.0 && s.rate_hz <= 10000.0, "rate_hz",
                         "finite and in [10, 10000]", s.rate_hz))
           .empty())
    return m;
  if (s.device != DeviceKind::kScript && s.device != DeviceKind::kSim &&
      s.device != DeviceKind::kUdp)
    return "device must be script, sim or udp";
  if (s.duration_s &&
      !(m = haptic_check(finite(*s.duration_s) && *s.duration_s > 0.0 && *s.duration_s <= 86400.0,
                         "duration_s", "finite and in (0, 86400]", *s.duration_s))
           .empty())
    return m;
  if (!(m = haptic_check(finite(s.settle_s) && s.settle_s >= 0.0 && s.settle_s <= 3600.0,
                         "settle_s", "finite and in [0, 3600]", s.settle_s))
           .empty())
    return m;
  if (!(m = haptic_check(finite(s.workspace.scale) && s.workspace.scale > 0.0, "workspace.scale",
                         "finite and > 0", s.workspace.scale))
           .empty())
    return m;
  if (!is_finite(s.workspace.offset_m)) return "workspace.offset_m must be finite";
  if (!(m = haptic_check(finite(s.workspace.yaw_deg) && std::abs(s.workspace.yaw_deg) <= 360.0,
                         "workspace.yaw_deg", "finite and in [-360, 360]", s.workspace.yaw_deg))
           .empty())
    return m;
  if (s.tool_rotation_deg && !is_finite(*s.tool_rotation_deg))
    return "tool.rotation_deg must be finite";
  if (!(m = haptic_check(finite(s.velocity_cutoff_hz) && s.velocity_cutoff_hz >= 0.0 &&
                             s.velocity_cutoff_hz < s.rate_hz / 2.0,
                         "velocity_cutoff_hz", "finite, >= 0 and below rate_hz / 2",
                         s.velocity_cutoff_hz))
           .empty())
    return m;
  if (s.surface_reference != SurfaceReference::kGround &&
      s.surface_reference != SurfaceReference::kTerrain)
    return "surface_reference must be ground or terrain";
  if (s.cut_depth != CutDepthMeasure::kAhead && s.cut_depth != CutDepthMeasure::kSection)
    return "cut_depth must be ahead or section";
  if (std::string f = validate(s.forces); !f.empty()) return "forces." + f;
  if (std::string f = validate(s.safety); !f.empty()) return "safety." + f;
  if (s.safety.max_force_n > s.forces.device.max_force_n)
    return "safety.max_force_n must not exceed forces.device.max_force_n = " +
           format_number(s.forces.device.max_force_n) + ", got " +
           format_number(s.safety.max_force_n);
  const SimHandParams& h = s.hand;
  if (!(m = haptic_check(finite(h.mass_kg) && h.mass_kg > 0.0, "hand.mass_kg", "finite and > 0",
                         h.mass_kg))
           .empty())
    return m;
  if (!(m = haptic_check(finite(h.stiffness_n_per_m) && h.stiffness_n_per_m > 0.0,
                         "hand.stiffness_n_per_m", "finite and > 0", h.stiffness_n_per_m))
           .empty())
    return m;
  if (!(m = haptic_check(finite(h.damping_n_s_per_m) && h.damping_n_s_per_m >= 0.0,
                         "hand.damping_n_s_per_m", "finite and >= 0", h.damping_n_s_per_m))
           .empty())
    return m;
  if (!(m = haptic_check(h.substeps >= 1 && h.substeps <= 1000, "hand.substeps", "in [1, 1000]",
                         h.substeps))
           .empty())
    return m;
  if (!is_finite(h.start_offset_m)) return "hand.start_offset_m must be finite";
  if (s.udp.address.empty()) return "udp.address must not be empty";
  if (!(m = haptic_check(s.udp.port >= 1 && s.udp.port <= 65535, "udp.port", "in [1, 65535]",
                         s.udp.port))
           .empty())
    return m;
  return {};
}

HapticSettings with_derived_fields(HapticSettings settings, double blade_length_m) {
  settings.forces.workspace_scale = settings.workspace.scale;
  settings.forces.loop_rate_hz = settings.rate_hz;
  settings.forces.max_contact_length_m = blade_length_m;
  return settings;
}

}  // namespace terracut::haptics
