// The `rig` command line: one subcommand per job (docs/contracts.md).
#include <iostream>

#include <CLI/CLI.hpp>

#include "app/commands.hpp"
#include "rig/core/errors.hpp"

int main(int argc, char** argv) {
  CLI::App app{"rig: acceptance test rig for quartz pendulum accelerometers (U10/U20 method)"};
  app.set_version_flag("--version", std::string("rig ") + RIG_VERSION);
  app.require_subcommand(1);
  int rc = rig::kExitPass;
  rig::cli::add_run(app, rc);
  rig::cli::add_analyze(app, rc);
  rig::cli::add_plant(app, rc);
  rig::cli::add_table(app, rc);
  rig::cli::add_dut(app, rc);
  rig::cli::add_filter(app, rc);
  rig::cli::add_report(app, rc);
  rig::cli::add_history(app, rc);
  rig::cli::add_capture(app, rc);
  rig::cli::add_verify(app, rc);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // `rig bogus`: CLI11 takes an unknown first word for a stray argument and reports only the
    // missing subcommand; name the word instead, with the subcommands there are.
    if (app.get_subcommands().empty() && !app.remaining().empty()) {
      const std::string word = app.remaining().front();
      if (word.rfind('-', 0) == 0) {
        std::cerr << "rig: unknown option '" << word << "' (see rig --help)\n";
      } else {
        std::cerr << "rig: unknown subcommand '" << word << "' (one of:";
        for (const CLI::App* s : app.get_subcommands({})) std::cerr << ' ' << s->get_name();
        std::cerr << "; see rig --help)\n";
      }
      return rig::kExitUsage;
    }
    const int r = app.exit(e);
    return r == 0 ? 0 : rig::kExitUsage;  // --help/--version exit 0; usage errors exit 2
  } catch (const rig::ConfigError& e) {
    std::cerr << "rig: configuration error: " << e.what() << "\n";
    return rig::kExitUsage;
  } catch (const rig::AbortedError& e) {
    std::cerr << "rig: " << e.what() << "\n";
    return rig::kExitAborted;
  } catch (const rig::HardwareError& e) {
    std::cerr << "rig: hardware fault: " << e.what() << "\n";
    return rig::kExitHardware;
  } catch (const std::exception& e) {
    std::cerr << "rig: error: " << e.what() << "\n";
    return rig::kExitHardware;
  }
  return rc;
}
