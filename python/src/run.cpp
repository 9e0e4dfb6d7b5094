// terracut.run: `terracut run` itself (session::run_scenario): the same
// files on disk, and the run's figures with contact.csv's columns as arrays.
#include <filesystem>

#include "bindings.hpp"
#include "terracut/session/batch.hpp"

namespace terracut::python {
namespace {

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
    d["over_top_m3"] = r.soil->over_top_m3;
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

}  // namespace

void bind_run(py::module_& m) {
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
}

}  // namespace terracut::python
