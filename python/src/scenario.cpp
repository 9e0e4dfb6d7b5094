// terracut.Scenario: a scenario file with all its sections
// (session::load_scenario), scenario text (the package writes a dict as
// text, so a dict has the file's checks), a bare heightmap, the command
// line's overrides; and the YAML reader the sweeps edit a file's mapping with.
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "bindings.hpp"
#include "terracut/core/format.hpp"
#include "terracut/core/ranges.hpp"
#include "terracut/session/batch.hpp"

namespace terracut::python {
namespace {

// ---------------------------------------------------------------------------
// YAML text -> Python objects (the sweep edits a scenario file as a dict).
// Scalars follow YAML's core schema as the scenario reader reads them:
// quoted scalars are strings; plain ones are null, booleans, integers or
// floats when they read as such, else strings.
// ---------------------------------------------------------------------------

py::object yaml_scalar(const YAML::Node& node) {
  const std::string& text = node.Scalar();
  if (node.Tag() == "!") return py::str(text);
  if (text.empty() || text == "~" || text == "null" || text == "Null" || text == "NULL")
    return py::none();
  if (text == "true" || text == "True" || text == "TRUE") return py::bool_(true);
  if (text == "false" || text == "False" || text == "FALSE") return py::bool_(false);
  bool integer = true;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char ch = text[i];
    if (!((ch >= '0' && ch <= '9') || (i == 0 && (ch == '-' || ch == '+') && text.size() > 1))) {
      integer = false;
      break;
    }
  }
  if (integer) return py::reinterpret_steal<py::object>(PyLong_FromString(text.c_str(), nullptr, 10));
  double value = 0.0;
  if (YAML::convert<double>::decode(node, value)) return py::float_(value);
  return py::str(text);
}

py::object yaml_to_python(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Sequence: {
      py::list out;
      for (const YAML::Node& item : node) out.append(yaml_to_python(item));
      return out;
    }
    case YAML::NodeType::Map: {
      py::dict out;
      for (const auto& kv : node) out[py::str(kv.first.Scalar())] = yaml_to_python(kv.second);
      return out;
    }
    case YAML::NodeType::Scalar:
      return yaml_scalar(node);
    default:
      return py::none();
  }
}

// The poses a batch run steps a cut through at rate_hz (session::cut_steps,
// Motion::sample at i / rate): (N, 7) x, y, z, qw, qx, qy, qz.
py::array_t<double> cut_poses(const Motion& motion, double rate_hz) {
  const std::int64_t n = session::cut_steps(motion, rate_hz);
  py::array_t<double> out({py::ssize_t(n), py::ssize_t(7)});
  double* p = out.mutable_data();
  for (std::int64_t i = 0; i < n; ++i) {
    const BladePose pose = motion.sample(double(i) / rate_hz);
    const double row[7] = {pose.position_m.x,    pose.position_m.y,    pose.position_m.z,
                           pose.orientation.w,   pose.orientation.x,   pose.orientation.y,
                           pose.orientation.z};
    std::copy(row, row + 7, p + 7 * i);
  }
  return out;
}

}  // namespace

int cut_index(const io::Scenario& sc, py::handle cut) {
  if (py::isinstance<py::str>(cut)) {
    const std::string name = cut.cast<std::string>();
    const int i = sc.find_cut(name);
    if (i < 0) throw InputError("cut: no cut named '" + name + "' in the scenario");
    return i;
  }
  if (PyLong_Check(cut.ptr())) {
    const long i = cut.cast<long>();
    if (i < 0 || i >= long(sc.cuts.size()))
      throw InputError("cut: index " + std::to_string(i) + " is outside [0, " +
                       std::to_string(sc.cuts.size()) + ")");
    return int(i);
  }
  throw InputError("cut: expected a cut's name or index");
}

