#include "apps/commands.hpp"
#include "host/error.hpp"

namespace talus::app {

void add_run_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("run", "not yet implemented");
  cmd->callback([] { throw Error("'talus run' is not implemented yet"); });
}

}  // namespace talus::app
