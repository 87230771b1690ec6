#include "apps/commands.hpp"
#include "host/error.hpp"

namespace talus::app {

void add_bench_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("bench", "not yet implemented");
  cmd->callback([] { throw Error("'talus bench' is not implemented yet"); });
}

}  // namespace talus::app
