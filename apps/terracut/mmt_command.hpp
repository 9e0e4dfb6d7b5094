// `terracut mmt`: model-mediated teleoperation, both stations in one process
// (or one station per process over UDP), and the study over delay and loss.
#pragma once

#include "commands.hpp"

namespace terracut::cli {

Command add_mmt_command(CLI::App& app);

}  // namespace terracut::cli
