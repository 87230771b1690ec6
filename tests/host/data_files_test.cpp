// host/data_files: the shipped data found without a build path compiled in
#include "host/data_files.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <unistd.h>

#include "host/error.hpp"

namespace talus {
namespace {

namespace fs = std::filesystem;

// this test program runs from the build tree (build/tests/), not the source folder: the data is
// found by walking up from the program to the repository's data/
TEST(DataFiles, FoundBesideTheRunningProgram) {
  ASSERT_EQ(std::getenv("TALUS_DATA_DIR"), nullptr) << "unset TALUS_DATA_DIR to run this test";
  const fs::path here = fs::current_path();
  fs::current_path(fs::temp_directory_path());  // no ./data to find
  const std::string machine = locate_data_file("machines/wa320.json");
  fs::current_path(here);
  ASSERT_FALSE(machine.empty());
  EXPECT_TRUE(fs::equivalent(machine, fs::path(TALUS_SOURCE_DIR) / "data" / "machines" / "wa320.json")) << machine;
}

// TALUS_DATA_DIR comes first; a file that is nowhere names every folder searched and the fix
TEST(DataFiles, TheUsersFolderComesFirstAndAMissingFileNamesTheSearch) {
  const fs::path dir = fs::temp_directory_path() / ("talus-data-" + std::to_string(::getpid()));
  fs::create_directories(dir / "machines");
  std::ofstream(dir / "machines" / "wa320.json") << "{}";
  ASSERT_EQ(setenv("TALUS_DATA_DIR", dir.c_str(), 1), 0);
  const std::string machine = locate_data_file("machines/wa320.json");
  const std::vector<std::string> roots = data_search_paths();
  std::string message;
  try {
    find_data_file("machines/no-such-machine.json");
  } catch (const InputError& e) {
    message = e.what();
  }
  unsetenv("TALUS_DATA_DIR");
  fs::remove_all(dir);
  EXPECT_EQ(fs::path(machine), dir / "machines" / "wa320.json");
  ASSERT_GE(roots.size(), 3u);  // the user's, ./data, the program's
  EXPECT_EQ(roots.front(), dir.string());
  EXPECT_NE(message.find("no-such-machine.json"), std::string::npos) << message;
  EXPECT_NE(message.find(dir.string()), std::string::npos) << message;
  EXPECT_NE(message.find("TALUS_DATA_DIR"), std::string::npos) << message;
}

}  // namespace
}  // namespace talus
