// Calibration of a soil material (terracut::validation): from material
// tests (`terracut calibrate --tests`) and from a force record along a known
// path (`terracut calibrate --record`).
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "bindings.hpp"
#include "terracut/validation/calibrate.hpp"

namespace terracut::python {
namespace {

// A calibration as a dict: material (the scenario's soil: keys), fields
// (name, value, uncertainty, how), rms_residual, rms_relative, evaluations,
// notes.
py::dict calibration_dict(const validation::Calibration& c) {
  py::dict d;
  d["material"] = material_dict(c.material);
  py::list fields;
  for (const validation::FittedField& f : c.fields) {
    py::dict x;
    x["name"] = f.name;
    x["value"] = f.value;
    x["uncertainty"] = f.uncertainty;
    x["how"] = f.how;
    fields.append(x);
  }
  d["fields"] = fields;
  d["rms_residual"] = c.rms_residual;
  d["rms_relative"] = c.rms_relative;
  d["evaluations"] = c.evaluations;
  d["notes"] = c.notes;
  d["soil_yaml"] = validation::material_yaml(c.material);
  return d;
}

// Material tests from a path (read_material_tests) or a dict of the same
// keys as the general JSON form.
validation::MaterialTests tests_arg(py::handle obj) {
  if (!py::isinstance<py::dict>(obj)) {
    if (!py::isinstance<py::str>(obj) && !py::hasattr(obj, "__fspath__"))
      throw InputError("tests: expected a JSON file's path or a dict of test results");
    return validation::read_material_tests(obj.cast<std::filesystem::path>());
  }
  validation::MaterialTests t;
  for (auto [key, value] : obj.cast<py::dict>()) {
    const std::string k = py::str(key);
    if (k == "bulk_density_kg_per_m3" || k == "repose_deg") {
      const auto a = doubles(value, k.c_str());
      if (a.ndim() > 1) throw InputError(k + ": expected a list of numbers");
      std::vector<double>& out = k == "repose_deg" ? t.repose_deg : t.bulk_density_kg_per_m3;
      for (py::ssize_t i = 0; i < a.size(); ++i) {
        if (!std::isfinite(a.data()[i])) throw InputError(k + ": a value is not finite");
        out.push_back(a.data()[i]);
      }
    } else if (k == "shear" || k == "plate") {
      const auto a = doubles(value, k.c_str());
      if (a.ndim() != 2 || a.shape(1) != 2)
        throw InputError(k + ": expected (N, 2) rows of normal stress and shear stress, Pa");
      for (py::ssize_t i = 0; i < a.shape(0); ++i) {
        const double sigma = a.at(i, 0), tau = a.at(i, 1);
        if (!(std::isfinite(sigma) && sigma > 0.0 && std::isfinite(tau) && tau >= 0.0))
          throw InputError(k + "[" + std::to_string(i) + "]: the normal stress must be > 0 and the shear stress >= 0");
        (k == "shear" ? t.shear : t.plate).push_back({sigma, tau});
      }
    } else {
      throw InputError(k + ": unknown test (bulk_density_kg_per_m3, repose_deg, shear, plate)");
    }
  }
  return t;
}

}  // namespace

void bind_calibration(py::module_& m) {
  m.def("calibrate_tests", [](py::object tests, py::object start) {
        const SoilMaterial s0 = start.is_none() ? SoilMaterial{} : material_arg(start);
        return calibration_dict(validation::calibrate_from_tests(tests_arg(tests), s0));
      }, py::arg("tests"), py::arg("start") = py::none(),
      "A soil material from material tests (`terracut calibrate --tests`): tests is a JSON "
      "file's path (the general form or a DEM's results/material.json) or a dict with "
      "bulk_density_kg_per_m3 and repose_deg (lists) and shear and plate ((N, 2) normal and "
      "shear stress, Pa). The shear tests' Mohr-Coulomb line gives internal_friction_deg and "
      "cohesion_pa, the plate tests soil_tool_friction_deg; start (a preset or dict) gives the "
      "rest. Returns material, fields (name, value, uncertainty: one standard uncertainty), "
      "rms_residual, rms_relative, notes, soil_yaml.");
  m.def("calibrate_record", [](const PyScenario& sc, py::object t_s, py::object poses, py::object force_n,
                               std::vector<std::string> fit, double window_s, double from_s, int max_iterations) {
        validation::ForceRecord rec;
        if (poses.is_none() && force_n.is_none()) {
          if (!py::isinstance<py::str>(t_s) && !py::hasattr(t_s, "__fspath__"))
            throw InputError("t_s: a record's CSV path, or times with poses and force_n");
          rec = validation::read_force_record(t_s.cast<std::filesystem::path>());
        } else {
          const auto t = doubles(t_s, "t_s");
          const auto p = doubles(poses, "poses");
          const auto f = doubles(force_n, "force_n");
          const py::ssize_t n = t.size();
          if (t.ndim() != 1 || n < 2) throw InputError("t_s: expected 2 times or more");
          if (p.ndim() != 2 || p.shape(0) != n || p.shape(1) != 7)
            throw InputError("poses: expected (N, 7) x, y, z, qw, qx, qy, qz with N = len(t_s)");
          if (f.ndim() != 2 || f.shape(0) != n || f.shape(1) != 3)
            throw InputError("force_n: expected (N, 3) with N = len(t_s)");
          for (py::ssize_t i = 0; i < n; ++i) {
            for (int k = 0; k < 7; ++k)
              if (!std::isfinite(p.at(i, k))) throw InputError("poses[" + std::to_string(i) + "]: not finite");
            for (int k = 0; k < 3; ++k)
              if (!std::isfinite(f.at(i, k))) throw InputError("force_n[" + std::to_string(i) + "]: not finite");
            if (!std::isfinite(t.data()[i]) || (i > 0 && !(t.data()[i] > t.data()[i - 1])))
              throw InputError("t_s[" + std::to_string(i) + "]: times must be finite and increase");
            const Quat q{p.at(i, 3), p.at(i, 4), p.at(i, 5), p.at(i, 6)};
            if (!(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z > 1e-12))
              throw InputError("poses[" + std::to_string(i) + "]: the orientation is zero");
            rec.t_s.push_back(t.data()[i]);
            rec.pose.push_back({{p.at(i, 0), p.at(i, 1), p.at(i, 2)}, normalized(q)});
            rec.force_n.push_back({f.at(i, 0), f.at(i, 1), f.at(i, 2)});
          }
        }
        validation::RecordFit rf;
        rf.fields = fit;
        rf.window_s = window_s;
        rf.from_t_s = from_s;
        rf.max_iterations = max_iterations;
        if (!(window_s > 0.0) || !std::isfinite(window_s)) throw InputError("window_s: expected > 0");
        const double dt = (rec.t_s.back() - rec.t_s.front()) / double(rec.t_s.size() - 1);
        validation::Calibration c;
        {
          py::gil_scoped_release release;
          c = validation::calibrate_from_force_record(io::sim_params(sc.base(), 1.0 / dt),
                                                      io::build_initial_heights(sc.base()), rec, rf);
        }
        return calibration_dict(c);
      }, py::arg("scenario"), py::arg("t_s"), py::arg("poses") = py::none(), py::arg("force_n") = py::none(),
      py::arg("fit") = std::vector<std::string>{"internal_friction_deg", "cohesion_pa"},
      py::arg("window_s") = 0.05, py::arg("from_s") = 0.0, py::arg("max_iterations") = 30,
      "Fits the scenario's soil material to a force record along a known path (`terracut "
      "calibrate --record`): t_s a CSV path (t_s,x_m,y_m,z_m,qw,qx,qy,qz,fx_n,fy_n,fz_n) or "
      "times (s) with poses (N, 7) and force_n (N, 3, world N on the tool). terracut replays the "
      "poses on the scenario's terrain at the record's rate; the fields in fit are fitted to "
      "the window means of the horizontal force along the motion and of the vertical force. "
      "Returns what calibrate_tests returns, evaluations counting the replays.");
}

}  // namespace terracut::python
