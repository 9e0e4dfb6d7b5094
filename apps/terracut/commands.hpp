// The subcommands of the terracut command-line tool. Each add_* function
// registers its subcommand, its options and its complete --help text; the
// returned function runs it after parsing and gives the process exit code.
#pragma once

#include <CLI/CLI.hpp>

#include <functional>

namespace terracut::cli {

/// Exit codes shared by every subcommand.
inline constexpr int kExitOk = 0;
inline constexpr int kExitError = 1;     ///< bad input, a failed run or an unwritable output;
                                         ///< validate: a check failed
inline constexpr int kExitNoFigures = 3; ///< reproduce, validate: results written, figures could not be made
inline constexpr int kExitLinkLost = 4;  ///< mmt --role: the link to the other station died (outputs written)

using Command = std::function<int()>;

Command add_run_command(CLI::App& app);
Command add_heightmap_command(CLI::App& app);
Command add_reproduce_command(CLI::App& app);
Command add_validate_command(CLI::App& app);

}  // namespace terracut::cli