std::optional<io::Resolution> resolution_arg(py::handle obj) {
  if (obj.is_none()) return std::nullopt;
  if (py::isinstance<py::str>(obj)) return io::parse_resolution(obj.cast<std::string>(), "resolution");
  if (PyLong_Check(obj.ptr())) return io::parse_resolution(std::to_string(obj.cast<long long>()), "resolution");
  if (py::isinstance<py::sequence>(obj) && py::len(obj) == 2) {
    py::sequence seq = obj.cast<py::sequence>();
    if (PyLong_Check(seq[0].ptr()) && PyLong_Check(seq[1].ptr()))
      return io::parse_resolution(std::to_string(seq[0].cast<long long>()) + "x" +
                                      std::to_string(seq[1].cast<long long>()),
                                  "resolution");
  }
  throw InputError("resolution: expected N, [cols, rows] or \"COLSxROWS\"");
}

std::optional<Representation> representation_arg(py::handle obj) {
  if (obj.is_none()) return std::nullopt;
  if (!py::isinstance<py::str>(obj)) throw InputError("representation: expected 'surface' or 'columns'");
  const std::string name = obj.cast<std::string>();
  auto r = parse_enum<Representation>(name);
  if (!r) throw InputError("representation: must be 'surface' or 'columns', got '" + name + "'");
  return r;
}

