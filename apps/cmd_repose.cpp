#include "apps/commands.hpp"
#include "host/error.hpp"

namespace talus::app {

void add_repose_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("repose", "not yet implemented");
  cmd->callback([] { throw Error("'talus repose' is not implemented yet"); });
}

}  // namespace talus::app
