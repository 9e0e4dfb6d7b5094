// Soil materials (presets, dicts of the soil: section's keys), the
// earthmoving equation over numpy arrays, and terracut.ForceModel, the
// haptic rendering of a scenario's haptics: section.
#include <cmath>
#include <string>
#include <vector>

#include "bindings.hpp"
#include "terracut/core/forces.hpp"
#include "terracut/core/format.hpp"
#include "terracut/haptics/settings.hpp"

namespace terracut::python {

// A soil material given as a preset name or a dict of SoilMaterial fields
// (the scenario's soil: keys: angles in degrees, a preset's values replaced
// by the fields given); unknown keys are refused by name.
SoilMaterial material_arg(py::handle obj) {
  const auto preset_of = [](const std::string& name) {
    auto preset = parse_enum<SoilPreset>(name);
    if (!preset)
      throw InputError("soil: unknown preset '" + name + "' (dry_sand, loose_sand, clay or gravel)");
    return soil_preset(*preset);
  };
  if (py::isinstance<py::str>(obj)) return preset_of(obj.cast<std::string>());
  if (!py::isinstance<py::dict>(obj)) throw InputError("soil: expected a preset name or a dict");
  const py::dict d = obj.cast<py::dict>();
  SoilMaterial m = d.contains("preset") ? preset_of(py::str(d["preset"])) : SoilMaterial{};
  for (auto [key, value] : d) {
    const std::string k = py::str(key);
    if (k == "preset") continue;
    if (k == "surcharge_pa")
      throw InputError("soil.surcharge_pa: a surcharge is a load, not the soil's: give it as "
                       "earthmoving_force(..., surcharge_pa=...)");
    double v = 0.0;
    try {
      v = value.cast<double>();
    } catch (py::cast_error&) {
      throw InputError("soil." + k + ": expected a number");
    }
    if (k == "unit_weight_n_per_m3") m.unit_weight_n_per_m3 = v;
    else if (k == "density_kg_per_m3") m.unit_weight_n_per_m3 = v * kStandardGravity_m_per_s2;
    else if (k == "cohesion_pa") m.cohesion_pa = v;
    else if (k == "adhesion_pa") m.adhesion_pa = v;
    else if (k == "internal_friction_deg") m.internal_friction_deg = v;
    else if (k == "soil_tool_friction_deg") m.soil_tool_friction_deg = v;
    else if (k == "repose_deg") m.repose_deg = v;
    else
      throw InputError("soil." + k +
                       ": unknown field (preset, unit_weight_n_per_m3, density_kg_per_m3, "
                       "cohesion_pa, adhesion_pa, internal_friction_deg, soil_tool_friction_deg, "
                       "repose_deg)");
  }
  if (std::string e = validate(m); !e.empty()) throw InputError("soil." + e);
  return m;
}

py::dict material_dict(const SoilMaterial& s) {
  py::dict d;
  d["unit_weight_n_per_m3"] = s.unit_weight_n_per_m3;
  d["density_kg_per_m3"] = s.density_kg_per_m3();
  d["cohesion_pa"] = s.cohesion_pa;
  d["adhesion_pa"] = s.adhesion_pa;
  d["internal_friction_deg"] = s.internal_friction_deg;
  d["soil_tool_friction_deg"] = s.soil_tool_friction_deg;
  d["repose_deg"] = s.repose_deg;
  return d;
}

namespace {

// earthmoving_force over arrays of widths and depths (broadcast by numpy).
py::dict earthmoving_arrays(py::object width, py::object depth, py::object soil,
                            double rake_angle_deg, double surcharge_pa, bool side_failure) {
  EarthmovingParams params;
  params.soil = material_arg(soil);
  params.rake_angle_deg = rake_angle_deg;
  params.side_failure = side_failure;
  if (!(std::isfinite(surcharge_pa) && surcharge_pa >= 0.0))
    throw InputError(must_be("surcharge_pa", "finite and >= 0", surcharge_pa));
  if (std::string e = validate(params); !e.empty()) throw InputError(e);
  py::module_ np = py::module_::import("numpy");
  py::tuple both = np.attr("broadcast_arrays")(doubles(width, "width_m"), doubles(depth, "depth_m"));
  auto w = doubles(np.attr("ascontiguousarray")(both[0]), "width_m");
  auto d = doubles(np.attr("ascontiguousarray")(both[1]), "depth_m");
  std::vector<py::ssize_t> shape(w.shape(), w.shape() + w.ndim());
  py::array_t<double> total(shape), horizontal(shape), vertical(shape), beta(shape), side(shape);
  const py::ssize_t n = w.size();
  {
    const double* pw = w.data();
    const double* pd = d.data();
    double* pt = total.mutable_data();
    double* ph = horizontal.mutable_data();
    double* pv = vertical.mutable_data();
    double* pb = beta.mutable_data();
    double* ps = side.mutable_data();
    py::gil_scoped_release release;
    for (py::ssize_t i = 0; i < n; ++i) {
      const EarthmovingResult r = earthmoving_force(params, pw[i], pd[i], surcharge_pa);
      pt[i] = r.total_n;
      ph[i] = r.horizontal_n;
      pv[i] = r.vertical_n;
      pb[i] = r.beta_rad;
      ps[i] = r.side_total_n;
    }
  }
  py::dict out;
  out["total_n"] = total;
  out["horizontal_n"] = horizontal;
  out["vertical_n"] = vertical;
  out["beta_rad"] = beta;
  out["side_total_n"] = side;
  return out;
}

py::dict force_output_dict(const ForceOutput& o) {
  py::dict d;
  d["world_n"] = tuple3(o.world_n);
  d["device_n"] = tuple3(o.device_n);
  d["cutting_n"] = tuple3(o.cutting_n);
  d["surface_n"] = tuple3(o.surface_n);
  d["penetration_n"] = tuple3(o.penetration_n);
  d["load_n"] = tuple3(o.load_n);
  d["bodies_n"] = tuple3(o.bodies_n);
  d["penetration_m"] = o.surface.penetration_m;
  d["in_contact"] = o.surface.in_contact;
  d["proxy_m"] = tuple3(o.surface.proxy_m);
  return d;
}

}  // namespace

void bind_forces(py::module_& m) {
  // --- Forces ----------------------------------------------------------------
  m.def("soil_preset", [](const std::string& name) { return material_dict(material_arg(py::str(name))); },
        py::arg("name"),
        "A built-in soil material ('dry_sand', 'loose_sand', 'clay', 'gravel'; sources in "
        "docs/forces.md) as a dict: unit_weight_n_per_m3 (N/m^3), density_kg_per_m3, "
        "cohesion_pa, adhesion_pa (Pa), internal_friction_deg, soil_tool_friction_deg, "
        "repose_deg (degrees): the keys of a scenario's soil: section.");
  m.def("earthmoving_force", &earthmoving_arrays, py::arg("width_m"), py::arg("depth_m"),
        py::arg("soil") = "dry_sand", py::arg("rake_angle_deg") = 90.0, py::arg("surcharge_pa") = 0.0,
        py::arg("side_failure") = true,
        "The cutting force (McKyes' earthmoving equation with McKyes & Ali's side crescents "
        "unless side_failure is False) for blades of engaged width width_m (m) at cutting depth "
        "depth_m (m), arrays broadcast, with a surcharge surcharge_pa (Pa) on the soil ahead: "
        "total_n (N, the soil's resultant on the face), horizontal_n (N, resisting motion), "
        "vertical_n (N, positive pushing the blade down), beta_rad (failure-plane angle, rad), "
        "side_total_n (N, the crescents' part of total_n). soil: a preset name or a dict as "
        "soil_preset() gives (missing keys: dry sand's); rake_angle_deg: blade face from the "
        "horizontal, degrees (90: vertical).");

  py::class_<ForceModel>(m, "ForceModel", R"doc(The haptic rendering of a scenario's haptics: section.

It renders the physical force of a step (StepResult.force) on a device: the
cutting model, the low-speed damper, the device's gain, the surface proxy,
the carried load's inertia; world_n in newtons, device_n = world_n *
force_scale. Built once (validated and checked against the device's
limits), then compute() is a pure function of one sample. It never changes
the physical force.)doc")
      .def(py::init([](const PyScenario& s) {
             const haptics::HapticSettings h =
                 haptics::with_derived_fields(s.s->haptics, s.base().blade.length_m,
                                              s.base().rate_hz);
             return ForceModel(h.forces);
           }), py::arg("scenario"))
      .def("compute", [](const ForceModel& f, const StepResult& step, py::object velocity,
                         py::object acceleration, py::object yaw_rate, py::object device_point_m,
                         double surface_y_m) {
            ForceInput in;
            in.physical = step.out.force;
            in.velocity_m_per_s = velocity.is_none() ? step.out.motion.velocity_m_per_s
                                                     : vec3(velocity, "velocity_m_per_s");
            in.acceleration_m_per_s2 = acceleration.is_none()
                                           ? step.out.motion.acceleration_m_per_s2
                                           : vec3(acceleration, "acceleration_m_per_s2");
            in.yaw_rate_rad_per_s = yaw_rate.is_none() ? step.out.motion.yaw_rate_rad_per_s
                                                       : yaw_rate.cast<double>();
            in.contact_length_m = step.out.contact.length_m;
            in.device_point_m = device_point_m.is_none() ? step.out.pose.position_m
                                                         : vec3(device_point_m, "device_point_m");
            in.surface_y_m = surface_y_m;
            return force_output_dict(f.compute(in));
          }, py::arg("step"), py::arg("velocity_m_per_s") = py::none(),
          py::arg("acceleration_m_per_s2") = py::none(), py::arg("yaw_rate_rad_per_s") = py::none(),
          py::arg("device_point_m") = py::none(), py::arg("surface_y_m") = -1e9,
          "The rendering of one step's physical force: at the step's own motion unless a "
          "(device's, filtered) velocity (world m/s), acceleration (m/s^2) or yaw rate (rad/s) "
          "is given; the surface proxy at device_point_m (default the blade centre) over "
          "surface_y_m (world m; the default is far below, no proxy force). Returns world_n, "
          "device_n, cutting_n, surface_n, penetration_n, load_n, bodies_n (N tuples), "
          "penetration_m, in_contact, proxy_m.")
      .def_property_readonly("cutting_model", [](const ForceModel& f) {
            return std::string(to_string(f.params().cutting));
          })
      .def_property_readonly("force_scale", [](const ForceModel& f) { return f.params().force_scale; },
                             "Device newtons per world newton.")
      .def_property_readonly("limited", [](const ForceModel& f) { return f.rendering().any_limited(); },
                             "True when the device check lowered a stiffness or damping.");
}

}  // namespace terracut::python
