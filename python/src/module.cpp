// The compiled part of the Python module `terracut` (terracut._terracut):
// a program over the session layer, like the apps. It wraps
//
//   - scenarios: session::load_scenario / parse_scenario (the Python package
//     turns a dict into scenario text, so a dict has the file's errors),
//     session::heightmap_scenario, io::apply_overrides;
//   - the simulation: a session::World built from a scenario (its
//     listeners, e.g. the Bullet bodies, included), or a core Simulation over
//     a numpy array of heights; single and batched steps with the GIL
//     released, contact and surface queries, the validated edit
//     (Simulation::edit_heights), zero-copy read-only numpy views of the
//     grid's layers;
//   - session::run_scenario (`terracut run`, the same outputs on disk);
//   - the force models and the safety limiter.
//
// Every terracut::InputError becomes terracut.InputError (a ValueError) with
// the same message; nothing here aborts the interpreter.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>
#include <yaml-cpp/yaml.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <mutex>
#include <numbers>
#include <optional>
#include <span>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "terracut/core/error.hpp"
#include "terracut/core/forces.hpp"
#include "terracut/core/format.hpp"
#include "terracut/core/safety.hpp"
#include "terracut/core/simulation.hpp"
#include "terracut/core/surface.hpp"
#include "terracut/io/files.hpp"
#include "terracut/io/image.hpp"
#include "terracut/io/scenario.hpp"
#include "terracut/session/batch.hpp"
#include "terracut/session/mmt.hpp"
#include "terracut/session/scenario.hpp"
#include "terracut/session/world.hpp"

namespace py = pybind11;

namespace terracut::python {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

// ---------------------------------------------------------------------------
// Argument conversion: every bad Python argument is an InputError naming it.
// ---------------------------------------------------------------------------

std::string shape_text(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) s += (i ? ", " : "") + std::to_string(a.shape(i));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

// A C-contiguous float64 copy (or view) of any array-like; InputError naming
// `what` when it holds something that is not a number.
py::array_t<double, py::array::c_style | py::array::forcecast> doubles(py::handle obj,
                                                                         const std::string& what) {
  // ensure() gives a null array (the Python error cleared) when obj cannot
  // be read as numbers.
  auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(obj);
  if (!a) throw InputError(what + ": expected numbers");
  return a;
}

template <std::size_t N>
std::array<double, N> fixed(py::handle obj, const std::string& what) {
  const auto a = doubles(obj, what);
  if (a.ndim() != 1 || a.size() != py::ssize_t(N))
    throw InputError(what + ": expected " + std::to_string(N) + " numbers");
  std::array<double, N> out{};
  for (std::size_t i = 0; i < N; ++i) {
    out[i] = a.data()[i];
    if (!std::isfinite(out[i])) throw InputError(what + ": must be finite");
  }
  return out;
}

Vec3 vec3(py::handle obj, const std::string& what) {
  const auto a = fixed<3>(obj, what);
  return {a[0], a[1], a[2]};
}

py::tuple tuple3(const Vec3& v) { return py::make_tuple(v.x, v.y, v.z); }
py::tuple tuple4(const Quat& q) { return py::make_tuple(q.w, q.x, q.y, q.z); }
py::tuple rect_tuple(const Rect& r) { return py::make_tuple(r.c0, r.r0, r.c1, r.r1); }

// A pose as 7 numbers x, y, z, qw, qx, qy, qz: finite, the quaternion not zero.
BladePose pose_from(const double* p, const std::string& what) {
  for (int i = 0; i < 7; ++i)
    if (!std::isfinite(p[i])) throw InputError(what + ": must be finite");
  const double norm2 = p[3] * p[3] + p[4] * p[4] + p[5] * p[5] + p[6] * p[6];
  if (!(norm2 > 1e-24)) throw InputError(what + ": the quaternion (qw, qx, qy, qz) must not be zero");
  return {{p[0], p[1], p[2]}, Quat{p[3], p[4], p[5], p[6]}};
}

// Fast path for a single pose given as a tuple or list of 7 numbers (the
// common case of step(pose) in a loop): no numpy array is made.
bool pose_from_sequence(py::handle obj, BladePose* pose) {
  if (!(PyTuple_Check(obj.ptr()) || PyList_Check(obj.ptr()))) return false;
  if (PySequence_Fast_GET_SIZE(obj.ptr()) != 7) return false;
  PyObject** items = PySequence_Fast_ITEMS(obj.ptr());
  double p[7];
  for (int i = 0; i < 7; ++i) {
    if (!PyFloat_Check(items[i]) && !PyLong_Check(items[i])) return false;
    p[i] = PyFloat_AsDouble(items[i]);
    if (p[i] == -1.0 && PyErr_Occurred()) throw py::error_already_set();
  }
  *pose = pose_from(p, "pose");
  return true;
}

const char* kPoseShape =
    "pose: expected 7 numbers [x, y, z, qw, qx, qy, qz] (metres, unit quaternion) or an (N, 7) "
    "array of them";

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

// ---------------------------------------------------------------------------
// Scenario
// ---------------------------------------------------------------------------

struct PyScenario {
  std::shared_ptr<const session::Scenario> s;
  const io::Scenario& base() const { return s->base; }
};

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
  auto r = parse_representation(name);
  if (!r) throw InputError("representation: must be 'surface' or 'columns', got '" + name + "'");
  return r;
}

// ---------------------------------------------------------------------------
// Per-step output columns
// ---------------------------------------------------------------------------

// One step's figures as a small Python object (step(pose) with one pose).
struct StepResult {
  StepOutput out;
};

