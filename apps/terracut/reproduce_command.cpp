// `terracut reproduce`: the paper's two experiments from the shipped scenario
// files, with an error analysis against exact geometry, a report and figures.
// The experiment definitions are in scenarios/paper_experiment{1,2}.yaml and
// docs/experiments.md.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "commands.hpp"
#include "report_files.hpp"
#include "terracut/core/error.hpp"
#include "terracut/core/generators.hpp"
#include "terracut/io/image.hpp"
#include "terracut/session/batch.hpp"
#include "terracut/io/scenario.hpp"

namespace terracut::cli {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;

// Experiment 1: the paper's five resolutions (Fig. 8) plus two finer ones for
// the convergence table.
constexpr int kFig8Resolutions[] = {5, 15, 25, 35, 50};
constexpr int kExp1Resolutions[] = {5, 15, 25, 35, 50, 100, 200};
constexpr Representation kRepresentations[] = {Representation::kColumns,
                                               Representation::kSurface};
// Experiment 2: the paper's three orders, and (A,B) for the Fig. 13 heightmap.
const std::vector<std::vector<std::string>> kExp2Sequences = {
    {"A", "B", "C"}, {"C", "A", "B"}, {"B", "C", "A"}, {"A", "B"}};
constexpr int kOrdersCompared = 3;  // the first three sequences are complete orders

std::string concat(const std::vector<std::string>& names, std::string_view sep = "") {
  std::string out;
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (i) out += sep;
    out += names[i];
  }
  return out;
}

// Contact-length errors of one experiment-1 run against the exact dome.
struct Exp1Row {
  Representation representation{};
  int resolution = 0;
  double cell_m = 0.0;
  double rms_m = 0.0;
  double max_abs_m = 0.0;
  double mean_abs_m = 0.0;
  std::int64_t dropouts = 0;
  std::int64_t steps = 0;
  double onset_s = NAN;        // first step with measured contact
  double exact_onset_s = NAN;  // first step with exact contact
  double end_s = NAN;          // last step with measured contact
  double exact_end_s = NAN;
  double removed_volume_m3 = 0.0;
  double max_sample_error_m = 0.0;
  double volume_error_m3 = 0.0;
  double p50_step_us = 0.0;
  double p99_step_us = 0.0;
};

struct Exp2Run {
  Representation representation{};
  std::vector<std::string> sequence;
  session::RunResult result;
};

struct OrderMatch {
  Representation representation{};
  std::vector<std::pair<std::string, std::string>> pairs;
  std::vector<double> max_abs_diff_m;
};

// Exact contact of the blade at each recorded pose with the reference dome.
std::vector<double> exact_contact(const io::Scenario& sc, const std::vector<io::StepRecord>& recs) {
  std::vector<double> exact;
  exact.reserve(recs.size());
  for (const io::StepRecord& r : recs)
    exact.push_back(
        contact_length(*sc.reference_mound, sc.origin_m.y, blade_segment(sc.blade, r.pose)));
  return exact;
}

