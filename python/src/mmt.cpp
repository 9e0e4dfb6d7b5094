// terracut.run_mmt: both teleoperation stations in one process over the
// emulated link, as `terracut mmt` runs them (session::MmtRun).
#include <cstdint>
#include <filesystem>
#include <optional>

#include "bindings.hpp"
#include "terracut/session/mmt.hpp"

namespace terracut::python {

void bind_mmt(py::module_& m) {
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
}

}  // namespace terracut::python