// Named numpy columns of n rows, allocated with the GIL held and filled
// row by row without it (set() makes no Python call). Float64 columns
// first, then int64 ones, in the order named.
class Columns {
 public:
  Columns(py::ssize_t n, std::vector<const char*> doubles, std::vector<const char*> ints) {
    for (const char* name : doubles) doubles_.emplace_back(name, py::array_t<double>(n));
    for (const char* name : ints) ints_.emplace_back(name, py::array_t<std::int64_t>(n));
    for (auto& [name, a] : doubles_) dptr_.push_back(a.mutable_data());
    for (auto& [name, a] : ints_) iptr_.push_back(a.mutable_data());
  }

  // Row i: one value per column, in the order they were named.
  void set(py::ssize_t i, std::span<const double> d, std::span<const std::int64_t> n) {
    for (std::size_t k = 0; k < dptr_.size(); ++k) dptr_[k][i] = d[k];
    for (std::size_t k = 0; k < iptr_.size(); ++k) iptr_[k][i] = n[k];
  }

  py::dict dict() const {
    py::dict out;
    for (const auto& [name, a] : doubles_) out[name] = a;
    for (const auto& [name, a] : ints_) out[name] = a;
    return out;
  }

 private:
  std::vector<std::pair<const char*, py::array_t<double>>> doubles_;
  std::vector<std::pair<const char*, py::array_t<std::int64_t>>> ints_;
  std::vector<double*> dptr_;
  std::vector<std::int64_t*> iptr_;
};

// t, then the pose's 7 numbers: the first columns of every per-step table.
constexpr std::size_t kTimePose = 8;
void time_pose(double t_s, const BladePose& p, double* out) {
  const double v[kTimePose] = {t_s,
                               p.position_m.x,
                               p.position_m.y,
                               p.position_m.z,
                               p.orientation.w,
                               p.orientation.x,
                               p.orientation.y,
                               p.orientation.z};
  std::copy(v, v + kTimePose, out);
}

// The columns of batched steps (Simulation.step(poses), Simulation.run()).
class StepColumns {
 public:
  StepColumns(py::ssize_t n, bool with_cut) : columns_(n, double_names(), int_names(with_cut)) {}

  // Row i from a finished step; cut: the cut's index (with_cut only).
  void fill(py::ssize_t i, const StepOutput& o, std::int64_t cut = -1) {
    double d[kTimePose + kOwn + kMaxForce];
    time_pose(o.t_s, o.pose, d);
    const double rest[kOwn] = {o.contact.length_m,        o.contact.section_area_m2,
                               o.contact.max_depth_m,     o.cut.removed_volume_m3,
                               o.soil.displaced_volume_m3, o.listener_force_world_n.x,
                               o.listener_force_world_n.y, o.listener_force_world_n.z,
                               o.timers.total_s};
    std::copy(std::begin(rest), std::end(rest), d + kTimePose);
    // The physical force, as force.csv has it (session::force_columns()).
    std::size_t k = kTimePose + kOwn;
    for (const session::ForceColumn& c : session::force_columns()) d[k++] = c.get(o);
    const std::int64_t n[] = {o.step,       o.contact.cells_visited + o.cut.cells_visited,
                              o.substeps,   o.changed.c0,
                              o.changed.r0, o.changed.c1,
                              o.changed.r1, cut};
    columns_.set(i, d, n);
  }

  py::dict dict() const { return columns_.dict(); }

 private:
  static constexpr std::size_t kOwn = 9;
  static constexpr std::size_t kMaxForce = 64;
  static std::vector<const char*> double_names() {
    std::vector<const char*> names = {"t", "x", "y", "z", "qw", "qx", "qy", "qz", "contact_length",
                                      "section_area", "max_depth", "removed_volume",
                                      "displaced_volume", "listener_fx", "listener_fy",
                                      "listener_fz", "step_s"};
    for (const session::ForceColumn& c : session::force_columns()) names.push_back(c.name);
    return names;
  }
  static std::vector<const char*> int_names(bool with_cut) {
    std::vector<const char*> names = {"step",       "cells_visited", "substeps",  "changed_c0",
                                      "changed_r0", "changed_c1",    "changed_r1"};
    if (with_cut) names.push_back("cut");
    return names;
  }

  Columns columns_;
};

// ---------------------------------------------------------------------------
// Simulation
// ---------------------------------------------------------------------------

class PySimulation {
 public:
  // A scenario's world: the simulation and its listeners (the bodies).
  PySimulation(const PyScenario& scenario, const std::optional<std::filesystem::path>& bodies_csv)
      : scenario_(scenario.s) {
    session::WorldOptions wo;
    if (bodies_csv) wo.bodies_csv = *bodies_csv;
    world_ = std::make_unique<session::World>(*scenario_, wo);
    sim_ = &world_->simulation();
  }

  // A bare simulation over heights (rows x cols, metres).
  PySimulation(const SimParams& params, std::vector<float> heights)
      : own_(std::make_unique<Simulation>(params, std::move(heights))), sim_(own_.get()) {}

  ~PySimulation() {
    if (world_) {
      try {
        world_->finish();
      } catch (...) {  // a file that could not be written: finish() was the place to hear it
      }
    }
  }

  Simulation& sim() { return *sim_; }
  const Simulation& sim() const { return *sim_; }
  bool has_scenario() const { return bool(scenario_); }
  const session::Scenario& scenario() const {
    if (!scenario_) throw InputError("this simulation was built from heights, not from a scenario");
    return *scenario_;
  }
  session::World* world() { return world_.get(); }

