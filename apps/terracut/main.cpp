// terracut: command-line entry point. Parses the subcommand and its options,
// runs it, and turns every error into a message on stderr and a non-zero exit
// code (never an uncaught exception).
#include <exception>
#include <iostream>
#include <new>
#include <string>
#include <vector>

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
      "Scenario format: docs/scenario-format.md. Experiments: docs/experiments.md.\n"
      "The soil's physical checks (terracut validate): docs/validation.md.\n" +
      std::string(terracut::apps::kExitCodesHelp));

  const terracut::cli::Command run = terracut::cli::add_run_command(app);
  const terracut::cli::Command heightmap = terracut::cli::add_heightmap_command(app);
  const terracut::cli::Command reproduce = terracut::cli::add_reproduce_command(app);
  const terracut::cli::Command validate = terracut::cli::add_validate_command(app);
  const terracut::cli::Command calibrate = terracut::cli::add_calibrate_command(app);
  const terracut::cli::Command haptics = terracut::cli::add_haptics_command(app);
  const terracut::cli::Command mmt = terracut::cli::add_mmt_command(app);
  const terracut::cli::Command key = terracut::cli::add_key_command(app);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // CLI11 checks the required options before the unknown ones: name an
    // unknown option first, it is the likelier mistake.
    if (dynamic_cast<const CLI::RequiredError*>(&e)) {
      // No subcommand at all, or a word that is none: name it and list the real ones.
      if (app.get_subcommands().empty()) {
        std::string names;
        for (const CLI::App* sub : app.get_subcommands({}))
          names += (names.empty() ? "" : ", ") + sub->get_name();
        const std::vector<std::string> extra = app.remaining();
        if (extra.empty())
          std::cerr << "terracut: a subcommand is required: " << names << "\n";
        else if (!extra.front().empty() && extra.front()[0] == '-')
          std::cerr << "terracut: unknown option " << extra.front() << " (the subcommands: " << names
                    << ")\n";
        else
          std::cerr << "terracut: unknown subcommand '" << extra.front() << "'; the subcommands are "
                    << names << "\n";
        std::cerr << "Run `terracut --help` or `terracut SUBCOMMAND --help` for more information.\n";
        return terracut::cli::kExitUsage;
      }
      for (const CLI::App* sub : app.get_subcommands()) {
        const std::vector<std::string> extra = sub->remaining();
        if (extra.empty()) continue;
        std::cerr << "terracut " << sub->get_name() << ": unknown option or argument:";
        for (const std::string& x : extra) std::cerr << " " << x;
        std::cerr << "\nRun with --help for more information.\n";
        return terracut::cli::kExitUsage;
      }
    }
    const int code = app.exit(e);
    // CLI11 uses many codes for usage errors; report them all as one.
    return code == 0 ? terracut::cli::kExitOk : terracut::cli::kExitUsage;
  }

  try {
    if (app.got_subcommand("run")) return run();
    if (app.got_subcommand("heightmap")) return heightmap();
    if (app.got_subcommand("reproduce")) return reproduce();
    if (app.got_subcommand("validate")) return validate();
    if (app.got_subcommand("calibrate")) return calibrate();
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
  std::cerr << "terracut: error: no subcommand given (run, heightmap, reproduce, validate, calibrate, haptics, mmt, key)\n";
  return terracut::cli::kExitUsage;
}
