// `terracut haptics`: runs the haptic loop on a scenario with a device
// backend (script, sim or udp) and writes haptics.csv, summary.json and a
// force plot. Registered by main.cpp like the other subcommands.
#pragma once

#include "commands.hpp"

namespace terracut::cli {

/// Registers `haptics` with its options and --help text; the returned
/// function runs it after parsing and gives the exit code.
Command add_haptics_command(CLI::App& app);

}  // namespace terracut::cli
