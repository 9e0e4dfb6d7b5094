// terracut.StepResult and terracut.Simulation: a scenario's session::World
// (the simulation with its listeners, the Bullet bodies included) or a bare
// core Simulation over a numpy array of heights; single and batched steps
// with the GIL released, contact and surface queries, the validated edit
// (Simulation::edit_heights), zero-copy read-only numpy views of the grid's
// layers.
#include <filesystem>
#include <limits>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "bindings.hpp"
#include "terracut/core/surface.hpp"
#include "terracut/io/files.hpp"
#include "terracut/io/image.hpp"
#include "terracut/session/batch.hpp"
#include "terracut/session/world.hpp"

namespace terracut::python {
namespace {

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
                               o.soil.displaced_volume_m3, o.soil.cut_from_ground_m3, o.listener_force_world_n.x,
                               o.listener_force_world_n.y, o.listener_force_world_n.z,
                               o.timers.total_s};
    std::copy(std::begin(rest), std::end(rest), d + kTimePose);
    // The physical force, as force.csv has it (session::force_columns()).
    std::size_t k = kTimePose + kOwn;
    for (const session::ForceColumn& c : session::force_columns()) d[k++] = c.get(o);
    const std::int64_t n[] = {o.step,
                              o.contact.cells_visited + o.cut.cells_visited,
                              o.substeps,
                              o.changed.c0,
                              o.changed.r0,
                              o.changed.c1,
                              o.changed.r1,
                              o.soil.pair_checks,
                              o.soil.reached_cap ? 1 : 0,
                              o.soil.backlog_cells,
                              cut};
    columns_.set(i, d, n);
  }

  py::dict dict() const { return columns_.dict(); }

 private:
  static constexpr std::size_t kOwn = 10;
  static constexpr std::size_t kMaxForce = 64;
  static std::vector<const char*> double_names() {
    std::vector<const char*> names = {"t", "x", "y", "z", "qw", "qx", "qy", "qz", "contact_length",
                                      "section_area", "max_depth", "removed_volume",
                                      "displaced_volume", "cut_from_ground", "listener_fx", "listener_fy",
                                      "listener_fz", "step_s"};
    for (const session::ForceColumn& c : session::force_columns()) names.push_back(c.name);
    return names;
  }
  static std::vector<const char*> int_names(bool with_cut) {
    std::vector<const char*> names = {"step",       "cells_visited", "substeps",   "changed_c0",  "changed_r0",
                                      "changed_c1", "changed_r1",    "soil_work",  "soil_capped", "soil_backlog"};
    if (with_cut) names.push_back("cut");
    return names;
  }

  Columns columns_;
};

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

}  // namespace

void bind_simulation(py::module_& m) {
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
      .def_property_readonly("over_top_m3", [](const StepResult& r) { return r.out.soil.over_top_m3; },
                             "Soil that fell over the blade's top this step (soil flow, blade_height_m), m^3.")
      .def_property_readonly("cells_visited", [](const StepResult& r) {
            return r.out.contact.cells_visited + r.out.cut.cells_visited;
          }, "Cells examined by the contact query and the cut.")
      .def_property_readonly("changed", [](const StepResult& r) { return rect_tuple(r.out.changed); },
                             "(c0, r0, c1, r1): half-open rectangle of samples the step changed.")
      .def_property_readonly("substeps", [](const StepResult& r) { return r.out.substeps; })
      .def_property_readonly("soil_work", [](const StepResult& r) { return r.out.soil.pair_checks; },
                             "The soil relaxation's work this step, neighbour visits (soil flow; at most "
                             "soil.max_pair_checks_per_step).")
      .def_property_readonly("soil_displace_work", [](const StepResult& r) { return r.out.soil.displace_visits; },
                             "What the displacement's walk cost this step, visits (soil flow; not bounded by the "
                             "cap, and taken from soil_budget after a run of steps at rest: docs/soil.md, \"A "
                             "crossing's settle over two steps\").")
      .def_property_readonly("soil_budget", [](const StepResult& r) { return r.out.soil.relax_budget; },
                             "What the soil's settle and passes could do this step, visits: "
                             "soil.max_pair_checks_per_step, less what soil_displace_work took from it.")
      .def_property_readonly("soil_capped", [](const StepResult& r) { return r.out.soil.reached_cap; },
                             "True when the work cap stopped the soil's relaxation this step: what it left "
                             "goes on in later steps, and can change a pushed pile (docs/soil.md).")
      .def_property_readonly("soil_backlog", [](const StepResult& r) { return r.out.soil.backlog_cells; },
                             "Cells left queued for the soil's relaxation after this step.")
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
                                     double rake_angle_deg, double blade_height_m) {
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
            auto model = parse_enum<SoilModel>(soil_model);
            if (!model) throw InputError("soil_model: must be 'vanish' or 'flow', got '" + soil_model + "'");
            p.soil.model = *model;
            p.soil.material = material_arg(soil);
            p.blade.rake_angle_deg = rake_angle_deg;
            p.blade.height_m = blade_height_m;
            if (std::string e = validate(p); !e.empty()) throw InputError(e);
            std::vector<float> h(a.data(), a.data() + a.size());
            return std::make_unique<PySimulation>(p, std::move(h));
          }, py::arg("heights"), py::arg("size_m") = std::make_pair(1.0, 1.0),
          py::arg("origin_m") = py::make_tuple(0.0, 0.0, 0.0), py::arg("representation") = "surface",
          py::arg("rate_hz") = 1000.0, py::arg("blade_length_m") = 1.0,
          py::arg("soil_model") = "vanish", py::arg("soil") = "dry_sand", py::arg("rake_angle_deg") = 90.0,
          py::arg("blade_height_m") = std::numeric_limits<double>::infinity(),
          "A simulation over a (rows, cols) array of heights in metres (copied): size_m = "
          "(size_x, size_z) metres, origin_m the origin corner (y = ground), representation "
          "'surface' or 'columns', rate_hz the step rate (Hz), blade_length_m metres, "
          "soil_model 'vanish' or 'flow', soil the material (a preset name or a dict of the soil: "
          "section's keys), rake_angle_deg the blade's rake (degrees, 90 vertical), blade_height_m "
          "the blade's top above its edge (m; soil flow: what stands higher falls over it; "
          "infinity, the default: unbounded).")
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
contact_length (m), section_area (m^2), max_depth (m), removed_volume (m^3: with
soil flow a pile cut again counts again), displaced_volume (m^3, a pile pushed
on counts at every step), cut_from_ground (m^3, the cut below the initial
surface), listener_fx..fz (N), step_s (s), cells_visited,
substeps, changed_c0, changed_r0, changed_c1, changed_r1, soil_work (the soil
relaxation's neighbour visits), soil_capped (1 where the work cap stopped it),
soil_backlog (cells left queued).)doc")
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
            self.sim().reset();  // tells the listeners (the Bullet world) itself
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
}

}  // namespace terracut::python
