// host/files: the JSON reader every data-file loader uses holds to the loaders' contract: the
// file parsed, or one talus::InputError naming it, whatever the bytes (docs/reliability.md,
// "Fuzzing": a number beyond double's range escaped the loaders as nlohmann's out_of_range).
#include "host/files.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "host/error.hpp"
#include "tests/host/scoped_env.hpp"

namespace talus {
namespace {

std::string write_temp(const std::string& name, const std::string& text) {
  const auto path =
      std::filesystem::temp_directory_path() / (std::to_string(::getpid()) + "-" + name);
  std::ofstream(path) << text;
  return path.string();
}

// the message of the InputError `read` throws ("" when it throws none)
std::string refusal(const std::string& path) {
  try {
    read_json_file(path, "a test file");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(Files, ReadJsonFileParsesAnObject) {
  const std::string path = write_temp("ok.json", R"({"a": [1, 2.5e300, -3]})");
  const nlohmann::json j = read_json_file(path, "a test file");
  EXPECT_DOUBLE_EQ(j.at("a").at(1).get<double>(), 2.5e300);
  std::filesystem::remove(path);
}

TEST(Files, ReadJsonFileRefusesEveryBadFileWithOneInputErrorNamingIt) {
  // the fuzzer's findings first: numbers beyond double's range (out_of_range.406, not a parse
  // error)
  for (const char* text :
       {R"({"name": -1e708})", R"({"x": 1e308972})", "{ not json", "", "[1, 2"}) {
    const std::string path = write_temp("bad.json", text);
    const std::string message = refusal(path);
    EXPECT_NE(message.find(path), std::string::npos) << text << ": " << message;
    std::filesystem::remove(path);
  }
  const std::string missing = refusal("/nonexistent/talus.json");
  EXPECT_NE(missing.find("cannot open the file (a test file)"), std::string::npos) << missing;
}

using test::ScopedEnv;

// where the piles and program binaries are kept: TALUS_CACHE_DIR first, then XDG_CACHE_HOME/talus,
// then ~/.cache/talus
TEST(Files, CacheDirFollowsTheEnvironment) {
  {
    ScopedEnv talus_dir("TALUS_CACHE_DIR", "/tmp/talus-here");
    ScopedEnv xdg("XDG_CACHE_HOME", "/tmp/xdg");
    EXPECT_EQ(default_cache_dir(), "/tmp/talus-here");
  }
  {
    ScopedEnv talus_dir("TALUS_CACHE_DIR", nullptr);
    ScopedEnv xdg("XDG_CACHE_HOME", "/tmp/xdg");
    EXPECT_EQ(default_cache_dir(), "/tmp/xdg/talus");
  }
  {
    ScopedEnv talus_dir("TALUS_CACHE_DIR", nullptr);
    ScopedEnv xdg("XDG_CACHE_HOME", nullptr);
    ScopedEnv home("HOME", "/home/someone");
    EXPECT_EQ(default_cache_dir(), "/home/someone/.cache/talus");
  }
}

}  // namespace
}  // namespace talus