Exp1Row exp1_errors(const io::Scenario& sc, const session::RunResult& run,
                    const std::vector<double>& exact) {
  Exp1Row row;
  row.representation = sc.representation;
  row.resolution = sc.resolution.cols;
  row.cell_m = std::max(sc.size_x_m / sc.resolution.cols, sc.size_z_m / sc.resolution.rows);
  row.steps = std::int64_t(run.records.size());
  double sum_sq = 0.0;
  double sum_abs = 0.0;
  for (std::size_t i = 0; i < run.records.size(); ++i) {
    const double measured = run.records[i].contact.length_m;
    const double t = run.records[i].t_s;
    const double err = measured - exact[i];
    sum_sq += err * err;
    sum_abs += std::abs(err);
    row.max_abs_m = std::max(row.max_abs_m, std::abs(err));
    if (measured > 0.0) {
      if (std::isnan(row.onset_s)) row.onset_s = t;
      row.end_s = t;
    }
    if (exact[i] > 0.0) {
      if (std::isnan(row.exact_onset_s)) row.exact_onset_s = t;
      row.exact_end_s = t;
    }
  }
  // A drop-out: a gap inside the measured contact episode (between its first
  // and last step in contact) where the contact is 0 though the exact one is
  // not. How far the episode's ends are from the exact ones is reported apart
  // (first / last contact times).
  std::size_t first = run.records.size(), last = 0;
  for (std::size_t i = 0; i < run.records.size(); ++i) {
    if (run.records[i].contact.length_m > 0.0) {
      first = std::min(first, i);
      last = i;
    }
  }
  for (std::size_t i = first; i <= last && i < run.records.size(); ++i)
    if (run.records[i].contact.length_m == 0.0 && exact[i] > 0.0) ++row.dropouts;
  const double n = std::max<double>(1.0, double(row.steps));
  row.rms_m = std::sqrt(sum_sq / n);
  row.mean_abs_m = sum_abs / n;
  row.removed_volume_m3 = run.removed_volume_m3;
  row.max_sample_error_m = run.max_sample_error_m;
  row.volume_error_m3 = run.volume_error_m3;
  row.p50_step_us = run.step_timing.p50_us;
  row.p99_step_us = run.step_timing.p99_us;
  return row;
}

std::string rep_name(Representation r) { return std::string(to_string(r)); }

std::string time_or_dash(double t) { return std::isnan(t) ? "-" : fmt("%.3f", t); }

// The keyframes of every cut, as a Markdown table.
std::string cut_table(const io::Scenario& sc) {
  std::ostringstream md;
  md << "| cut | t (s) | position (m) | rotation (deg, X,Y,Z) |\n|---|---|---|---|\n";
  for (const Motion& m : sc.cuts)
    for (const Keyframe& k : m.keyframes) {
      const Vec3 e = euler_deg_from_quat(k.pose.orientation);
      md << "| " << m.name << " | " << fmt("%.3g", k.t_s) << " | ("
         << fmt("%.3g", k.pose.position_m.x) << ", " << fmt("%.3g", k.pose.position_m.y) << ", "
         << fmt("%.3g", k.pose.position_m.z) << ") | (" << fmt("%.4g", e.x + 0.0) << ", "
         << fmt("%.4g", e.y + 0.0) << ", " << fmt("%.4g", e.z + 0.0) << ") |\n";
    }
  return md.str();
}

struct ReportInput {
  fs::path out_dir;
  const io::Scenario* exp1 = nullptr;
  const io::Scenario* exp2 = nullptr;
  std::vector<Exp1Row> exp1_rows;
  std::vector<Exp2Run> exp2_runs;
  std::vector<OrderMatch> matches;
  std::optional<std::string> figures_problem;  // set when the figures could not be made
};

