// Running a helper program (the plot scripts) from a subcommand.
#pragma once

#include <string>
#include <vector>

namespace terracut::cli {

/// Runs argv[0] with the arguments argv[1..] (no shell; stdout and stderr are
/// shared with this process, flushed first). Returns its exit code, or -1 when
/// it could not be started or did not exit normally.
int run_program(const std::vector<std::string>& argv);

}  // namespace terracut::cli
