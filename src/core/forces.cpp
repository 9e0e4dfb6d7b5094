// The haptic rendering of the physical force, and its device check.
// Derivations and sources: docs/forces.md.
#include "terracut/core/forces.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "terracut/core/error.hpp"
#include "terracut/core/format.hpp"
#include "terracut/core/ranges.hpp"

namespace terracut {

namespace {

// "FIELD must be ..., got VALUE" for the derived fields, or "".
std::string check_positive(const std::string& field, double value) {
  if (std::isfinite(value) && value > 0.0) return {};
  return must_be(field, "finite and > 0", value);
}

// The ranges of the fields a scenario's haptics.forces sets (the derived
// ones, set by the session, are checked by validate(ForceModelParams) alone).
constexpr Range kRanges[] = {
    {"force_scale", 0.0, kRangeMax, RangeEnds::kOpenLow},
    {"low_speed_damping_n_s_per_m", 0.0, kRangeMax, RangeEnds::kOpenLow},
    {"contact_drag.drag_n_per_m", 0.0, kRangeMax, RangeEnds::kClosed},
    {"contact_drag.viscous_n_s_per_m2", 0.0, kRangeMax, RangeEnds::kClosed},
    {"surface.stiffness_n_per_m", 0.0, kRangeMax, RangeEnds::kOpenLow},
    {"surface.damping_n_s_per_m", 0.0, kRangeMax, RangeEnds::kClosed},
    {"device.max_force_n", 0.0, kRangeMax, RangeEnds::kOpenLow},
    {"device.max_stiffness_n_per_m", 0.0, kRangeMax, RangeEnds::kOpenLow},
    {"device.max_damping_n_s_per_m", 0.0, kRangeMax, RangeEnds::kOpenLow},
    {"device.inherent_damping_n_s_per_m", 0.0, kRangeMax, RangeEnds::kOpenLow},
};

// The check of field (its name in its own struct) by its entry at
// struct_path + field: "FIELD must be ..., got VALUE" or "".
std::string check_entry(std::string_view struct_path, std::string_view field, double value) {
  const Range& r = find_range(kRanges, std::string(struct_path) + std::string(field));
  return check(r, value, field);
}

// Prefixes a sub-structure's message with its field name.
std::string nested(const std::string& prefix, const std::string& message) {
  return message.empty() ? message : prefix + "." + message;
}

std::string validate(const ContactDragParams& params) {
  if (auto m = check_entry("contact_drag.", "drag_n_per_m", params.drag_n_per_m); !m.empty())
    return m;
  return check_entry("contact_drag.", "viscous_n_s_per_m2", params.viscous_n_s_per_m2);
}

std::string validate(const SurfaceParams& params) {
  if (auto m = check_entry("surface.", "stiffness_n_per_m", params.stiffness_n_per_m); !m.empty())
    return m;
  return check_entry("surface.", "damping_n_s_per_m", params.damping_n_s_per_m);
}

}  // namespace

std::string validate(const DeviceLimits& limits) {
  constexpr std::string_view at = "device.";
  if (auto m = check_entry(at, "max_force_n", limits.max_force_n); !m.empty()) return m;
  if (auto m = check_entry(at, "max_stiffness_n_per_m", limits.max_stiffness_n_per_m); !m.empty())
    return m;
  if (auto m = check_entry(at, "max_damping_n_s_per_m", limits.max_damping_n_s_per_m); !m.empty())
    return m;
  return check_entry(at, "inherent_damping_n_s_per_m", limits.inherent_damping_n_s_per_m);
}

double passive_stiffness_limit_n_per_m(double inherent_damping_n_s_per_m,
                                       double virtual_damping_n_s_per_m, double rate_hz) noexcept {
  return 2.0 * (inherent_damping_n_s_per_m - std::abs(virtual_damping_n_s_per_m)) * rate_hz;
}

std::string validate(const ForceModelParams& params) {
  if (auto m = nested("contact_drag", validate(params.contact_drag)); !m.empty()) return m;
  if (auto m = nested("surface", validate(params.surface)); !m.empty()) return m;
  if (auto m = check_entry("", "low_speed_damping_n_s_per_m", params.low_speed_damping_n_s_per_m);
      !m.empty())
    return m;
  if (auto m = check_entry("", "force_scale", params.force_scale); !m.empty()) return m;
  if (auto m = check_positive("workspace_scale", params.workspace_scale); !m.empty()) return m;
  if (auto m = check_positive("max_contact_length_m", params.max_contact_length_m); !m.empty())
    return m;
  if (std::string e = check(kRateRange, params.loop_rate_hz, "loop_rate_hz"); !e.empty()) return e;
  return nested("device", validate(params.device));
}

std::span<const Range> force_ranges() { return kRanges; }

ForceModel::ForceModel(const ForceModelParams& params) : requested_(params), params_(params) {
  if (auto m = validate(params); !m.empty()) throw InputError(m);
  const bool refuse = params.policy == LimitPolicy::kRefuse;
  const DeviceLimits& dev = params.device;
  // World N/m (or N s/m) -> device N/m (or N s/m).
  const double gain = params.force_scale * params.workspace_scale;
  const std::string scaling = " (x force_scale " + format_number(params.force_scale) +
                              " x workspace_scale " + format_number(params.workspace_scale) + ")";

  // Surface: damping within the device's figure, then stiffness within both
  // the device's figure and Colgate & Brown's passivity bound for that damping.
  if (params.surface_enabled) {
    double damping = params.surface.damping_n_s_per_m * gain;
    check_.requested_surface_damping_n_s_per_m = damping;
    check_.requested_surface_stiffness_n_per_m = params.surface.stiffness_n_per_m * gain;
    if (damping > dev.max_damping_n_s_per_m) {
      if (refuse) {
        throw InputError("surface.damping_n_s_per_m = " +
                         format_number(params.surface.damping_n_s_per_m) + " N s/m (world) is " +
                         format_number(damping) + " N s/m on the device" + scaling +
                         ", above device.max_damping_n_s_per_m = " +
                         format_number(dev.max_damping_n_s_per_m));
      }
      damping = dev.max_damping_n_s_per_m;
      params_.surface.damping_n_s_per_m = damping / gain;
      check_.surface_damping_limited = true;
    }
    if (!refuse && damping >= dev.inherent_damping_n_s_per_m) {
      // No stiffness would be passive: halve the budget between damping and stiffness.
      damping = 0.5 * dev.inherent_damping_n_s_per_m;
      params_.surface.damping_n_s_per_m = damping / gain;
      check_.surface_damping_limited = true;
    }
    double passive = passive_stiffness_limit_n_per_m(dev.inherent_damping_n_s_per_m, damping,
                                                     params.loop_rate_hz);
    if (!(passive > 0.0)) {
      throw InputError("surface.damping_n_s_per_m = " +
                       format_number(params_.surface.damping_n_s_per_m) + " N s/m (world) is " +
                       format_number(damping) + " N s/m on the device" + scaling +
                       ", not below device.inherent_damping_n_s_per_m = " +
                       format_number(dev.inherent_damping_n_s_per_m) +
                       ": no stiffness is passive (Colgate & Brown: b > K T / 2 + |B|)");
    }
    double limit = std::min(dev.max_stiffness_n_per_m, passive);
    double stiffness = params.surface.stiffness_n_per_m * gain;
    if (stiffness > limit) {
      if (refuse) {
        throw InputError(
            "surface.stiffness_n_per_m = " + format_number(params.surface.stiffness_n_per_m) +
            " N/m (world) is " + format_number(stiffness) + " N/m on the device" + scaling +
            ", above the limit " + format_number(limit) +
            " N/m = min(device.max_stiffness_n_per_m = " +
            format_number(dev.max_stiffness_n_per_m) + ", passivity 2 (b - |B|) / T = 2 (" +
            format_number(dev.inherent_damping_n_s_per_m) + " - " + format_number(damping) +
            ") * " + format_number(params.loop_rate_hz) + " Hz = " + format_number(passive) +
            ") (Colgate & Brown 1994)");
      }
      stiffness = limit;
      params_.surface.stiffness_n_per_m = limit / gain;
      check_.surface_stiffness_limited = true;
    }
    check_.surface_stiffness_n_per_m = stiffness;
    check_.surface_damping_n_s_per_m = damping;
    check_.passive_stiffness_n_per_m = passive;
  }

  // Cutting: the low-speed slope (and the viscous term at the longest
  // contact) is a virtual damping, within the device's figure. The same
  // slope regularises penetration and twist.
  if (params.cutting != CuttingModel::kNone) {
    double viscous = params.cutting == CuttingModel::kContactDrag
                         ? params.contact_drag.viscous_n_s_per_m2 * params.max_contact_length_m
                         : 0.0;
    double damping = (params.low_speed_damping_n_s_per_m + viscous) * gain;
    check_.requested_cutting_damping_n_s_per_m = damping;
    if (damping > dev.max_damping_n_s_per_m) {
      if (refuse) {
        throw InputError(
            "low_speed_damping_n_s_per_m = " + format_number(params.low_speed_damping_n_s_per_m) +
            " N s/m (world)" +
            (viscous > 0.0 ? " + contact_drag.viscous_n_s_per_m2 * max_contact_length_m = " +
                                 format_number(viscous)
                           : std::string()) +
            " is " + format_number(damping) + " N s/m on the device" + scaling +
            ", above device.max_damping_n_s_per_m = " + format_number(dev.max_damping_n_s_per_m));
      }
      // Scale the whole soil force, not its low-speed slope alone: a lower
      // slope alone would make the force velocity-bound (min(k L, beta |v|)
      // = beta |v| at ordinary speeds), flat whatever the contact.
      check_.cutting_gain = dev.max_damping_n_s_per_m / damping;
      damping = dev.max_damping_n_s_per_m;
      check_.cutting_damping_limited = true;
    }
    check_.cutting_damping_n_s_per_m = damping;
  }
}

std::vector<std::string> ForceModel::limit_changes() const {
  std::vector<std::string> out;
  const RenderingCheck& c = check_;
  auto line = [](const std::string& what, double world_from, double world_to, double device_from,
                 double device_to, const std::string& unit) {
    return what + " " + format_number(world_from) + " -> " + format_number(world_to) + " " + unit +
           " (world; " + format_number(device_from) + " -> " + format_number(device_to) + " " +
           unit + " on the device)";
  };
  if (c.surface_stiffness_limited)
    out.push_back(line("surface stiffness", requested_.surface.stiffness_n_per_m,
                       params_.surface.stiffness_n_per_m, c.requested_surface_stiffness_n_per_m,
                       c.surface_stiffness_n_per_m, "N/m"));
  if (c.surface_damping_limited)
    out.push_back(line("surface damping", requested_.surface.damping_n_s_per_m,
                       params_.surface.damping_n_s_per_m, c.requested_surface_damping_n_s_per_m,
                       c.surface_damping_n_s_per_m, "N s/m"));
  if (c.cutting_damping_limited)
    out.push_back(line("cutting damping", params_.low_speed_damping_n_s_per_m,
                       params_.low_speed_damping_n_s_per_m * c.cutting_gain,
                       c.requested_cutting_damping_n_s_per_m, c.cutting_damping_n_s_per_m,
                       "N s/m") +
                  ": the rendered soil force x " + format_number(c.cutting_gain));
  return out;
}

ForceOutput ForceModel::compute(const ForceInput& input) const noexcept {
  ForceOutput out;
  const ToolForce& phys = input.physical;
  const Vec3 v = input.velocity_m_per_s;
  const double beta = params_.low_speed_damping_n_s_per_m;
  if (params_.surface_enabled) {
    out.surface = surface_force(params_.surface, input.device_point_m, v, input.surface_y_m);
    out.surface_n = out.surface.force_n;
  }
  switch (params_.cutting) {
    case CuttingModel::kNone:
      break;
    case CuttingModel::kContactDrag:
      out.cutting_n = contact_drag_force(params_.contact_drag, input.contact_length_m, v, beta);
      out.cutting_uncapped_n = params_.contact_drag.drag_n_per_m * std::max(input.contact_length_m, 0.0);
      out.cutting_cap_n = beta * length(v);
      break;
    case CuttingModel::kEarthmoving:
      // The physical H and V (the pile's surcharge in them), along the
      // device's motion and under its low-speed cap.
      out.cutting_n = earthmoving_world_force(phys.earthmoving, v, beta);
      out.cutting_uncapped_n = std::abs(phys.earthmoving.horizontal_n);
      out.cutting_cap_n = beta * std::hypot(v.x, v.z);
      break;
  }
  if (params_.cutting != CuttingModel::kNone) {
    if (params_.penetration_enabled)
      out.penetration_n = penetration_world_force(phys.penetration, v, beta);
    if (params_.twist_enabled && input.yaw_rate_rad_per_s != 0.0 && phys.twist.engaged_length_m > 0.0) {
      // The soil's resistance per metre of edge: the drag per metre of
      // contact, or the physical cutting force per metre at the parts' depth.
      const double per_m = params_.cutting == CuttingModel::kContactDrag
                               ? params_.contact_drag.drag_n_per_m
                               : phys.twist_resistance_n_per_m;
      const TwistResult t = twist_resistance(per_m, phys.twist, input.yaw_rate_rad_per_s, beta,
                                             params_.max_contact_length_m);
      out.twist_torque_n_m = t.torque_n_m;
      out.twist_n = phys.edge_normal * t.net_force_n;
    }
    // A device that cannot render the cutting damping gets the whole soil
    // force scaled (RenderingCheck::cutting_gain).
    const double k = check_.cutting_gain;
    if (k != 1.0) {
      out.cutting_n = out.cutting_n * k;
      out.cutting_uncapped_n *= k;
      out.cutting_cap_n *= k;
      out.penetration_n = out.penetration_n * k;
      out.twist_n = out.twist_n * k;
      out.twist_torque_n_m *= k;
    }
  }
  // The carried load: its weight, and its mass against the device's
  // (filtered) acceleration; the rigid bodies' push as the step gave it.
  out.load_n = Vec3{0.0, -phys.load_mass_kg * kStandardGravity_m_per_s2, 0.0} +
               input.acceleration_m_per_s2 * (-phys.load_mass_kg);
  out.bodies_n = phys.bodies_n;
  out.world_n = out.cutting_n + out.penetration_n + out.twist_n + out.surface_n + out.load_n + out.bodies_n;
  out.device_n = out.world_n * params_.force_scale;
  return out;
}

}  // namespace terracut
