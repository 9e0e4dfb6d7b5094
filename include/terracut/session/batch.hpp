// A batch run (`terracut run`): builds the scenario's world (the simulation
// and its step listeners, e.g. the rigid bodies), performs the cuts of the
// scenario's sequence at the fixed rate, and writes the outputs into a folder:
//
//   contact.csv   one row per step (io/recording.hpp):
//                 t,cut,x,y,z,qw,qx,qy,qz,contact_length,removed_volume,
//                 section_area,max_depth,cells_visited
//   force.csv     one row per step: t,cut and the physical force on the tool
//                 (force_columns(): the total and its parts, world N, and
//                 what it was computed from)
//   height.npy    float32 (rows, cols) final heights, metres
//   removed.npy   float32 (rows, cols) removed material, metres
//   height.png    16-bit grey, pixel = height / full_scale_m
//   removed.png   16-bit grey, pixel = removed / full_scale_m
//   deposited.npy, deposited.png   with soil flow only: soil put down on
//                 each sample (height above its initial height), metres;
//                 removed is then the soil taken from it (never negative)
//   bodies.csv    only when the scenario has bodies (bullet/bodies_csv.hpp)
//   summary.json  inputs, step count, volumes, conservation error, per-cut
//                 results, per-step timing percentiles, the bodies' entry
//                 and, when paced, the "realtime" entry
//
// Everything except the "timing" and "realtime" objects of summary.json is
// bitwise identical between two runs of the same scenario on the same build.
#pragma once

#include <cstdint>
#include <filesystem>
#include <iosfwd>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "terracut/core/stats.hpp"
#include "terracut/haptics/pacer.hpp"
#include "terracut/io/recording.hpp"
#include "terracut/session/scenario.hpp"

