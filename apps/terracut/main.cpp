// terracut: command-line entry point. Parses the subcommand and its options,
// runs it, and turns every error into a message on stderr and a non-zero exit
// code (never an uncaught exception).
#include <exception>
#include <iostream>
#include <new>

#include "commands.hpp"
#include "haptics_command.hpp"
#include "mmt_command.hpp"
#include "terracut/core/error.hpp"

int main(int argc, char** argv) {
  CLI::App app{
      "terracut " TERRACUT_VERSION
      " -- heightmap soil cutting: contact length and cut shape of a blade moving through\n"
      "a heightmap terrain, stepped at a fixed rate (default 1 kHz).",
      "terracut"};
  app.set_version_flag("--version", "terracut " TERRACUT_VERSION);
  app.require_subcommand(1);
  app.footer(
      "Run `terracut SUBCOMMAND --help` for the options of each subcommand.\n"
      "Units are SI (metres, seconds). World frame: right-handed, Y up, ground plane X-Z;\n"
      "heightmap column index runs along +X, row index along +Z.\n"
      "Exit codes: 0 success; 1 bad input or failed output (validate: a check failed);\n"
      "2 bad command line; 3 (reproduce, validate) results written but figures not made;\n"
      "4 (mmt --role) the link to the other station died, outputs written.\n"
      "Scenario format: docs/scenario-format.md. Experiments: docs/experiments.md.\n"
      "The soil's physical checks (terracut validate): docs/validation.md.");

  const terracut::cli::Command run = terracut::cli::add_run_command(app);
  const terracut::cli::Command heightmap = terracut::cli::add_heightmap_command(app);
  const terracut::cli::Command reproduce = terracut::cli::add_reproduce_command(app);
  const terracut::cli::Command validate = terracut::cli::add_validate_command(app);
  const terracut::cli::Command haptics = terracut::cli::add_haptics_command(app);
  const terracut::cli::Command mmt = terracut::cli::add_mmt_command(app);
  const terracut::cli::Command key = terracut::cli::add_key_command(app);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // CLI11 checks the required options before the unknown ones: name an
    // unknown option first, it is the likelier mistake.
    if (dynamic_cast<const CLI::RequiredError*>(&e)) {
      for (const CLI::App* sub : app.get_subcommands()) {
        const std::vector<std::string> extra = sub->remaining();
        if (extra.empty()) continue;
        std::cerr << "terracut " << sub->get_name() << ": unknown option or argument:";
        for (const std::string& x : extra) std::cerr << " " << x;
        std::cerr << "\nRun with --help for more information.\n";
        return 2;
      }
    }
    const int code = app.exit(e);
    // CLI11 uses many codes for usage errors; report them all as 2.
    return code == 0 ? 0 : 2;
  }

  try {
    if (app.got_subcommand("run")) return run();
    if (app.got_subcommand("heightmap")) return heightmap();
    if (app.got_subcommand("reproduce")) return reproduce();
    if (app.got_subcommand("validate")) return validate();
    if (app.got_subcommand("haptics")) return haptics();
    if (app.got_subcommand("mmt")) return mmt();
    if (app.got_subcommand("key")) return key();
  } catch (const terracut::InputError& e) {
    std::cerr << "terracut: error: " << e.what() << "\n";
    return terracut::cli::kExitError;
  } catch (const std::bad_alloc&) {
    std::cerr << "terracut: error: out of memory (is the resolution too large?)\n";
    return terracut::cli::kExitError;
  } catch (const std::exception& e) {
    std::cerr << "terracut: error: " << e.what() << "\n";
    return terracut::cli::kExitError;
  }
  std::cerr << "terracut: error: no subcommand given (run, heightmap, reproduce, validate, haptics, mmt, key)\n";
  return 2;
}
