// talus: wheel-loader digging in granular terrain. Entry point of the command-line tool.
#include <iostream>
#include <string>

#include "apps/commands.hpp"
#include "host/error.hpp"
#include "host/interrupt.hpp"
#include "host/version.hpp"

int main(int argc, char** argv) {
  // SIGINT and SIGTERM stop a command between steps, not mid-write (host/interrupt.hpp)
  talus::watch_interrupts();
  CLI::App app{"talus: nonsmooth DEM and multibody simulation of a wheel loader digging in gravel"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("talus ") + talus::talus_version() + " (" +
                                        talus::git_commit() + ")");
  const std::string command_line = talus::app::command_line(argc, argv);
  talus::app::add_pile_command(app, command_line);
  talus::app::add_repose_command(app, command_line);
  talus::app::add_soil_command(app, command_line);
  talus::app::add_cut_command(app, command_line);
  talus::app::add_bench_command(app);
  talus::app::add_run_command(app, command_line);
  talus::app::add_sweep_command(app, command_line);
  talus::app::add_synth_command(app, command_line);
  talus::app::add_diagnose_command(app);
  talus::app::add_compare_command(app);
  talus::app::add_plot_command(app);
  try {
    // a first word that names no subcommand (CLI11 would only say "A subcommand is required")
    std::string names;
    bool known = false;
    for (const CLI::App* sub : app.get_subcommands({})) {
      names += (names.empty() ? "" : ", ") + sub->get_name();
      known = known || (argc > 1 && sub->get_name() == argv[1]);
    }
    if (argc > 1 && argv[1][0] != '-' && !known) {
      throw talus::InputError(std::string("unknown subcommand '") + argv[1] +
                              "'; the subcommands are " + names + " (talus --help describes them)");
    }
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version are "errors" with exit code 0 in CLI11
    return app.exit(e) == 0 ? 0 : talus::app::kExitUsage;
  } catch (const talus::Interrupted& e) {
    // what was written stays, without the summary.json that marks a finished run
    std::cerr << "talus: " << e.what()
              << "; stopped between steps, outputs written so far kept without their "
              << "summary.json (the mark of a finished run)\n";
    return e.exit_code();
  } catch (const talus::InputError& e) {
    // bad input file or field: a usage error, not a runtime failure
    std::cerr << "talus: error: " << e.what() << "\n";
    return talus::app::kExitUsage;
  } catch (const talus::Error& e) {
    std::cerr << "talus: error: " << e.what() << "\n";
    return talus::app::kExitFailure;
  } catch (const std::exception& e) {
    std::cerr << "talus: error: " << e.what() << "\n";
    return talus::app::kExitFailure;
  }
  return 0;
}
