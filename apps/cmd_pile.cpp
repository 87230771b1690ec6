#include "apps/commands.hpp"
#include "host/error.hpp"

namespace talus::app {

void add_pile_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("pile", "not yet implemented");
  cmd->callback([] { throw Error("'talus pile' is not implemented yet"); });
}

}  // namespace talus::app
