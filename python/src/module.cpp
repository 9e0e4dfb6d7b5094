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
//
// This file defines the module; each area is bound in its own file
// (bindings.hpp lists them).
#include "bindings.hpp"
#include "terracut/session/world.hpp"

PYBIND11_MODULE(_terracut, m) {
  using namespace terracut;
  using namespace terracut::python;
  m.doc() =
      "terracut's compiled core: scenarios, the simulation, batch runs, forces. SI units "
      "throughout (metres, seconds, newtons); world frame right-handed, Y up, ground plane X-Z.";

  py::register_exception<InputError>(m, "InputError", PyExc_ValueError);
  // The version `terracut --version` prints (the project's, CMakeLists.txt).
  m.attr("__version__") = TERRACUT_VERSION;

  m.def("bodies_available", &session::bodies_available,
        "True when this build has the rigid-body engine (Bullet).");

  bind_scenario(m);
  bind_simulation(m);
  bind_run(m);
  bind_mmt(m);
  bind_forces(m);
  bind_calibration(m);
  bind_safety(m);
}