namespace terracut::session {

/// The file names every run writes into the output folder, in writing order
/// (summary.json last, so its presence means the run completed). A run with
/// bodies also writes bodies.csv.
inline constexpr const char* kRunOutputFiles[] = {"contact.csv", "force.csv",   "height.npy",
                                                  "removed.npy", "height.png",  "removed.png",
                                                  "summary.json"};

/// One column of the per-step physical force (StepOutput::force): its name
/// in force.csv and in Python's step columns, its unit, and how it is read.
struct ForceColumn {
  const char* name;
  const char* unit;
  double (*get)(const StepOutput& out);
};
/// The force columns, in order: fx, fy, fz (the total, world N), the parts
/// (cutting_*, surcharge_*, penetration_y, twist_x, twist_z, twist_torque,
/// load_*, bodies_*), the cut it was computed from (cut_depth, cut_width,
/// pile_height, m) and the tool's velocity over the step (vx, vy, vz, m/s).
std::span<const ForceColumn> force_columns();

/// A cut's physical force over its steps (StepOutput::force.total_n).
struct CutForceStats {
  Vec3 mean_n{};                  ///< mean force vector, world N
  double mean_horizontal_n = 0.0;  ///< mean |horizontal part|, N
  double peak_horizontal_n = 0.0;  ///< largest |horizontal part|, N
  double mean_vertical_n = 0.0;    ///< mean vertical part (+ up), N
  double peak_vertical_n = 0.0;    ///< the vertical part of largest magnitude (signed), N
  double mean_surcharge_horizontal_n = 0.0;  ///< mean |horizontal| of the pile's part, N
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
  /// Pace the steps to the wall clock at the scenario's rate (absolute
  /// deadlines, sleep then a short spin), as a haptic loop would; the
  /// pacer's figures go to RunResult::realtime and summary.json's "realtime".
  bool realtime = false;
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
  CutForceStats force{};           ///< the physical force on the tool
};

/// What the soil phase did over a run (SoilModel::kFlow).
struct SoilRunStats {
  double displaced_volume_m3 = 0.0;  ///< cut soil put down ahead of the blade, m^3 (soil pushed again counts again)
  double cut_from_ground_m3 = 0.0;   ///< what the blade cut below the initial surface, m^3 (SoilStepResult::cut_from_ground_m3)
  double net_moved_m3 = 0.0;         ///< at the end, soil no longer where it was: sum of max(initial - height, 0) x cell area, m^3
  double left_over_edge_m3 = 0.0;    ///< soil that left over an open edge, m^3
  double over_top_m3 = 0.0;          ///< soil that fell over the blade's top (BladeSpec::height_m), m^3
  std::int64_t passes = 0;           ///< relaxation passes
  std::int64_t pair_checks = 0;      ///< neighbour pairs examined
  std::int64_t settle_visits = 0;    ///< of them, the settle of the displaced pile's (soil.md)
  std::int64_t max_backlog_cells = 0;  ///< largest number of cells carried to the next step
  std::int64_t final_backlog_cells = 0;  ///< cells still active at the end
  std::int64_t capped_steps = 0;         ///< steps whose relaxation stopped at the work cap (SoilStepResult::reached_cap)
  double bucket_in_m3 = 0.0;          ///< cut soil the bucket took in, m^3 (0 without a bucket)
  double poured_m3 = 0.0;             ///< soil poured from the bucket, m^3
  double max_bucket_load_m3 = 0.0;    ///< largest load the bucket carried, m^3
  double final_bucket_load_m3 = 0.0;  ///< soil still in the bucket at the end, m^3
  TimingStats soil_timing{};          ///< StepTimers::soil_s
};

/// What a run did.
struct RunResult {
  std::int64_t steps = 0;            ///< steps simulated in total
  double initial_volume_m3 = 0.0;    ///< material before the first cut, m^3
  double final_volume_m3 = 0.0;      ///< material after the last cut, m^3
  double removed_volume_m3 = 0.0;    ///< sum of every step's cut volume, m^3 (vanished with kVanish, moved with kFlow)
  double max_sample_error_m = 0.0;   ///< max over samples of |height + removed - initial|, metres
  /// initial - final - vanished, m^3 (vanished: the cut volume with
  /// kVanish; with kFlow what left over an open edge, 0 with a wall, plus
  /// what a bucket still holds).
  double volume_error_m3 = 0.0;
  std::vector<CutStats> cuts;        ///< one per entry of the sequence
  TimingStats contact_timing{};      ///< StepTimers::contact_s
  TimingStats cut_timing{};          ///< StepTimers::cut_s
  TimingStats step_timing{};         ///< StepTimers::total_s
  /// StepTimers::listeners_s (e.g. the Bullet world's step), when the world
  /// has step listeners.
  std::optional<TimingStats> listeners_timing;
  /// The soil phase's figures, with SoilModel::kFlow.
  std::optional<SoilRunStats> soil;
  /// The pacer's figures, with RunOptions::realtime.
  std::optional<haptics::LoopStats> realtime;
  std::vector<io::StepRecord> records;  ///< every step, when RunOptions::keep_records
  /// What the user should know about the result (also summary.json's
  /// "warnings"): soil left steeper than its repose angle when the work
  /// cap stopped the relaxation short, cells too far from square for the
  /// repose angle to hold in every direction (soil_warnings); a cut whose
  /// blade never crosses the terrain (cut_warnings); soil the bodies'
  /// heightfield deleted above its bound (bounds_warnings).
  std::vector<std::string> warnings;
  double wall_s = 0.0;               ///< wall-clock time of the simulation loop, seconds
};

/// Steps a batch run gives a cut at rate_hz: one at t = i / rate_hz (from
/// the cut's start, Motion::sample) for i = 0..n, n = round(duration * rate_hz).
std::int64_t cut_steps(const Motion& motion, double rate_hz);

/// What a user should know about the scenario's cuts: each cut of the
/// sequence whose blade edge, at every step (t = i / rate_hz), lies outside
/// the terrain's X-Z extent seen from above, so that it cuts nothing (a
/// keyframe written as an offset from the terrain's corner, a wrong sign).
/// One readable line per such cut, naming it.
std::vector<std::string> cut_warnings(const io::Scenario& scenario);

/// What a user should know about a run's soil (kFlow; none with kVanish):
/// cells still active at the end (the work cap stopped the relaxation
/// short), steps whose relaxation the work cap stopped (capped_steps: what
/// it deferred changes a pushed pile's history), and cells so far from
/// square that planes steeper than on square cells stand
/// (steepest_standing_slope_deg more than 0.5 degree above square cells').
/// One readable line each.
std::vector<std::string> soil_warnings(const SoilFlowParams& soil, const GridSpec& grid,
                                       std::int64_t final_backlog_cells, std::int64_t capped_steps = 0);

/// What a user should know about the rigid bodies' heightfield: samples it
/// lowered to its upper bound (max_height_m, metres above the ground) over
/// the run, `samples` times in all, deleting `deleted_m3` of soil. One
/// readable line naming the count, the volume, the bound and how to raise
/// it; none when nothing was lowered.
std::vector<std::string> bounds_warnings(std::int64_t samples, double deleted_m3, double max_height_m);

/// Runs the scenario's sequence and writes the outputs into options.out_dir.
/// Throws terracut::InputError naming the file or folder when an output cannot
/// be written, or the field when the scenario cannot be simulated.
RunResult run_scenario(const Scenario& scenario, const RunOptions& options);

/// The "realtime" entry of summary.json (JSON text, one line): the pacer's
/// rate, period, ticks, missed deadlines, skipped slots, and step time,
/// period jitter and wake latency percentiles in microseconds.
std::string realtime_json(const haptics::LoopStats& stats);

}  // namespace terracut::session
