// The pile cache from the command line: talus bench dig saves HD27's D400 pile in $TALUS_CACHE_DIR
// and reads it back the second time, --no-pile-cache leaves the folder alone, and a build with
// uncommitted changes says why it does not use the cache.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "host/version.hpp"
#include "tests/apps/cli_test_util.hpp"

namespace talus {
namespace {

namespace fs = std::filesystem;

TEST(PileCacheCli, BenchDigSavesThenReadsThePile) {
  const fs::path dir =
      fs::temp_directory_path() / ("talus_cli_pile_cache_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const std::string env = "TALUS_CACHE_DIR=" + dir.string();
  const std::string args = "bench dig --scenario hd27 --level D400 --seconds 0.1 --quiet";

  const test::Outcome off = test::run_talus(env, args + " --no-pile-cache");
  ASSERT_EQ(off.code, 0) << off.err;
  EXPECT_EQ(off.err.find("pile"), std::string::npos) << off.err;
  // no pile saved (the folder holds the program binaries: host/program_cache.hpp)
  EXPECT_FALSE(fs::exists(dir / "piles"));

  const test::Outcome first = test::run_talus(env, args);
  ASSERT_EQ(first.code, 0) << first.err;
  const test::Outcome second = test::run_talus(env, args);
  ASSERT_EQ(second.code, 0) << second.err;
  const std::string commit = git_commit();
  if (commit.size() > 6 && commit.substr(commit.size() - 6) == "-dirty") {
    // the tool was built from a tree with uncommitted changes: no pile is saved, and it says so
    EXPECT_NE(first.err.find("uncommitted changes"), std::string::npos) << first.err;
    EXPECT_FALSE(fs::exists(dir / "piles"));
  } else {
    EXPECT_NE(first.err.find("pile saved to cache " + dir.string()), std::string::npos)
        << first.err;
    EXPECT_NE(second.err.find("pile from cache " + dir.string()), std::string::npos) << second.err;
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace talus
