// `terracut run`: one scenario, outputs into a folder.
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>
#include <string>

#include "commands.hpp"
#include "terracut/core/error.hpp"
#include "terracut/io/scenario.hpp"
#include "terracut/session/batch.hpp"

namespace terracut::cli {

Command add_run_command(CLI::App& app) {
  struct Options {
    std::string scenario;
    std::string out;
    std::string resolution;
    std::string representation;
    std::string sequence;
    bool quiet = false;
    bool realtime = false;
  };
  auto opt = std::make_shared<Options>();

  CLI::App* sub = app.add_subcommand(
      "run",
      "Run one scenario: perform its cuts at the fixed step rate and write the contact log,\n"
      "the final heightmaps and a summary into an output folder.");
  sub->add_option("scenario", opt->scenario,
                  "Scenario file (YAML; format in docs/scenario-format.md)")
      ->required()
      ->type_name("SCENARIO.yaml");
  sub->add_option("--out,-o", opt->out,
                  "Output folder; created if missing. Output files of the same names are\n"
                  "replaced; if the run stops with an error, none of them is left behind")
      ->required()
      ->type_name("DIR");
  sub->add_option("--resolution", opt->resolution,
                  "Grid resolution overriding the scenario's terrain.resolution: N for N x N\n"
                  "samples, or COLSxROWS (e.g. 64x32; cols along X, rows along Z), each side in\n"
                  "[1, 65536]. Image terrain is resampled (area average when shrinking, bilinear\n"
                  "when enlarging). Default: the scenario's")
      ->type_name("N|COLSxROWS");
  sub->add_option("--representation", opt->representation,
                  "How samples are read as a solid, overriding the scenario's: 'surface' (a\n"
                  "continuous surface through the cell-centred samples) or 'columns' (the\n"
                  "paper's boxes). Default: the scenario's (itself 'surface' by default)")
      ->check(CLI::IsMember({"surface", "columns"}))
      ->type_name("REP");
  sub->add_option("--sequence", opt->sequence,
                  "Order of the cuts to run, as cut names separated by commas (names may\n"
                  "repeat), overriding the scenario's sequence. Default: the scenario's\n"
                  "sequence, or its cuts in the order listed")
      ->type_name("A,B,C");
  sub->add_flag("--realtime", opt->realtime,
                "Pace the steps to the wall clock at the scenario's rate_hz (absolute\n"
                "deadlines, sleep then a short spin), as a haptic loop would, and add a\n"
                "\"realtime\" entry to summary.json: step time and period jitter (p50, p99,\n"
                "max, us) and the number of missed deadlines, so you can see whether your\n"
                "terrain and blade fit the budget on this machine. Default: as fast as possible");
  sub->add_flag("--quiet,-q", opt->quiet,
                "No progress lines on stderr and no summary line on stdout (errors are still\n"
                "printed)");
  sub->footer(
      "Each cut of the sequence is a separate stroke: the blade is lifted, then stepped\n"
      "at t = i / rate_hz for i = 0 .. round(duration * rate_hz) through the cut's keyframes\n"
      "(position linear, rotation slerp). Each step measures contact, then cuts what the\n"
      "blade swept since the previous step.\n"
      "\n"
      "Outputs in DIR:\n"
      "  contact.csv   one row per step; columns (SI units):\n"
      "                  t               global simulation time of the step, s\n"
      "                  cut             name of the cut\n"
      "                  x,y,z           blade centre, world m\n"
      "                  qw,qx,qy,qz     blade orientation (unit quaternion, blade -> world)\n"
      "                  contact_length  length of the blade inside material, m (measured\n"
      "                                  before the step's cut)\n"
      "                  removed_volume  volume cut in this step, m^3\n"
      "                  section_area    integral of (surface - blade) depth along the\n"
      "                                  contact, m^2\n"
      "                  max_depth       deepest point of the blade below the surface, m\n"
      "                  cells_visited   cells examined by the contact query and the cut\n"
      "  force.csv     one row per step: the physical force on the tool, world N, whatever a\n"
      "                device would render (docs/forces.md): t,cut, fx,fy,fz (the total),\n"
      "                its parts cutting_*, surcharge_* (the pile), penetration_y,\n"
      "                twist_x,twist_z,twist_torque (N m), load_* (a bucket's soil),\n"
      "                bodies_*, and cut_depth,cut_width,pile_height (m), vx,vy,vz (m/s)\n"
      "  height.npy    final heights, float32 (rows, cols), m above ground, row r along +Z\n"
      "  removed.npy   removed material, float32 (rows, cols), m\n"
      "  height.png    final heights, 16-bit grey, pixel = height / full_scale_m\n"
      "  removed.png   removed material, 16-bit grey, pixel = removed / full_scale_m\n"
      "  bodies.csv    only when the scenario has bodies: one row per body per step,\n"
      "                t,body,name,x,y,z,qw,qx,qy,qz,vx,vy,vz (SI; Bullet rigid bodies\n"
      "                on the same terrain; plot with tools/plot_bodies.py DIR)\n"
      "  summary.json  inputs, steps, initial/final/removed volume (m^3), conservation\n"
      "                error, per-cut peak/mean contact, removed volume and physical force\n"
      "                (mean and peak), the soil material, and per-step\n"
      "                timing percentiles (us; the only part that differs between runs);\n"
      "                with --realtime also \"realtime\": missed_deadlines, step_time and\n"
      "                period_jitter {p50_us, p99_us, max_us, mean_us}; with soil\n"
      "                model flow also \"soil\": cut_from_ground_m3 (what the blade cut\n"
      "                below the initial surface), displaced_volume_m3 (what it pushed,\n"
      "                a pile pushed on counted at every step), net_moved_m3 (soil no\n"
      "                longer where it was at the end); summary.json's removed volume\n"
      "                is then every step's cut, the pushed pile counted again\n"
      "\n"
      "Progress is printed to stderr about once a second for runs longer than 2 s.\n"
      "Plot a run with: /usr/bin/python3 tools/plot_run.py DIR\n"
      "\n"
      "Example:\n"
      "  terracut run scenarios/paper_experiment1.yaml --out out/exp1 --resolution 50 \\\n"
      "      --representation columns");

  return [opt]() {
    session::Scenario scenario = session::load_scenario(opt->scenario);
    std::optional<io::Resolution> resolution;
    if (!opt->resolution.empty()) resolution = io::parse_resolution(opt->resolution);
    std::optional<Representation> representation;
    if (!opt->representation.empty())
      representation = parse_enum<Representation>(opt->representation);
    std::optional<std::vector<std::string>> sequence;
    if (!opt->sequence.empty()) sequence = io::parse_name_list(opt->sequence);
    io::apply_overrides(scenario.base, resolution, representation, sequence);

    session::RunOptions run_options;
    run_options.out_dir = opt->out;
    run_options.progress = opt->quiet ? nullptr : &std::cerr;
    run_options.progress_label = "terracut run " + scenario.base.name;
    run_options.realtime = opt->realtime;
    const session::RunResult result = session::run_scenario(scenario, run_options);
    for (const std::string& w : result.warnings) std::cerr << "terracut run: warning: " << w << "\n";

    if (!opt->quiet) {
      char line[512];
      // With soil that flows the edge cuts a pushed pile again at every
      // step, so the sum of the steps' cuts is not soil removed: name the
      // ground cut, the soil pushed and the net soil moved instead.
      char volumes[256];
      if (result.soil) {
        const int n = std::snprintf(
            volumes, sizeof volumes,
            "cut from the ground %.6g m^3, displaced %.6g m^3 (each push counted), net moved %.6g m^3",
            result.soil->cut_from_ground_m3, result.soil->displaced_volume_m3, result.soil->net_moved_m3);
        // A blade with a top (blade.height_m): what fell over it.
        if (std::isfinite(scenario.base.blade.height_m) && n > 0 && std::size_t(n) < sizeof volumes)
          std::snprintf(volumes + n, sizeof volumes - std::size_t(n), ", over the blade's top %.6g m^3",
                        result.soil->over_top_m3);
      } else
        std::snprintf(volumes, sizeof volumes, "removed %.6g m^3", result.removed_volume_m3);
      std::snprintf(line, sizeof line,
                    "%s: %lld steps, %s of %.6g m^3, conservation error %.3g m "
                    "(per sample), %.3g m^3 (volume), p99 step %.1f us -> %s\n",
                    scenario.base.name.c_str(), static_cast<long long>(result.steps), volumes,
                    result.initial_volume_m3, result.max_sample_error_m, result.volume_error_m3,
                    result.step_timing.p99_us, opt->out.c_str());
      std::cout << line;
      if (result.realtime) {
        // A readable line; the full figures are in summary.json's "realtime".
        const haptics::LoopStats& rt = *result.realtime;
        std::snprintf(line, sizeof line,
                      "realtime at %.0f Hz: %lld ticks, %lld missed deadlines; step p50 %.1f us, "
                      "p99 %.1f us; period jitter p99 %.1f us, max %.1f us (summary.json: "
                      "realtime)\n",
                      rt.rate_hz, static_cast<long long>(rt.ticks),
                      static_cast<long long>(rt.missed_deadlines), rt.compute.p50_s * 1e6,
                      rt.compute.p99_s * 1e6, rt.period_jitter.p99_s * 1e6,
                      rt.period_jitter.max_s * 1e6);
        std::cout << line;
      }
    }
    return kExitOk;
  };
}

}  // namespace terracut::cli