  // One thread at a time: a second thread stepping (or editing) the same
  // simulation gets an error instead of a data race.
  std::unique_lock<std::mutex> claim() {
    std::unique_lock<std::mutex> lock(busy_, std::try_to_lock);
    if (!lock.owns_lock())
      throw std::runtime_error(
          "Simulation: already being stepped by another thread; use one Simulation per thread");
    return lock;
  }

  void finish() {
    if (world_) world_->finish();
  }

 private:
  std::shared_ptr<const session::Scenario> scenario_;
  std::unique_ptr<session::World> world_;
  std::unique_ptr<Simulation> own_;
  Simulation* sim_ = nullptr;
  std::mutex busy_;
};

// A read-only (rows, cols) float32 view of a layer; `owner` (the Python
// Simulation) stays alive while the view exists.
py::array layer_view(py::object owner, const float* data, const HeightGrid& grid) {
  py::array_t<float> view({py::ssize_t(grid.rows()), py::ssize_t(grid.cols())},
                          {py::ssize_t(sizeof(float)) * grid.cols(), py::ssize_t(sizeof(float))},
                          data, owner);
  py::detail::array_proxy(view.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return view;
}

py::object step_poses(PySimulation& self, py::object poses) {
  // One pose: the fast path, then any 7-element array-like.
  BladePose pose;
  bool single = pose_from_sequence(poses, &pose);
  py::array_t<double, py::array::c_style | py::array::forcecast> array;
  if (!single) {
    array = doubles(poses, "pose");
    if (array.ndim() == 1 && array.size() == 7) {
      pose = pose_from(array.data(), "pose");
      single = true;
    } else if (!(array.ndim() == 2 && array.shape(1) == 7)) {
      throw InputError(std::string(kPoseShape) + ", got shape " + shape_text(array));
    }
  }
  auto lock = self.claim();
  if (single) {
    StepResult r;
    {
      py::gil_scoped_release release;
      r.out = self.sim().step(pose);
    }
    return py::cast(std::move(r));
  }
  // Batched: every pose checked before the first step, then one C++ loop.
  const py::ssize_t n = array.shape(0);
  std::vector<BladePose> list(static_cast<std::size_t>(n));
  for (py::ssize_t i = 0; i < n; ++i)
    list[std::size_t(i)] = pose_from(array.data() + 7 * i, "poses[" + std::to_string(i) + "]");
  StepColumns columns(n, false);
  {
    py::gil_scoped_release release;
    for (py::ssize_t i = 0; i < n; ++i) columns.fill(i, self.sim().step(list[std::size_t(i)]));
  }
  return columns.dict();
}

// The scenario's sequence (or the given cuts), as `terracut run` steps it:
// each cut a separate stroke (lift), steps at t = i / rate.
py::dict run_sequence(PySimulation& self, py::object cuts) {
  const io::Scenario& sc = self.scenario().base;
  std::vector<int> order = sc.sequence;
  if (py::isinstance<py::str>(cuts)) {  // "A" or "A,B,C"
    order.clear();
    for (const std::string& name : io::parse_name_list(cuts.cast<std::string>(), "cuts"))
      order.push_back(cut_index(sc, py::str(name)));
  } else if (!cuts.is_none()) {
    order.clear();
    for (py::handle c : cuts) order.push_back(cut_index(sc, c));
  }
  std::vector<BladePose> poses;
  std::vector<std::int64_t> cut_of;
  std::vector<char> stroke_start;  // 1 at the first step of each entry of the order
  const double rate = self.sim().params().rate_hz;
  for (int index : order) {
    const Motion& m = sc.cuts[std::size_t(index)];
    const std::int64_t n = session::cut_steps(m, rate);
    for (std::int64_t i = 0; i < n; ++i) {
      poses.push_back(m.sample(double(i) / rate));
      cut_of.push_back(index);
      stroke_start.push_back(i == 0 ? 1 : 0);
    }
  }
  auto lock = self.claim();
  StepColumns columns(py::ssize_t(poses.size()), true);
  {
    py::gil_scoped_release release;
    for (std::size_t i = 0; i < poses.size(); ++i) {
      // Each entry of the order is a separate stroke, as in a batch run.
      if (stroke_start[i]) self.sim().lift();
      columns.fill(py::ssize_t(i), self.sim().step(poses[i]), cut_of[i]);
    }
  }
  return columns.dict();
}


// ---------------------------------------------------------------------------
// Batch run (session::run_scenario)
// ---------------------------------------------------------------------------

py::dict timing_dict(const TimingStats& t) {
  py::dict d;
  d["p50_us"] = t.p50_us;
  d["p90_us"] = t.p90_us;
  d["p99_us"] = t.p99_us;
  d["max_us"] = t.max_us;
  d["mean_us"] = t.mean_us;
  return d;
}

py::dict run_result_dict(const session::RunResult& r, const io::Scenario& sc) {
  py::dict out;
  out["steps"] = r.steps;
  out["initial_volume_m3"] = r.initial_volume_m3;
  out["final_volume_m3"] = r.final_volume_m3;
  out["removed_volume_m3"] = r.removed_volume_m3;
  out["max_sample_error_m"] = r.max_sample_error_m;
  out["volume_error_m3"] = r.volume_error_m3;
  out["wall_s"] = r.wall_s;
  py::list cuts;
  for (const session::CutStats& c : r.cuts) {
    py::dict d;
    d["name"] = c.name;
    d["sequence_index"] = c.sequence_index;
    d["start_t_s"] = c.start_t_s;
    d["duration_s"] = c.duration_s;
    d["steps"] = c.steps;
    d["peak_contact_m"] = c.peak_contact_m;
    d["mean_contact_m"] = c.mean_contact_m;
    d["removed_volume_m3"] = c.removed_volume_m3;
    cuts.append(d);
  }
  out["cuts"] = cuts;
  out["step_timing"] = timing_dict(r.step_timing);
  if (r.soil) {
    py::dict d;
    d["cut_from_ground_m3"] = r.soil->cut_from_ground_m3;
    d["displaced_volume_m3"] = r.soil->displaced_volume_m3;
    d["net_moved_m3"] = r.soil->net_moved_m3;
    d["left_over_edge_m3"] = r.soil->left_over_edge_m3;
    d["passes"] = r.soil->passes;
    d["final_backlog_cells"] = r.soil->final_backlog_cells;
    d["capped_steps"] = r.soil->capped_steps;
    out["soil"] = d;
  }
  out["warnings"] = r.warnings;
  // The per-step records as columns (contact.csv's, with the cut index).
  Columns records(py::ssize_t(r.records.size()),
                  {"t", "x", "y", "z", "qw", "qx", "qy", "qz", "contact_length", "removed_volume",
                   "section_area", "max_depth"},
                  {"cut", "sequence_index"});
  for (std::size_t i = 0; i < r.records.size(); ++i) {
    const io::StepRecord& rec = r.records[i];
    double d[kTimePose + 4];
    time_pose(rec.t_s, rec.pose, d);
    const double rest[] = {rec.contact.length_m, rec.removed_volume_m3, rec.contact.section_area_m2,
                           rec.contact.max_depth_m};
    std::copy(std::begin(rest), std::end(rest), d + kTimePose);
    const std::int64_t n[] = {rec.cut, rec.sequence_index};
    records.set(py::ssize_t(i), d, n);
  }
  out["records"] = records.dict();
  py::list cut_names;
  for (const Motion& m : sc.cuts) cut_names.append(m.name);
  out["cut_names"] = cut_names;
  return out;
}

// ---------------------------------------------------------------------------
// Forces
// ---------------------------------------------------------------------------

// A soil material given as a preset name or a dict of SoilMaterial fields
// (the scenario's soil: keys: angles in degrees, a preset's values replaced
// by the fields given); unknown keys are refused by name.
SoilMaterial material_arg(py::handle obj) {
  const auto preset_of = [](const std::string& name) {
    auto preset = parse_soil_preset(name);
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

// The physical force of a step as a dict (world N tuples; force.csv's parts).
py::dict tool_force_dict(const StepOutput& o) {
  const ToolForce& f = o.force;
  py::dict d;
  d["total_n"] = tuple3(f.total_n);
  d["cutting_n"] = tuple3(f.cutting_n);
  d["surcharge_n"] = tuple3(f.surcharge_n);
  d["penetration_n"] = tuple3(f.penetration_n);
  d["twist_n"] = tuple3(f.twist_n);
  d["twist_torque_n_m"] = f.twist_torque_n_m;
  d["load_n"] = tuple3(f.load_n);
  d["bodies_n"] = tuple3(f.bodies_n);
  d["cut_depth_m"] = f.cut_depth_m;
  d["cut_width_m"] = f.engaged_width_m;
  d["pile_height_m"] = f.pile_m;
  d["surcharge_pa"] = f.surcharge_pa;
  d["beta_rad"] = f.earthmoving.beta_rad;
  d["velocity_m_per_s"] = tuple3(o.motion.velocity_m_per_s);
  return d;
}

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
}  // namespace terracut::python

// ---------------------------------------------------------------------------
// The module
// ---------------------------------------------------------------------------

PYBIND11_MODULE(_terracut, m) {
  using namespace terracut;
  using namespace terracut::python;
  m.doc() =
      "terracut's compiled core: scenarios, the simulation, batch runs, forces. SI units "
      "throughout (metres, seconds, newtons); world frame right-handed, Y up, ground plane X-Z.";

  py::register_exception<InputError>(m, "InputError", PyExc_ValueError);

  m.def("_yaml_to_python", [](const std::string& text, const std::string& source) {
        try {
          return yaml_to_python(YAML::Load(text));
        } catch (const YAML::Exception& e) {
          throw InputError(source + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
        }
      }, py::arg("text"), py::arg("source"),
      "Scenario YAML text as Python objects (dicts, lists, str, int, float, bool, None).");

  m.def("bodies_available", &session::bodies_available,
        "True when this build has the rigid-body engine (Bullet).");

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
            if (!(std::isfinite(rate) && rate > 0.0 && rate <= 1e6))
              throw InputError(must_be("rate_hz", "in (0, 1e6]", rate));
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

  // --- StepResult ----------------------------------------------------------
  py::class_<StepResult>(m, "StepResult", "What one step did (SI units).")
      .def_property_readonly("step", [](const StepResult& r) { return r.out.step; }, "Index of the step, from 0.")
      .def_property_readonly("t_s", [](const StepResult& r) { return r.out.t_s; }, "Simulation time of the step, s.")
      .def_property_readonly("position_m", [](const StepResult& r) { return tuple3(r.out.pose.position_m); },
                             "Blade centre, world metres.")
      .def_property_readonly("orientation", [](const StepResult& r) { return tuple4(r.out.pose.orientation); },
                             "Blade orientation (qw, qx, qy, qz), unit quaternion.")
      .def_property_readonly("contact_length_m", [](const StepResult& r) { return r.out.contact.length_m; },
                             "Length of the blade inside material, measured before the step's cut, m.")
      .def_property_readonly("section_area_m2", [](const StepResult& r) { return r.out.contact.section_area_m2; },
                             "Depth integrated along the contact, m^2.")
      .def_property_readonly("max_depth_m", [](const StepResult& r) { return r.out.contact.max_depth_m; },
                             "Largest depth of the edge below the surface, m.")
      .def_property_readonly("removed_volume_m3", [](const StepResult& r) { return r.out.cut.removed_volume_m3; },
                             "Volume the step's sweep cut, m^3 (with soil flow: a pile cut again counts again).")
      .def_property_readonly("cut_from_ground_m3", [](const StepResult& r) { return r.out.soil.cut_from_ground_m3; },
                             "The part of the step's cut below the initial surface (soil flow), m^3.")
      .def_property_readonly("displaced_volume_m3", [](const StepResult& r) { return r.out.soil.displaced_volume_m3; },
                             "Soil put down ahead of the blade (soil flow; a pile pushed on counts at every step), m^3.")
      .def_property_readonly("cells_visited", [](const StepResult& r) {
            return r.out.contact.cells_visited + r.out.cut.cells_visited;
          }, "Cells examined by the contact query and the cut.")
      .def_property_readonly("changed", [](const StepResult& r) { return rect_tuple(r.out.changed); },
                             "(c0, r0, c1, r1): half-open rectangle of samples the step changed.")
      .def_property_readonly("substeps", [](const StepResult& r) { return r.out.substeps; })
      .def_property_readonly("listener_force_n", [](const StepResult& r) {
            return tuple3(r.out.listener_force_world_n);
          }, "Force of the step listeners (the rigid bodies) on the tool, world N.")
      .def_property_readonly("step_s", [](const StepResult& r) { return r.out.timers.total_s; },
                             "Wall-clock time of the step in C++, s.")
      .def_property_readonly("force", [](const StepResult& r) { return tool_force_dict(r.out); },
                             "The physical force on the tool (world N): total_n and its parts "
                             "cutting_n, surcharge_n, penetration_n, twist_n, load_n, bodies_n, "
                             "twist_torque_n_m, and what it was computed from (cut_depth_m, "
                             "cut_width_m, pile_height_m, surcharge_pa, beta_rad, "
                             "velocity_m_per_s): terracut run's force.csv.")
      .def("__repr__", [](const StepResult& r) {
            std::ostringstream s;
            s << "<StepResult step " << r.out.step << " t " << r.out.t_s << " s contact "
              << r.out.contact.length_m << " m removed " << r.out.cut.removed_volume_m3 << " m^3>";
            return s.str();
          });

  // --- Simulation ----------------------------------------------------------
  py::class_<PySimulation>(m, "Simulation", R"doc(The fixed-step cutting simulation.

Units: metres, seconds, newtons; world frame right-handed, Y up, ground
plane X-Z. A pose is 7 numbers [x, y, z, qw, qx, qy, qz]: the blade centre
in world metres and its orientation as a unit quaternion (the blade lies
along its local X axis).

The layers heights, removed and initial are read-only (rows, cols) float32
numpy views of the C++ grid in metres (row r along +Z, column c along +X),
no copy; write through edit_heights(). step() releases the GIL, so threads
stepping different simulations run in parallel; one Simulation is stepped by
one thread at a time.)doc")
      .def(py::init<const PyScenario&, const std::optional<std::filesystem::path>&>(),
           py::arg("scenario"), py::arg("bodies_csv") = py::none(),
           "The scenario's world: terrain, representation, blade, rate and its listeners (the "
           "rigid bodies when it has bodies: and this build has Bullet). bodies_csv: where the "
           "bodies' states go, or None.")
      .def_static("from_heights", [](py::object heights, std::pair<double, double> size_m,
                                     py::object origin_m, const std::string& representation,
                                     double rate_hz, double blade_length_m,
                                     const std::string& soil_model, py::object soil,
                                     double rake_angle_deg) {
            auto a = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(heights);
            if (!a || a.ndim() != 2)
              throw InputError("heights: expected a 2-D (rows, cols) array of metres");
            SimParams p;
            p.grid.rows = int(std::min<py::ssize_t>(a.shape(0), kMaxGridSide + 1));
            p.grid.cols = int(std::min<py::ssize_t>(a.shape(1), kMaxGridSide + 1));
            p.grid.size_x_m = size_m.first;
            p.grid.size_z_m = size_m.second;
            p.grid.origin_m = vec3(origin_m, "origin_m");
            p.representation = *representation_arg(py::str(representation));
            p.rate_hz = rate_hz;
            p.blade.length_m = blade_length_m;
            auto model = parse_soil_model(soil_model);
            if (!model) throw InputError("soil_model: must be 'vanish' or 'flow', got '" + soil_model + "'");
            p.soil.model = *model;
            p.soil.material = material_arg(soil);
            p.blade.rake_angle_deg = rake_angle_deg;
            if (std::string e = validate(p); !e.empty()) throw InputError(e);
            std::vector<float> h(a.data(), a.data() + a.size());
            return std::make_unique<PySimulation>(p, std::move(h));
          }, py::arg("heights"), py::arg("size_m") = std::make_pair(1.0, 1.0),
          py::arg("origin_m") = py::make_tuple(0.0, 0.0, 0.0), py::arg("representation") = "surface",
          py::arg("rate_hz") = 1000.0, py::arg("blade_length_m") = 1.0,
          py::arg("soil_model") = "vanish", py::arg("soil") = "dry_sand", py::arg("rake_angle_deg") = 90.0,
          "A simulation over a (rows, cols) array of heights in metres (copied): size_m = "
          "(size_x, size_z) metres, origin_m the origin corner (y = ground), representation "
          "'surface' or 'columns', rate_hz the step rate (Hz), blade_length_m metres, "
          "soil_model 'vanish' or 'flow', soil the material (a preset name or a dict of the soil: "
          "section's keys), rake_angle_deg the blade's rake (degrees, 90 vertical).")
      .def_property_readonly("heights", [](py::object self) {
            auto& s = self.cast<PySimulation&>();
            return layer_view(self, s.sim().grid().heights(), s.sim().grid());
          }, "Current heights above ground, (rows, cols) float32, metres; read-only view.")
      .def_property_readonly("removed", [](const PySimulation& s) {
            // The grid derives removed from the two stored layers, so this is
            // a copy, taken now (later steps do not show in it).
            const HeightGrid& g = s.sim().grid();
            py::array_t<float> out({py::ssize_t(g.rows()), py::ssize_t(g.cols())});
            g.copy_removed(out.mutable_data());
            py::detail::array_proxy(out.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
            return out;
          }, "Material removed (initial - height), (rows, cols) float32, metres; a read-only copy "
             "taken when read (not a view: later steps do not show in it).")
      .def_property_readonly("initial", [](py::object self) {
            auto& s = self.cast<PySimulation&>();
            return layer_view(self, s.sim().grid().initial(), s.sim().grid());
          }, "Heights at construction, (rows, cols) float32, metres; read-only view.")
      .def("step", &step_poses, py::arg("pose"),
           R"doc(Steps the simulation: contact (before the cut), cut, soil flow, listeners.

pose: 7 numbers [x, y, z, qw, qx, qy, qz] (metres; unit quaternion) ->
StepResult; or an (N, 7) array -> a dict of numpy columns, one row per step,
stepped in one C++ loop without the GIL: step, t (s), x, y, z (m), qw..qz,
contact_length (m), section_area (m^2), max_depth (m), removed_volume (m^3),
displaced_volume (m^3), listener_fx..fz (N), step_s (s), cells_visited,
substeps, changed_c0, changed_r0, changed_c1, changed_r1.)doc")
      .def("run", &run_sequence, py::arg("cuts") = py::none(),
           "Steps the scenario's sequence (or the given cuts: names or indices, or 'A,B,C') as `terracut "
           "run` does, each cut a separate stroke, and returns the step() columns plus 'cut' "
           "(the cut's index). Writes no files; see terracut.run for that.")
      .def("contact", [](PySimulation& self, py::object pose) {
            BladePose p;
            if (!pose_from_sequence(pose, &p)) p = pose_from(fixed<7>(pose, "pose").data(), "pose");
            auto lock = self.claim();
            const ContactResult c = measure_contact(
                self.sim().grid(), self.sim().params().representation,
                blade_segment(self.sim().params().blade, {p.position_m, normalized(p.orientation)}));
            py::dict d;
            d["length_m"] = c.length_m;
            d["section_area_m2"] = c.section_area_m2;
            d["max_depth_m"] = c.max_depth_m;
            d["cells_visited"] = c.cells_visited;
            return d;
          }, py::arg("pose"),
          "Contact of the blade at pose with the terrain as it is, without cutting or "
          "stepping: length_m (m), section_area_m2 (m^2), max_depth_m (m), cells_visited.")
      .def("surface_y", [](PySimulation& self, py::object x, py::object z) {
            py::module_ np = py::module_::import("numpy");
            py::tuple both = np.attr("broadcast_arrays")(doubles(x, "x"), doubles(z, "z"));
            auto xs = doubles(np.attr("ascontiguousarray")(both[0]), "x");
            auto zs = doubles(np.attr("ascontiguousarray")(both[1]), "z");
            std::vector<py::ssize_t> shape(xs.shape(), xs.shape() + xs.ndim());
            py::array_t<double> out(shape);
            for (py::ssize_t i = 0; i < xs.size(); ++i)
              out.mutable_data()[i] = surface_y_m(self.sim().grid(), self.sim().params().representation,
                                                  xs.data()[i], zs.data()[i]);
            if (xs.ndim() == 0) return py::object(py::float_(out.data()[0]));
            return py::object(out);
          }, py::arg("x"), py::arg("z"),
          "World Y of the terrain surface at world (x, z), metres, as the representation "
          "reads the samples (0 above ground level outside the terrain). Scalars or arrays.")
      .def("edit_heights", [](PySimulation& self, py::object values, int c0, int r0) {
            auto a = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(values);
            if (!a || a.ndim() != 2)
              throw InputError("edit_heights: expected a 2-D (rows, cols) array of heights in metres");
            // The far corner in 64 bits, so a huge c0 or r0 is refused, not wrapped.
            const auto far = [](int start, py::ssize_t size) {
              return int(std::min<std::int64_t>(std::int64_t(start) + size, std::int64_t(INT32_MAX)));
            };
            const Rect rect{c0, r0, far(c0, a.shape(1)), far(r0, a.shape(0))};
            auto lock = self.claim();
            return rect_tuple(self.sim().edit_heights(rect, {a.data(), std::size_t(a.size())}));
          }, py::arg("values"), py::arg("c0") = 0, py::arg("r0") = 0,
          "Replaces the heights of the rectangle whose first sample is (column c0, row r0) "
          "with values ((rows, cols) metres, finite, >= 0), updates removed, wakes the soil "
          "flow and tells the listeners (the rigid bodies). Returns the changed rectangle "
          "(c0, r0, c1, r1), half-open. Refused (InputError, nothing written) when it "
          "leaves the grid or a value is bad.")
      .def("lift", [](PySimulation& self) {
            auto lock = self.claim();
            self.sim().lift();
          }, "Lifts the blade: the next step starts a new stroke and sweeps nothing from the "
             "previous pose.")
      .def("reset", [](PySimulation& self) {
            auto lock = self.claim();
            self.sim().reset();
            // Whoever caches heights (the Bullet world) hears of the whole grid.
            const Rect all{0, 0, self.sim().grid().cols(), self.sim().grid().rows()};
            for (StepListener* listener : self.sim().listeners()) listener->on_edit(all);
          }, "Restores the initial terrain, time and counters. Rigid bodies keep their poses and "
             "are woken over the restored terrain.")
      .def("save", [](PySimulation& self, const std::filesystem::path& dir, std::optional<double> full_scale_m) {
            const HeightGrid& g = self.sim().grid();
            const double fs = full_scale_m.value_or(g.spec().full_scale_m);
            io::make_output_folder(dir);
            io::write_npy(dir / "height.npy", g.heights(), g.rows(), g.cols());
            std::vector<float> removed(std::size_t(g.spec().sample_count()));
            g.copy_removed(removed.data());
            io::write_npy(dir / "removed.npy", removed.data(), g.rows(), g.cols());
            io::write_png16(dir / "height.png", g.heights(), g.cols(), g.rows(), fs);
            io::write_png16(dir / "removed.png", removed.data(), g.cols(), g.rows(), fs);
          }, py::arg("out_dir"), py::arg("full_scale_m") = py::none(),
          "Writes height.npy and removed.npy (float32 (rows, cols), metres) and height.png, "
          "removed.png (16-bit, pixel = value / full_scale_m) into out_dir (created).")
      .def("bodies", [](PySimulation& self) {
            const BodySource* src = self.world() ? self.world()->bodies() : nullptr;
            const int n = src ? src->body_total() : 0;
            std::vector<BodyView> views(static_cast<std::size_t>(n));
            if (src) src->write_bodies(views);
            py::array_t<double> pos({py::ssize_t(n), py::ssize_t(3)}), rot({py::ssize_t(n), py::ssize_t(4)});
            py::array_t<bool> active(n);
            for (int i = 0; i < n; ++i) {
              const BodyView& b = views[std::size_t(i)];
              const double p[3] = {b.position_m.x, b.position_m.y, b.position_m.z};
              const double q[4] = {b.orientation.w, b.orientation.x, b.orientation.y, b.orientation.z};
              std::copy(p, p + 3, pos.mutable_data() + 3 * i);
              std::copy(q, q + 4, rot.mutable_data() + 4 * i);
              active.mutable_data()[i] = b.active;
            }
            py::dict d;
            d["position_m"] = pos;
            d["orientation"] = rot;
            d["active"] = active;
            return d;
          }, "The rigid bodies now: position_m (n, 3) world metres, orientation (n, 4) unit "
             "quaternions (qw, qx, qy, qz), active (n,) (False while asleep); n = 0 without bodies.")
      .def("finish", &PySimulation::finish, "Flushes and closes the listeners' files (bodies.csv).")
      .def_property_readonly("step_count", [](const PySimulation& s) { return s.sim().step_count(); })
      .def_property_readonly("time_s", [](const PySimulation& s) { return s.sim().time_s(); },
                             "Simulation time, s (step_count / rate_hz).")
      .def_property_readonly("removed_volume_m3", [](const PySimulation& s) { return s.sim().removed_volume_m3(); },
                             "Total volume cut since construction or reset, m^3.")
      .def_property_readonly("volume_m3", [](const PySimulation& s) { return s.sim().grid().volume_m3(); },
                             "Material above ground now, m^3.")
      .def_property_readonly("conservation_error_m", [](const PySimulation& s) {
            return s.sim().grid().conservation_error_m();
          }, "Largest |height + removed - initial| over the samples, m.")
      .def_property_readonly("state_hash", [](const PySimulation& s) { return s.sim().grid().state_hash(); },
                             "64-bit hash of the height, removed and initial layers (bitwise), for "
                             "determinism checks.")
      .def_property_readonly("shape", [](const PySimulation& s) {
            return py::make_tuple(s.sim().grid().rows(), s.sim().grid().cols());
          }, "(rows, cols) of the layers.")
      .def_property_readonly("cell_m", [](const PySimulation& s) {
            return py::make_tuple(s.sim().params().grid.cell_x_m(), s.sim().params().grid.cell_z_m());
          }, "(cell_x, cell_z), metres.")
      .def_property_readonly("size_m", [](const PySimulation& s) {
            return py::make_tuple(s.sim().params().grid.size_x_m, s.sim().params().grid.size_z_m);
          }, "(size_x, size_z), metres.")
      .def_property_readonly("origin_m", [](const PySimulation& s) { return tuple3(s.sim().params().grid.origin_m); },
                             "Origin corner, world metres; y is the ground level.")
      .def_property_readonly("representation", [](const PySimulation& s) {
            return std::string(to_string(s.sim().params().representation));
          })
      .def_property_readonly("rate_hz", [](const PySimulation& s) { return s.sim().params().rate_hz; })
      .def_property_readonly("blade_length_m", [](const PySimulation& s) { return s.sim().params().blade.length_m; });

  // --- Batch run -------------------------------------------------------------
  m.def("_run", [](const PyScenario& scenario, const std::filesystem::path& out_dir, bool realtime) {
        session::RunOptions o;
        o.out_dir = out_dir;
        o.keep_records = true;
        o.realtime = realtime;
        session::RunResult r;
        {
          py::gil_scoped_release release;
          r = session::run_scenario(*scenario.s, o);
        }
        return run_result_dict(r, scenario.base());
      }, py::arg("scenario"), py::arg("out_dir"), py::arg("realtime") = false,
      "session::run_scenario: `terracut run`'s outputs in out_dir, and the figures.");

  // --- Teleoperation (session::MmtRun) ---------------------------------------
  m.def("_run_mmt", [](const PyScenario& scenario, std::optional<std::filesystem::path> out_dir,
                       std::optional<double> rtt_s, std::optional<double> loss, std::optional<double> deadband,
                       std::optional<std::uint64_t> seed) {
        session::MmtOverrides o;
        o.rtt_s = rtt_s;
        o.loss = loss;
        o.deadband = deadband;
        o.seed = seed;
        session::MmtSummary s;
        {
          py::gil_scoped_release release;
          session::MmtRun run(*scenario.s, o);
          run.run();
          if (out_dir) {
            std::filesystem::create_directories(*out_dir);
            run.write_outputs(*out_dir);
          }
          s = run.summary();
        }
        py::dict d;
        d["rtt_s"] = s.rtt_s;
        d["loss"] = s.loss;
        d["deadband"] = s.deadband;
        d["force_rms_remote_n"] = s.force_rms_remote_n;
        d["force_error_rms_mmt_n"] = s.force_error_rms_mmt_n;
        d["force_error_max_mmt_n"] = s.force_error_max_mmt_n;
        d["force_error_rms_dfr_n"] = s.force_error_rms_dfr_n;
        d["force_error_max_dfr_n"] = s.force_error_max_dfr_n;
        d["terrain_rms_max_m"] = s.terrain_rms_max_m;
        d["terrain_rms_final_m"] = s.terrain_rms_final_m;
        d["tracking_rms_m"] = s.tracking_rms_m;
        d["tracking_max_m"] = s.tracking_max_m;
        d["packets_per_s_to_remote"] = s.packets_per_s_to_remote;
        d["packets_per_s_to_operator"] = s.packets_per_s_to_operator;
        d["update_packets_per_s"] = s.update_packets_per_s;
        d["patches"] = s.patches;
        d["estimates"] = s.estimates;
        d["max_update_step_n"] = s.max_update_step_n;
        d["passivity_max_mmt_j"] = s.passivity_max_mmt_j;
        d["passivity_max_dfr_j"] = s.passivity_max_dfr_j;
        d["force_scale_final"] = s.force_scale_final;
        return d;
      }, py::arg("scenario"), py::arg("out_dir") = py::none(), py::arg("rtt_s") = py::none(),
      py::arg("loss") = py::none(), py::arg("deadband") = py::none(), py::arg("seed") = py::none(),
      "session::MmtRun: both teleoperation stations in one process over the emulated link "
      "(`terracut mmt`); the summary's figures (forces N, terrain and tracking m, rates per s, "
      "passivity J), and the per-tick files in out_dir when given.");

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
                 haptics::with_derived_fields(s.s->haptics, s.base().blade.length_m);
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

  py::class_<SafetyLimiter>(m, "SafetyLimiter", R"doc(The last stage before a device: clamp, soft start, rate limit, watchdog.

Device units: newtons, seconds. update() never raises for bad samples: a
non-finite force gives zero and is counted.)doc")
      .def(py::init([](double max_force_n, double max_force_rate_n_per_s, double rise_time_s,
                       double watchdog_timeout_s, double watchdog_ramp_s) {
             SafetyParams p;
             p.max_force_n = max_force_n;
             p.max_force_rate_n_per_s = max_force_rate_n_per_s;
             p.rise_time_s = rise_time_s;
             p.watchdog_timeout_s = watchdog_timeout_s;
             p.watchdog_ramp_s = watchdog_ramp_s;
             return SafetyLimiter(p);
           }), py::arg("max_force_n") = 8.0, py::arg("max_force_rate_n_per_s") = 1000.0,
           py::arg("rise_time_s") = 1.0, py::arg("watchdog_timeout_s") = 0.05,
           py::arg("watchdog_ramp_s") = 0.1)
      .def("update", [](SafetyLimiter& s, double t_s, py::object force_n, double last_sample_t_s) {
            // Non-finite values pass: the limiter answers them with zero and counts them.
            auto raw = doubles(force_n, "force_n");
            if (raw.ndim() != 1 || raw.size() != 3) throw InputError("force_n: expected 3 numbers");
            const Vec3 f{raw.data()[0], raw.data()[1], raw.data()[2]};
            const SafetyOutput o = s.update(t_s, f, last_sample_t_s);
            return py::make_tuple(tuple3(o.force_n), o.gain, o.flags.bits());
          }, py::arg("t_s"), py::arg("force_n"), py::arg("last_sample_t_s"),
          "Limits one device force (N) at loop time t_s (s), the newest device sample having "
          "come at last_sample_t_s (s). Returns (force_n, gain, flags): flags bits clamped 1, "
          "rate_limited 2, ramping 4, watchdog 8, nonfinite 16.")
      .def_property_readonly("counters", [](const SafetyLimiter& s) {
            const SafetyCounters& c = s.counters();
            py::dict d;
            d["samples"] = c.samples;
            d["clamped"] = c.clamped;
            d["rate_limited"] = c.rate_limited;
            d["ramping"] = c.ramping;
            d["watchdog"] = c.watchdog;
            d["watchdog_trips"] = c.watchdog_trips;
            d["nonfinite"] = c.nonfinite;
            d["restarts"] = c.restarts;
            return d;
          });
}
