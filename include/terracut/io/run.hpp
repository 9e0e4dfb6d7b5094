// Running a scenario: builds the simulation, performs the cuts of the
// scenario's sequence at the fixed rate, and writes the outputs of
// `terracut run` into a folder:
//
//   contact.csv   one row per step:
//                 t,cut,x,y,z,qw,qx,qy,qz,contact_length,removed_volume,
//                 section_area,max_depth,cells_visited
//   height.npy    float32 (rows, cols) final heights, metres
//   removed.npy   float32 (rows, cols) removed material, metres
//   height.png    16-bit grey, pixel = height / full_scale_m
//   removed.png   16-bit grey, pixel = removed / full_scale_m
//   summary.json  inputs, step count, volumes, conservation error, per-cut
//                 results and per-step timing percentiles
//
// Everything except the "timing" object of summary.json is bitwise identical
// between two runs of the same scenario on the same build.
#pragma once

#include <cstdint>
#include <filesystem>
#include <iosfwd>
#include <string>
#include <vector>

#include "terracut/core/simulation.hpp"
#include "terracut/io/scenario.hpp"

namespace terracut::io {

/// The file names written into the output folder, in writing order
/// (summary.json last, so its presence means the run completed).
inline constexpr const char* kRunOutputFiles[] = {"contact.csv", "height.npy", "removed.npy",
                                                  "height.png",  "removed.png", "summary.json"};

/// An engine that follows the run step by step (the Bullet world, a
/// real-time pacer). Its hooks are called on the run's thread, in order:
/// start once, then per cut lifted and per step before_step / stepped, then
/// finish, which writes its own files into the output folder.
class RunObserver {
 public:
  virtual ~RunObserver() = default;
  /// Before the first step; the simulation lives until finish() returns.
  virtual void start(Simulation& sim, const std::filesystem::path& out_dir) = 0;
  /// The blade was lifted: the next step starts a new cut.
  virtual void lifted() {}
  /// Just before a step.
  virtual void before_step() {}
  /// Just after a step.
  virtual void stepped(const StepOutput& out) = 0;
  /// After the last step: write files; throw terracut::InputError naming a file on failure.
  virtual void finish() {}
  /// Key and JSON object text added to summary.json (empty key: nothing added).
  virtual std::string summary_key() const { return {}; }
  virtual std::string summary_json() const { return "{}"; }
};

/// How to run.
struct RunOptions {
  /// Output folder; created (with parents) when missing. Output files of the
  /// same names are replaced; when the run stops with an error (an exception),
  /// none of them is left behind. summary.json is written last.
  std::filesystem::path out_dir;
  /// Where progress lines go (e.g. &std::cerr), or nullptr for none. A line is
  /// written about once a second once the run has taken progress_after_s.
  std::ostream* progress = nullptr;
  /// Seconds of wall-clock time before the first progress line, >= 0.
  double progress_after_s = 2.0;
  /// Prefix of each progress line (e.g. "exp1 surface 50x50").
  std::string progress_label = "terracut run";
  /// Keep every step's record in RunResult::records (memory ~ 150 bytes/step).
  bool keep_records = false;
  /// Engines that follow the run (not owned; may be empty).
  std::vector<RunObserver*> observers;
};

/// One step: one row of contact.csv.
struct StepRecord {
  double t_s = 0.0;        ///< global simulation time, seconds
  int cut = 0;             ///< index into Scenario::cuts
  int sequence_index = 0;  ///< index into Scenario::sequence
  BladePose pose{};        ///< blade pose during the step
  ContactResult contact{};  ///< contact measured before the step's cut
  double removed_volume_m3 = 0.0;  ///< volume cut in this step, m^3
};

/// Results of one cut of the sequence.
struct CutStats {
  std::string name;                ///< the cut's name
  int sequence_index = 0;          ///< position in the sequence, from 0
  double start_t_s = 0.0;          ///< global time of its first step, seconds
  double duration_s = 0.0;         ///< time of its last keyframe, seconds
  std::int64_t steps = 0;          ///< steps it took (round(duration * rate) + 1)
  double peak_contact_m = 0.0;     ///< largest contact length, metres
  double mean_contact_m = 0.0;     ///< mean contact length over its steps, metres
  double removed_volume_m3 = 0.0;  ///< volume it cut, m^3
};

/// Percentiles of one per-step timer, microseconds.
struct TimingStats {
  double p50_us = 0.0;
  double p90_us = 0.0;
  double p99_us = 0.0;
  double max_us = 0.0;
  double mean_us = 0.0;
};

/// What a run did.
struct RunResult {
  std::int64_t steps = 0;            ///< steps simulated in total
  double initial_volume_m3 = 0.0;    ///< material before the first cut, m^3
  double final_volume_m3 = 0.0;      ///< material after the last cut, m^3
  double removed_volume_m3 = 0.0;    ///< sum of every step's removed volume, m^3
  double max_sample_error_m = 0.0;   ///< max over samples of |height + removed - initial|, metres
  double volume_error_m3 = 0.0;      ///< initial - final - removed, m^3
  std::vector<CutStats> cuts;        ///< one per entry of the sequence
  TimingStats contact_timing{};      ///< StepTimers::contact_s
  TimingStats cut_timing{};          ///< StepTimers::cut_s
  TimingStats step_timing{};         ///< StepTimers::total_s
  std::vector<StepRecord> records;   ///< every step, when RunOptions::keep_records
  double wall_s = 0.0;               ///< wall-clock time of the simulation loop, seconds
};

/// The simulation parameters of a scenario (grid, representation, rate, blade).
SimParams sim_params(const Scenario& scenario);

/// Runs the scenario's sequence and writes the outputs into options.out_dir.
/// Throws terracut::InputError naming the file or folder when an output cannot
/// be written, or the field when the scenario cannot be simulated.
RunResult run_scenario(const Scenario& scenario, const RunOptions& options);

}  // namespace terracut::io