void bind_scenario(py::module_& m) {
  m.def("_parse_resolution", [](const std::string& text) {
        const io::Resolution r = io::parse_resolution(text, "resolution");
        return py::make_tuple(r.cols, r.rows);
      }, py::arg("text"),
      "The command line's --resolution text, 'N' or 'COLSxROWS', as (cols, rows); "
      "InputError naming 'resolution' when it is not one.");

  m.def("_yaml_to_python", [](const std::string& text, const std::string& source) {
        try {
          return yaml_to_python(YAML::Load(text));
        } catch (const YAML::Exception& e) {
          throw InputError(source + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
        }
      }, py::arg("text"), py::arg("source"),
      "Scenario YAML text as Python objects (dicts, lists, str, int, float, bool, None).");

  // --- Scenario ------------------------------------------------------------
  py::class_<PyScenario>(m, "Scenario", R"doc(A loaded, validated scenario (docs/scenario-format.md).

Build one with Scenario.load(path), Scenario.from_dict(mapping) or
Scenario.from_image(png). Errors are terracut.InputError with the scenario
reader's message, "FILE:LINE: field: what".)doc")
      .def_static("load", [](const std::filesystem::path& path) {
            return PyScenario{std::make_shared<const session::Scenario>(session::load_scenario(path))};
          }, py::arg("path"), "Reads and validates a scenario file with all its sections.")
      .def_static("_parse", [](const std::string& text, const std::filesystem::path& source) {
            return PyScenario{std::make_shared<const session::Scenario>(session::parse_scenario(text, source))};
          }, py::arg("text"), py::arg("source_name"),
          "Parses scenario text as if it were the file source_name (relative image paths "
          "resolve against its folder).")
      .def_static("from_image", [](const std::filesystem::path& png, double extent_m,
                                   double full_scale_m) {
            // Checked here so that the message names this function's arguments.
            if (!(std::isfinite(extent_m) && extent_m > 0.0))
              throw InputError(must_be("extent_m", "finite and > 0", extent_m));
            if (!(std::isfinite(full_scale_m) && full_scale_m > 0.0))
              throw InputError(must_be("full_scale_m", "finite and > 0", full_scale_m));
            return PyScenario{std::make_shared<const session::Scenario>(
                session::heightmap_scenario(png, extent_m, full_scale_m))};
          }, py::arg("png"), py::arg("extent_m") = 1.0, py::arg("full_scale_m") = 1.0,
          "A bare heightmap as a scenario: the PNG at its own resolution over extent_m x "
          "extent_m metres, a white pixel full_scale_m metres high, a blade half the extent "
          "long, no cuts.")
      .def("with_overrides", [](const PyScenario& self, py::object resolution,
                                py::object representation, py::object sequence) {
            session::Scenario copy = *self.s;
            std::optional<std::vector<std::string>> seq;
            if (!sequence.is_none()) {
              if (py::isinstance<py::str>(sequence))
                seq = io::parse_name_list(sequence.cast<std::string>(), "sequence");
              else
                seq = sequence.cast<std::vector<std::string>>();
            }
            io::apply_overrides(copy.base, resolution_arg(resolution),
                                representation_arg(representation), seq);
            return PyScenario{std::make_shared<const session::Scenario>(std::move(copy))};
          }, py::arg("resolution") = py::none(), py::arg("representation") = py::none(),
          py::arg("sequence") = py::none(),
          "A copy with the command line's overrides (terracut run --resolution, "
          "--representation, --sequence): resolution N, [cols, rows] or 'COLSxROWS'; "
          "representation 'surface' or 'columns'; sequence a list of cut names or 'A,B,C'.")
      .def_property_readonly("name", [](const PyScenario& s) { return s.base().name; })
      .def_property_readonly("source", [](const PyScenario& s) { return s.base().source_path; },
                             "The file it was read from, or the source name it was parsed as.")
      .def_property_readonly("resolution", [](const PyScenario& s) {
            return py::make_tuple(s.base().resolution.cols, s.base().resolution.rows);
          }, "(cols, rows): samples along X and along Z.")
      .def_property_readonly("size_m", [](const PyScenario& s) {
            return py::make_tuple(s.base().size_x_m, s.base().size_z_m);
          }, "(size_x, size_z): terrain extent, metres.")
      .def_property_readonly("origin_m", [](const PyScenario& s) { return tuple3(s.base().origin_m); },
                             "World position of the origin corner, metres; y is the ground level.")
      .def_property_readonly("full_scale_m", [](const PyScenario& s) { return s.base().full_scale_m; },
                             "Height of a white pixel, metres.")
      .def_property_readonly("representation", [](const PyScenario& s) {
            return std::string(to_string(s.base().representation));
          })
      .def_property_readonly("rate_hz", [](const PyScenario& s) { return s.base().rate_hz; },
                             "Fixed step rate, Hz.")
      .def_property_readonly("blade_length_m", [](const PyScenario& s) { return s.base().blade.length_m; })
      .def_property_readonly("soil_model", [](const PyScenario& s) {
            return std::string(to_string(s.base().soil.model));
          }, "'vanish' or 'flow'.")
      .def_property_readonly("cut_names", [](const PyScenario& s) {
            std::vector<std::string> names;
            for (const Motion& m : s.base().cuts) names.push_back(m.name);
            return names;
          })
      .def_property_readonly("sequence", [](const PyScenario& s) { return s.base().sequence_names(); },
                             "Names of the cuts in the order a run performs them.")
      .def_property_readonly("body_count", [](const PyScenario& s) { return s.s->bodies.size(); })
      .def("cut_poses", [](const PyScenario& s, py::object cut, std::optional<double> rate_hz) {
            const io::Scenario& sc = s.base();
            const double rate = rate_hz.value_or(sc.rate_hz);
            if (std::string m = check(kRateRange, rate); !m.empty()) throw InputError(m);
            return cut_poses(sc.cuts[std::size_t(cut_index(sc, cut))], rate);
          }, py::arg("cut"), py::arg("rate_hz") = py::none(),
          "The poses a run steps the cut (name or index) through: (N, 7) float64 rows "
          "x, y, z (metres), qw, qx, qy, qz (unit quaternion), one per step of 1/rate_hz "
          "seconds from the cut's start to its last keyframe.")
      .def("__repr__", [](const PyScenario& s) {
            return "<terracut.Scenario '" + s.base().name + "' " +
                   std::to_string(s.base().resolution.cols) + "x" +
                   std::to_string(s.base().resolution.rows) + " " +
                   std::string(to_string(s.base().representation)) + ">";
          });
}

}  // namespace terracut::python
