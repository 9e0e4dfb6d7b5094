// The subcommands of the terracut command-line tool. Each add_* function
// registers its subcommand, its options and its complete --help text; the
// returned function runs it after parsing and gives the process exit code.
#pragma once

#include <CLI/CLI.hpp>

#include <functional>

#include "../exit_codes.hpp"

namespace terracut::cli {

/// Exit codes of the subcommands: those of every terracut program (exit_codes.hpp).
inline constexpr int kExitOk = apps::kExitOk;
inline constexpr int kExitError = apps::kExitError;  ///< bad input, a failed run or an unwritable
                                                     ///< output; validate: a check failed
inline constexpr int kExitUsage = apps::kExitUsage;  ///< a command line that cannot be parsed
/// reproduce, validate: results written, figures could not be made.
inline constexpr int kExitNoFigures = apps::kExitPartial;
/// mmt --role: the link to the other station died (outputs written).
inline constexpr int kExitLinkLost = apps::kExitLinkLost;

using Command = std::function<int()>;

Command add_run_command(CLI::App& app);
Command add_heightmap_command(CLI::App& app);
Command add_reproduce_command(CLI::App& app);
Command add_validate_command(CLI::App& app);
Command add_calibrate_command(CLI::App& app);

}  // namespace terracut::cli