std::string report_markdown(const ReportInput& in) {
  const io::Scenario& e1 = *in.exp1;
  const io::Scenario& e2 = *in.exp2;
  const MoundShape& ref = *e1.reference_mound;
  std::ostringstream md;
  md << "# terracut: the paper's experiments reproduced\n\n"
     << "Written by `terracut reproduce` (terracut " TERRACUT_VERSION ") from `"
     << e1.source_path.string() << "` and `" << e2.source_path.string()
     << "`. The experiments and the cuts are defined in `docs/experiments.md`. "
     << "All lengths in metres, volumes in cubic metres, times in seconds.\n\n";
  if (in.figures_problem) {
    md << "> **The figures could not be made:** " << *in.figures_problem
       << "\n> The numbers below and the CSV/NumPy outputs are complete.\n\n";
  }

  // ---- Experiment 1 --------------------------------------------------------
  const Motion& cut1 = e1.cuts[std::size_t(e1.sequence.front())];
  const Vec3 p0 = cut1.keyframes.front().pose.position_m;
  const Vec3 p1 = cut1.keyframes.back().pose.position_m;
  md << "## Experiment 1: contact length against resolution\n\n"
     << "Terrain `" << e1.image_path.filename().string() << "` (a dome of peak "
     << fmt("%.3g", ref.height_m) << " m and radius " << fmt("%.3g", ref.radius_m)
     << " m centred at (" << fmt("%.3g", ref.centre_x_m) << ", " << fmt("%.3g", ref.centre_z_m)
     << ")) over " << fmt("%.3g", e1.size_x_m) << " m x " << fmt("%.3g", e1.size_z_m)
     << " m, resampled to each resolution. One horizontal cut: a blade of "
     << fmt("%.3g", e1.blade.length_m) << " m along X at height y = " << fmt("%.3g", p0.y)
     << " m moves along Z from z = " << fmt("%.3g", p0.z) << " to z = " << fmt("%.3g", p1.z)
     << " m in " << fmt("%.3g", cut1.duration_s()) << " s, stepped at "
     << fmt("%.4g", e1.rate_hz) << " Hz.\n\n"
     << "Exact contact: the chord of the dome's circular section, 2*sqrt(r^2 - (z - zc)^2) with "
     << "r = R*sqrt(1 - (y/H)^2) = " << fmt("%.4f", ref.radius_m * std::sqrt(1.0 - std::pow((p0.y - e1.origin_m.y) / ref.height_m, 2)))
     << " m (peak chord " << fmt("%.4f", 2.0 * ref.radius_m * std::sqrt(1.0 - std::pow((p0.y - e1.origin_m.y) / ref.height_m, 2)))
     << " m). Errors are measured - exact over all " << (in.exp1_rows.empty() ? 0 : in.exp1_rows[0].steps)
     << " steps. A drop-out is a gap inside the measured contact episode: a step between the first "
     << "and the last step in contact where the contact is 0 although the exact chord is not. How far "
     << "the episode starts and ends from the exact one is in the last two columns (the blade moves "
     << fmt("%.3g", length(p1 - p0) / cut1.duration_s() / e1.rate_hz * 1000.0) << " mm per step).\n\n";
  md << "| representation | resolution | cell (m) | RMS error (m) | max abs error (m) | mean abs error (m) | drop-out steps | first contact (s), measured / exact | last contact (s), measured / exact |\n"
     << "|---|---|---|---|---|---|---|---|---|\n";
  for (const Exp1Row& r : in.exp1_rows)
    md << "| " << rep_name(r.representation) << " | " << r.resolution << "x" << r.resolution
       << " | " << fmt("%.4g", r.cell_m) << " | " << fmt("%.4f", r.rms_m) << " | "
       << fmt("%.4f", r.max_abs_m) << " | " << fmt("%.4f", r.mean_abs_m) << " | " << r.dropouts
       << " | " << time_or_dash(r.onset_s) << " / " << time_or_dash(r.exact_onset_s) << " | "
       << time_or_dash(r.end_s) << " / " << time_or_dash(r.exact_end_s) << " |\n";
  md << "\n";

  // Findings computed from the table (nothing here is typed in by hand).
  for (Representation rep : kRepresentations) {
    std::vector<const Exp1Row*> rows;
    for (const Exp1Row& r : in.exp1_rows)
      if (r.representation == rep) rows.push_back(&r);
    if (rows.empty()) continue;
    bool falling = true;
    for (std::size_t i = 1; i < rows.size(); ++i)
      if (!(rows[i]->rms_m < rows[i - 1]->rms_m)) falling = false;
    std::int64_t dropouts_from_50 = 0;
    for (const Exp1Row* r : rows)
      if (r->resolution >= 50) dropouts_from_50 += r->dropouts;
    md << "- **" << rep_name(rep) << "**: RMS error " << fmt("%.4f", rows.front()->rms_m)
       << " m at " << rows.front()->resolution << "x" << rows.front()->resolution << ", "
       << fmt("%.4f", rows.back()->rms_m) << " m at " << rows.back()->resolution << "x"
       << rows.back()->resolution << "; "
       << (falling ? "falls at every finer resolution" : "does not fall at every finer resolution")
       << "; drop-out steps from 50x50 up: " << dropouts_from_50 << ".\n";
  }
  md << "\n";
  if (!in.figures_problem) {
    for (Representation rep : kRepresentations)
      md << "![Contact length over time, " << rep_name(rep) << " (the paper's Fig. 8)](fig8_"
         << rep_name(rep) << ".png)\n\n";
    md << "![RMS contact error against resolution](convergence.png)\n\n";
  }

  // ---- Experiment 2 --------------------------------------------------------
  md << "## Experiment 2: sequences of cuts on a cube\n\n"
     << "Terrain: a " << e2.resolution.cols << "x" << e2.resolution.rows
     << " all-white square, " << fmt("%.3g", e2.size_x_m) << " m x " << fmt("%.3g", e2.size_z_m)
     << " m, full scale " << fmt("%.3g", e2.full_scale_m) << " m (a cube). Blade "
     << fmt("%.3g", e2.blade.length_m) << " m. Cuts (rotation as extrinsic X, Y, Z Euler "
     << "angles; between keyframes position is linear and rotation slerp):\n\n"
     << cut_table(e2) << "\n";
  for (Representation rep : kRepresentations) {
    md << "### " << rep_name(rep) << "\n\n"
       << "| sequence | cut | start (s) | peak contact (m) | mean contact (m) | volume removed (m^3) |\n"
       << "|---|---|---|---|---|---|\n";
    for (const Exp2Run& run : in.exp2_runs) {
      if (run.representation != rep) continue;
      for (const session::CutStats& c : run.result.cuts)
        md << "| (" << concat(run.sequence, ",") << ") | " << c.name << " | "
           << fmt("%.3f", c.start_t_s) << " | " << fmt("%.4f", c.peak_contact_m) << " | "
           << fmt("%.4f", c.mean_contact_m) << " | " << fmt("%.5f", c.removed_volume_m3)
           << " |\n";
    }
    md << "\n";
  }
  md << "Final heights of the complete orders compared sample by sample (height.npy):\n\n"
     << "| representation | orders compared | max abs height difference (m) | final shapes match |\n"
     << "|---|---|---|---|\n";
  for (const OrderMatch& m : in.matches) {
    double worst = 0.0;
    std::string pairs;
    for (std::size_t i = 0; i < m.pairs.size(); ++i) {
      worst = std::max(worst, m.max_abs_diff_m[i]);
      if (i) pairs += ", ";
      pairs += m.pairs[i].first + " vs " + m.pairs[i].second;
    }
    md << "| " << rep_name(m.representation) << " | " << pairs << " | " << fmt("%.3g", worst)
       << " | " << (worst == 0.0 ? "yes (identical)" : "no") << " |\n";
  }
  md << "\n";
  if (!in.figures_problem) {
    for (Representation rep : kRepresentations)
      md << "![Contact length for three sequences, " << rep_name(rep) << " (Fig. 9)](fig9_"
         << rep_name(rep) << ".png)\n\n";
    for (Representation rep : kRepresentations)
      md << "![Heights after (A,B), " << rep_name(rep) << " (Fig. 13)](fig13_" << rep_name(rep)
         << ".png)\n\n![Heights after all cuts, " << rep_name(rep) << " (Fig. 14)](fig14_"
         << rep_name(rep) << ".png)\n\n";
  }

  // ---- Conservation and timing --------------------------------------------
  double worst_sample = 0.0;
  double worst_volume = 0.0;
  for (const Exp1Row& r : in.exp1_rows) {
    worst_sample = std::max(worst_sample, r.max_sample_error_m);
    worst_volume = std::max(worst_volume, std::abs(r.volume_error_m3));
  }
  for (const Exp2Run& r : in.exp2_runs) {
    worst_sample = std::max(worst_sample, r.result.max_sample_error_m);
    worst_volume = std::max(worst_volume, std::abs(r.result.volume_error_m3));
  }
  md << "## Conservation\n\n"
     << "Over every run above: max |height + removed - initial| per sample = "
     << fmt("%.3g", worst_sample) << " m; max |initial - final - removed| volume = "
     << fmt("%.3g", worst_volume) << " m^3.\n\n";
  md << "## Step time (this machine; the only non-deterministic numbers)\n\n"
     << "| representation | resolution | p50 step (us) | p99 step (us) |\n|---|---|---|---|\n";
  for (const Exp1Row& r : in.exp1_rows)
    md << "| " << rep_name(r.representation) << " | " << r.resolution << "x" << r.resolution
       << " | " << fmt("%.2f", r.p50_step_us) << " | " << fmt("%.2f", r.p99_step_us) << " |\n";
  md << "\n## Files\n\n"
     << "- `exp1/<representation>/<N>/`: `terracut run` outputs (contact.csv, height/removed "
        ".npy and .png, summary.json) for each resolution N.\n"
     << "- `exp1/exact.csv`: the exact contact length at every step (t, z, exact_contact).\n"
     << "- `exp1/errors.csv`: the table above as CSV.\n"
     << "- `exp2/<representation>/<sequence>/`: `terracut run` outputs for each sequence.\n"
     << "- `reproduce.json`: what was run, for `tools/plot_reproduce.py`.\n";
  return md.str();
}

}  // namespace

