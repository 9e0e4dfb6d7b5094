// The exit codes of every terracut program (terracut, terracut-viewer,
// terracut-device): one table, printed by `terracut --help` (and the --help of
// the subcommands that use codes past 2), terracut-viewer's and
// terracut-device's, and in the README ("Exit codes"). A program uses the
// codes that apply to it.
#pragma once

namespace terracut::apps {

/// Success (and --help, --version).
inline constexpr int kExitOk = 0;
/// Bad input (a file, a field or an option's value, named in the message), a
/// failed run or an output that could not be written; `terracut validate`:
/// a check failed.
inline constexpr int kExitError = 1;
/// A command line that cannot be parsed: an unknown option or subcommand, a
/// missing value, a value outside the option's stated range.
inline constexpr int kExitUsage = 2;
/// Done, but not all of it: `terracut reproduce`, `validate` and `haptics`
/// wrote their results but could not make the figures; `terracut-device`
/// played, but no force came back.
inline constexpr int kExitPartial = 3;
/// `terracut mmt --role`: the link to the other station died (its outputs
/// are written, and the summary says how the session ended).
inline constexpr int kExitLinkLost = 4;
/// `terracut-viewer`: no OpenGL 3.3 context could be made (no EGL/Mesa for
/// headless rendering, no display for a window); the tests skip on it.
inline constexpr int kExitNoContext = 77;

/// The table for a --help footer.
inline constexpr const char* kExitCodesHelp =
    "Exit codes (every terracut program): 0 success; 1 bad input (the message names the\n"
    "file, field or option), a failed run or an unwritable output (validate: a check\n"
    "failed); 2 a command line that cannot be parsed; 3 done but not all (reproduce,\n"
    "validate, haptics: no figures; terracut-device: no force came back); 4 mmt --role:\n"
    "the link to the other station died (outputs written); 77 terracut-viewer: no OpenGL\n"
    "context.";

}  // namespace terracut::apps
