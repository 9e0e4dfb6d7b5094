// The haptic session's settings: names and checks. See settings.hpp.
#include "terracut/haptics/settings.hpp"

#include <cmath>

#include "terracut/core/format.hpp"

namespace terracut::haptics {

namespace {

// The ranges of HapticSettings' own numbers (forces and safety have theirs,
// core/forces.hpp and core/safety.hpp). velocity_cutoff_hz must also be
// below the loop's rate / 2, which LoopParams checks.
constexpr Range kRanges[] = {
    {"duration_s", 0.0, 86400.0, RangeEnds::kOpenLow},
    {"settle_s", 0.0, 3600.0, RangeEnds::kClosed},
    {"workspace.scale", 0.0, kRangeMax, RangeEnds::kOpenLow},
    {"workspace.yaw_deg", -360.0, 360.0, RangeEnds::kClosed},
    {"velocity_cutoff_hz", 0.0, 5000.0, RangeEnds::kOpenHigh},
    {"hand.mass_kg", 0.0, kRangeMax, RangeEnds::kOpenLow},
    {"hand.stiffness_n_per_m", 0.0, kRangeMax, RangeEnds::kOpenLow},
    {"hand.damping_n_s_per_m", 0.0, kRangeMax, RangeEnds::kClosed},
    {"hand.substeps", 1, 1000, RangeEnds::kClosed, true},
    {"udp.port", 1, 65535, RangeEnds::kClosed, true},
};

std::string check(std::string_view field, double value) {
  return terracut::check(find_range(kRanges, field), value);
}

}  // namespace

std::string validate(const HapticSettings& s) {
  std::string m;
  if (s.device != DeviceKind::kScript && s.device != DeviceKind::kSim &&
      s.device != DeviceKind::kUdp)
    return "device must be script, sim or udp";
  if (s.duration_s && !(m = check("duration_s", *s.duration_s)).empty()) return m;
  if (!(m = check("settle_s", s.settle_s)).empty()) return m;
  if (!(m = check("workspace.scale", s.workspace.scale)).empty()) return m;
  if (!is_finite(s.workspace.offset_m)) return "workspace.offset_m must be finite";
  if (!(m = check("workspace.yaw_deg", s.workspace.yaw_deg)).empty()) return m;
  if (s.tool_rotation_deg && !is_finite(*s.tool_rotation_deg))
    return "tool.rotation_deg must be finite";
  if (!(m = check("velocity_cutoff_hz", s.velocity_cutoff_hz)).empty()) return m;
  if (s.surface_reference != SurfaceReference::kGround &&
      s.surface_reference != SurfaceReference::kTerrain)
    return "surface_reference must be ground or terrain";
  if (std::string f = validate(s.forces); !f.empty()) return "forces." + f;
  if (std::string f = validate(s.safety); !f.empty()) return "safety." + f;
  if (s.safety.max_force_n > s.forces.device.max_force_n)
    return "safety.max_force_n must not exceed forces.device.max_force_n = " +
           format_number(s.forces.device.max_force_n) + ", got " +
           format_number(s.safety.max_force_n);
  const SimHandParams& h = s.hand;
  if (!(m = check("hand.mass_kg", h.mass_kg)).empty()) return m;
  if (!(m = check("hand.stiffness_n_per_m", h.stiffness_n_per_m)).empty()) return m;
  if (!(m = check("hand.damping_n_s_per_m", h.damping_n_s_per_m)).empty()) return m;
  if (!(m = check("hand.substeps", h.substeps)).empty()) return m;
  if (!is_finite(h.start_offset_m)) return "hand.start_offset_m must be finite";
  if (s.udp.address.empty()) return "udp.address must not be empty";
  if (!(m = check("udp.port", s.udp.port)).empty()) return m;
  return {};
}

std::span<const Range> haptic_settings_ranges() { return kRanges; }

HapticSettings with_derived_fields(HapticSettings settings, double blade_length_m,
                                   double rate_hz) {
  settings.forces.workspace_scale = settings.workspace.scale;
  settings.forces.loop_rate_hz = rate_hz;
  settings.forces.max_contact_length_m = blade_length_m;
  return settings;
}

}  // namespace terracut::haptics
