// `terracut mmt`: model-mediated teleoperation, both stations in one process
// (or one station per process over UDP), and the study over delay and loss.
#pragma once

#include "commands.hpp"

namespace terracut::cli {

Command add_mmt_command(CLI::App& app);
/// `terracut key`: makes the key file of a pair of stations, or shows a key's fingerprint.
Command add_key_command(CLI::App& app);

}  // namespace terracut::cli