Command add_reproduce_command(CLI::App& app) {
  struct Options : ReportOptions {
    std::string scenarios = TERRACUT_SCENARIOS_DIR;
  };
  auto opt = std::make_shared<Options>();

  CLI::App* sub = app.add_subcommand(
      "reproduce",
      "Reproduce the paper's two experiments from the shipped scenario files: run them for\n"
      "both representations, compare the contact length with exact geometry, and write the\n"
      "outputs, a report (report.md) and figures into a folder.");
  add_report_options(*sub, *opt, "plot_reproduce.py",
                     "Do not make figures (report.md then has tables only); exit code 0");
  sub->add_option("--scenarios", opt->scenarios,
                  "Folder holding paper_experiment1.yaml and paper_experiment2.yaml")
      ->capture_default_str()
      ->type_name("DIR");
  sub->footer(
      "Experiment 1 (paper_experiment1.yaml): a mound image, one horizontal cut through it,\n"
      "run at 5x5, 15x15, 25x25, 35x35, 50x50, 100x100 and 200x200 for the 'columns' and\n"
      "'surface' representations; contact length compared with the exact chord of the\n"
      "dome's circular section (RMS, max and mean absolute error, drop-outs).\n"
      "Experiment 2 (paper_experiment2.yaml): a 35x35 cube and cuts A, B, C run in the\n"
      "orders (A,B,C), (C,A,B), (B,C,A) and (A,B); peak and mean contact and volume per cut;\n"
      "final heights of the three orders compared sample by sample.\n"
      "\n"
      "Outputs in DIR:\n"
      "  report.md                       the numbers, with the figures embedded\n"
      "  exp1/<rep>/<N>/, exp2/<rep>/<ABC>/  outputs of `terracut run` for each run\n"
      "  exp1/exact.csv, exp1/errors.csv the exact contact per step; the error table\n"
      "  fig8_<rep>.png                  contact vs time, 5 resolutions + exact (Fig. 8)\n"
      "  fig9_<rep>.png                  contact vs time for the three orders (Fig. 9)\n"
      "  fig13_<rep>.png, fig14_<rep>.png  heights after (A,B) and after all cuts\n"
      "  convergence.png                 RMS error vs resolution, both representations\n"
      "  reproduce.json                  what was run (read by the plot script)\n"
      "Figures are drawn by `PYTHON TOOLS/plot_reproduce.py DIR` (matplotlib). If that\n"
      "fails, report.md is still written and the exit code is 3.");

  return [opt]() {
    const fs::path out(opt->out);
    create_output_folder(out);
    auto say = [&](const std::string& line) {
      if (!opt->quiet) std::cerr << "reproduce: " << line << "\n" << std::flush;
    };

    const session::Scenario exp1_file =
        session::load_scenario(fs::path(opt->scenarios) / "paper_experiment1.yaml");
    const session::Scenario exp2_file =
        session::load_scenario(fs::path(opt->scenarios) / "paper_experiment2.yaml");
    const io::Scenario& exp1 = exp1_file.base;
    const io::Scenario& exp2 = exp2_file.base;
    if (!exp1.reference_mound)
      throw InputError(exp1.source_path.string() +
                       ": reference: experiment 1 needs a 'reference: mound:' block for the "
                       "exact contact length");

    ReportInput report;
    report.out_dir = out;
    report.exp1 = &exp1;
    report.exp2 = &exp2;

    // Experiment 1: every representation and resolution.
    std::vector<double> exact;
    std::vector<io::StepRecord> exact_records;
    for (Representation rep : kRepresentations)
      for (int n : kExp1Resolutions) {
        session::Scenario run_sc = exp1_file;
        io::apply_overrides(run_sc.base, io::Resolution{n, n}, rep, std::nullopt);
        const io::Scenario& sc = run_sc.base;
        session::RunOptions ro;
        ro.out_dir = out / "exp1" / rep_name(rep) / std::to_string(n);
        ro.keep_records = true;
        ro.progress = opt->quiet ? nullptr : &std::cerr;
        ro.progress_label = "reproduce: exp1 " + rep_name(rep) + " " + std::to_string(n);
        session::RunResult run = session::run_scenario(run_sc, ro);
        const std::vector<double> run_exact = exact_contact(sc, run.records);
        if (exact.empty()) {
          // Every run steps the same motion; its first run's poses give exact.csv.
          exact = run_exact;
          exact_records = run.records;
        }
        report.exp1_rows.push_back(exp1_errors(sc, run, run_exact));
        const Exp1Row& r = report.exp1_rows.back();
        say("exp1 " + rep_name(rep) + " " + std::to_string(n) + "x" + std::to_string(n) + ": " +
            std::to_string(run.steps) + " steps, RMS error " + fmt("%.4f", r.rms_m) + " m, " +
            std::to_string(r.dropouts) + " drop-outs, " + fmt("%.2f", run.wall_s) + " s");
      }

    // The exact contact and the error table as CSV, for the plots.
    {
      std::string csv = "t,z,exact_contact\n";
      char line[128];
      for (std::size_t i = 0; i < exact_records.size(); ++i) {
        std::snprintf(line, sizeof line, "%.9g,%.9g,%.9g\n", exact_records[i].t_s,
                      exact_records[i].pose.position_m.z, exact[i]);
        csv += line;
      }
      write_file(out / "exp1" / "exact.csv", csv);
      std::string table =
          "representation,resolution,cell_m,rms_m,max_abs_m,mean_abs_m,dropouts,steps\n";
      for (const Exp1Row& r : report.exp1_rows) {
        std::snprintf(line, sizeof line, "%s,%d,%.9g,%.9g,%.9g,%.9g,%lld,%lld\n",
                      rep_name(r.representation).c_str(), r.resolution, r.cell_m, r.rms_m,
                      r.max_abs_m, r.mean_abs_m, static_cast<long long>(r.dropouts),
                      static_cast<long long>(r.steps));
        table += line;
      }
      write_file(out / "exp1" / "errors.csv", table);
    }

    // Experiment 2: every representation and order.
    for (Representation rep : kRepresentations) {
      for (const std::vector<std::string>& seq : kExp2Sequences) {
        session::Scenario sc = exp2_file;
        io::apply_overrides(sc.base, std::nullopt, rep, seq);
        session::RunOptions ro;
        ro.out_dir = out / "exp2" / rep_name(rep) / concat(seq);
        ro.progress = opt->quiet ? nullptr : &std::cerr;
        ro.progress_label = "reproduce: exp2 " + rep_name(rep) + " " + concat(seq);
        Exp2Run run{rep, seq, session::run_scenario(sc, ro)};
        say("exp2 " + rep_name(rep) + " (" + concat(seq, ",") + "): " +
            std::to_string(run.result.steps) + " steps, removed " +
            fmt("%.5f", run.result.removed_volume_m3) + " m^3, " + fmt("%.2f", run.result.wall_s) +
            " s");
        report.exp2_runs.push_back(std::move(run));
      }
      // Compare the final heights of the complete orders, as written to disk.
      OrderMatch match;
      match.representation = rep;
      std::vector<std::vector<float>> heights;
      for (int k = 0; k < kOrdersCompared; ++k) {
        int rows = 0;
        int cols = 0;
        heights.push_back(io::read_npy(
            out / "exp2" / rep_name(rep) / concat(kExp2Sequences[std::size_t(k)]) / "height.npy",
            &rows, &cols));
      }
      for (int a = 0; a < kOrdersCompared; ++a)
        for (int b = a + 1; b < kOrdersCompared; ++b) {
          double worst = 0.0;
          if (heights[std::size_t(a)].size() != heights[std::size_t(b)].size()) {
            worst = INFINITY;
          } else {
            for (std::size_t i = 0; i < heights[std::size_t(a)].size(); ++i)
              worst = std::max(worst, double(std::abs(heights[std::size_t(a)][i] -
                                                      heights[std::size_t(b)][i])));
          }
          match.pairs.emplace_back(concat(kExp2Sequences[std::size_t(a)]),
                                   concat(kExp2Sequences[std::size_t(b)]));
          match.max_abs_diff_m.push_back(worst);
        }
      report.matches.push_back(match);
    }

    // What was run, for the plot script.
    {
      Json meta;
      Json reps = Json::array();
      for (Representation rep : kRepresentations) reps.push_back(rep_name(rep));
      meta["representations"] = reps;
      meta["exp1"] = {{"resolutions", kExp1Resolutions},
                      {"fig8_resolutions", kFig8Resolutions},
                      {"exact_csv", "exp1/exact.csv"},
                      {"errors_csv", "exp1/errors.csv"},
                      {"reference_mound",
                       {{"centre_m", {exp1.reference_mound->centre_x_m, exp1.reference_mound->centre_z_m}},
                        {"radius_m", exp1.reference_mound->radius_m},
                        {"height_m", exp1.reference_mound->height_m}}}};
      Json seqs = Json::array();
      for (int k = 0; k < kOrdersCompared; ++k) seqs.push_back(concat(kExp2Sequences[std::size_t(k)]));
      meta["exp2"] = {{"sequences", seqs},
                      {"after_ab", concat(kExp2Sequences.back())},
                      {"after_all", concat(kExp2Sequences.front())},
                      {"size_m", {exp2.size_x_m, exp2.size_z_m}},
                      {"origin_m", {exp2.origin_m.x, exp2.origin_m.y, exp2.origin_m.z}},
                      {"full_scale_m", exp2.full_scale_m}};
      write_file(out / "reproduce.json", meta.dump(2) + "\n");
    }

    write_file(out / "report.md", report_markdown(report));
    if (opt->no_plots) {
      say("figures skipped (--no-plots); report: " + (out / "report.md").string());
      return kExitOk;
    }

    // Figures, by the plot script; on failure the report says so.
    const std::optional<std::string> problem =
        draw_figures(opt->python, fs::path(opt->tools) / "plot_reproduce.py", out, opt->quiet, say);
    if (problem) {
      report.figures_problem = problem;
      write_file(out / "report.md", report_markdown(report));
      std::cerr << "terracut reproduce: error: figures not made: " << *problem
                << "\nThe report without figures is in " << (out / "report.md").string() << "\n";
      return kExitNoFigures;
    }
    say("report: " + (out / "report.md").string());
    return kExitOk;
  };
}

}  // namespace terracut::cli
