// terracut.SafetyLimiter: the last stage before a device (clamp, soft start,
// rate limit, watchdog), in device newtons and seconds.
#include "bindings.hpp"
#include "terracut/core/safety.hpp"

namespace terracut::python {

void bind_safety(py::module_& m) {
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

}  // namespace terracut::python
