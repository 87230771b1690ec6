// The facade's pile cache (SimulationOptions::pile_cache, Simulation::pile_from_cache): a second
// Simulation of the same scenario, level and seed reads the pile the first one saved in
// $TALUS_CACHE_DIR, and one without the cache builds its own and saves nothing.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include "embed/talus.hpp"
#include "host/version.hpp"

namespace talus {
namespace {

namespace fs = std::filesystem;

TEST(SimulationPileCache, SecondSimulationReadsThePileBack) {
  const fs::path dir =
      fs::temp_directory_path() / ("talus-embed-pile-cache-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const char* old = std::getenv("TALUS_CACHE_DIR");
  const std::string previous = old ? old : "";
  ASSERT_EQ(setenv("TALUS_CACHE_DIR", dir.c_str(), 1), 0);
  SimulationOptions o;
  o.scenario = "hd27";
  o.level = "D400";

  o.pile_cache = false;
  EXPECT_FALSE(Simulation(o).pile_from_cache());
  // no pile saved (the folder holds the program binaries: host/program_cache.hpp)
  EXPECT_FALSE(fs::exists(dir / "piles"));

  o.pile_cache = true;
  const Simulation first(o);
  EXPECT_FALSE(first.pile_from_cache());
  const Simulation second(o);
  // a build with uncommitted changes never uses the cache (docs/embedding.md)
  const std::string commit = git_commit();
  const bool dirty = commit.size() > 6 && commit.substr(commit.size() - 6) == "-dirty";
  EXPECT_EQ(second.pile_from_cache(), !dirty);
  if (!dirty) {
    EXPECT_EQ(second.particles().position, first.particles().position);
  }

  if (old)
    setenv("TALUS_CACHE_DIR", previous.c_str(), 1);
  else
    unsetenv("TALUS_CACHE_DIR");
  fs::remove_all(dir);
}

}  // namespace
}  // namespace talus
