// What the report-writing subcommands (reproduce, validate) share: their
// output folder, their text files, their numbers in Markdown, and the plot
// script that draws their figures.
#pragma once

#include <CLI/CLI.hpp>

#include <filesystem>
#include <functional>
#include <optional>
#include <string>

namespace terracut::cli {

/// The options of a report-writing subcommand.
struct ReportOptions {
  std::string out;                          ///< --out: the output folder
  std::string tools = TERRACUT_TOOLS_DIR;   ///< --tools-dir: where the plot script is
  std::string python = "/usr/bin/python3";  ///< --python: the figures' interpreter
  bool no_plots = false;                    ///< --no-plot(s): tables only
  bool quiet = false;                       ///< --quiet: no progress lines
};

/// Adds --out, --tools-dir (the folder holding `script`), --python,
/// --no-plot/--no-plots (no_plots_help says what then happens) and --quiet.
void add_report_options(CLI::App& sub, ReportOptions& options, const std::string& script,
                        const std::string& no_plots_help);

/// Creates the output folder (with parents). Throws InputError naming it
/// when that fails.
void create_output_folder(const std::filesystem::path& dir);

/// Writes text to a file, replacing it. Throws InputError naming the file.
void write_file(const std::filesystem::path& path, const std::string& text);

/// A number in a printf format (e.g. "%.3g"), for the reports' tables.
std::string fmt(const char* format, double v);

/// Draws a report's figures: runs `python script out_dir [--quiet]`.
/// Returns nullopt when it succeeded, else the problem in words (python
/// missing, script missing, numpy/matplotlib missing (its exit code 3), or
/// the script's exit code), for the report and the error message. say
/// receives a progress line.
std::optional<std::string> draw_figures(const std::string& python,
                                        const std::filesystem::path& script,
                                        const std::filesystem::path& out_dir, bool quiet,
                                        const std::function<void(const std::string&)>& say);

}  // namespace terracut::cli
