#include "report_files.hpp"

#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <vector>

#include "subprocess.hpp"
#include "terracut/core/error.hpp"

namespace terracut::cli {

namespace fs = std::filesystem;

void add_report_options(CLI::App& sub, ReportOptions& o, const std::string& script,
                        const std::string& no_plots_help) {
  sub.add_option("--out,-o", o.out, "Output folder; created if missing")
      ->required()
      ->type_name("DIR");
  sub.add_option("--tools-dir", o.tools, "Folder holding " + script)
      ->capture_default_str()
      ->type_name("DIR");
  sub.add_option("--python", o.python,
                 "Python interpreter used for the figures (needs numpy and matplotlib)")
      ->capture_default_str()
      ->type_name("PATH");
  sub.add_flag("--no-plot,--no-plots", o.no_plots, no_plots_help);
  sub.add_flag("--quiet,-q", o.quiet, "No progress lines on stderr");
}

void create_output_folder(const fs::path& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir))
    throw InputError(dir.string() + ": cannot create the output folder");
}

void write_file(const fs::path& path, const std::string& text) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  if (!f) throw InputError(path.string() + ": cannot create the file");
  f << text;
  f.close();
  if (!f) throw InputError(path.string() + ": write failed");
}

std::string fmt(const char* format, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

std::optional<std::string> draw_figures(const std::string& python, const fs::path& script,
                                        const fs::path& out_dir, bool quiet,
                                        const std::function<void(const std::string&)>& say) {
  if (access(python.c_str(), X_OK) != 0)
    return "the Python interpreter " + python +
           " is missing (on Debian: apt-get install python3 python3-matplotlib python3-numpy)";
  if (!fs::exists(script))
    return "the plot script " + script.string() + " is missing (use --tools-dir)";
  say("drawing figures: " + python + " " + script.string() + " " + out_dir.string());
  std::vector<std::string> argv{python, script.string(), out_dir.string()};
  if (quiet) argv.push_back("--quiet");
  const int code = run_program(argv);
  if (code == 3)
    return std::string(
        "Python modules are missing (see the message above; on Debian: apt-get install "
        "python3-matplotlib python3-numpy)");
  if (code != 0)
    return "the plot script " + script.string() + " failed (exit code " + std::to_string(code) +
           "; see the messages above)";
  return std::nullopt;
}

}  // namespace terracut::cli
