// The Python module's own toolkit (terracut._terracut, python/src/): what
// its files share. module.cpp defines the module and calls one bind_*
// function per area, each in its own file:
//
//   scenario.cpp     Scenario (session::load_scenario, parse_scenario,
//                    heightmap_scenario, io::apply_overrides), the YAML reader
//                    for the sweeps' dicts, the argument readers of scenarios
//   simulation.cpp   StepResult, Simulation (a session::World or a bare core
//                    Simulation; steps, queries, edits, numpy views)
//   run.cpp          terracut.run (session::run_scenario)
//   mmt.cpp          terracut.run_mmt (session::MmtRun)
//   forces.cpp       soil materials, the earthmoving equation, ForceModel
//   safety.cpp       SafetyLimiter
//   calibration.cpp  calibrate_tests, calibrate_record (terracut::validation)
//   arguments.cpp    Python arguments read into terracut's types
//
// Every bad Python argument is a terracut::InputError naming it, which the
// module turns into terracut.InputError (a ValueError).
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "terracut/core/error.hpp"
#include "terracut/core/simulation.hpp"
#include "terracut/io/scenario.hpp"
#include "terracut/session/scenario.hpp"

namespace py = pybind11;

namespace terracut::python {

// ---------------------------------------------------------------------------
// The areas, in the order the module registers them (a class is registered
// before the functions whose signatures name it).
// ---------------------------------------------------------------------------

void bind_scenario(py::module_& m);
void bind_simulation(py::module_& m);
void bind_run(py::module_& m);
void bind_mmt(py::module_& m);
void bind_forces(py::module_& m);
void bind_calibration(py::module_& m);
void bind_safety(py::module_& m);

// ---------------------------------------------------------------------------
// Argument conversion (arguments.cpp): every bad Python argument is an
// InputError naming it.
// ---------------------------------------------------------------------------

/// An array's shape as Python writes it: "(3,)", "(2, 7)".
std::string shape_text(const py::array& a);

/// A C-contiguous float64 copy (or view) of any array-like; InputError naming
/// `what` when it holds something that is not a number.
py::array_t<double, py::array::c_style | py::array::forcecast> doubles(py::handle obj,
                                                                         const std::string& what);

/// Exactly N finite numbers.
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
/// Three finite numbers.
Vec3 vec3(py::handle obj, const std::string& what);

py::tuple tuple3(const Vec3& v);
py::tuple tuple4(const Quat& q);
/// (c0, r0, c1, r1), half-open.
py::tuple rect_tuple(const Rect& r);

/// A pose as 7 numbers x, y, z, qw, qx, qy, qz: finite, the quaternion not zero.
BladePose pose_from(const double* p, const std::string& what);
/// Fast path for a single pose given as a tuple or list of 7 numbers: false
/// (nothing read) when obj is not one.
bool pose_from_sequence(py::handle obj, BladePose* pose);

inline constexpr const char* kPoseShape =
    "pose: expected 7 numbers [x, y, z, qw, qx, qy, qz] (metres, unit quaternion) or an (N, 7) "
    "array of them";

/// A soil material given as a preset name or a dict of SoilMaterial fields
/// (forces.cpp).
SoilMaterial material_arg(py::handle obj);
/// A soil material as a dict: the keys of a scenario's soil: section.
py::dict material_dict(const SoilMaterial& s);

// ---------------------------------------------------------------------------
// Scenarios (scenario.cpp)
// ---------------------------------------------------------------------------

struct PyScenario {
  std::shared_ptr<const session::Scenario> s;
  const io::Scenario& base() const { return s->base; }
};

/// A cut of the scenario by name or index; InputError naming it otherwise.
int cut_index(const io::Scenario& sc, py::handle cut);
/// The command line's --resolution: None, N, [cols, rows] or "COLSxROWS".
std::optional<io::Resolution> resolution_arg(py::handle obj);
/// None, 'surface' or 'columns'.
std::optional<Representation> representation_arg(py::handle obj);

// ---------------------------------------------------------------------------
// Per-step output columns (the simulation's steps, the batch run's records)
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
inline void time_pose(double t_s, const BladePose& p, double* out) {
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

}  // namespace terracut::python
