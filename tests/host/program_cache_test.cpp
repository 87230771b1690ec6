// host/program_cache: program binaries saved and read back under their key, a damaged or foreign
// file read as a miss, and a Device that builds from a saved binary (its kernels then computing
// what the source's do) and rebuilds from source over a damaged one.
#include "host/program_cache.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "host/device.hpp"
#include "host/scan.hpp"
#include "tests/host/scoped_env.hpp"

namespace talus {
namespace {

namespace fs = std::filesystem;
using test::ScopedEnv;

// a fresh folder for the test, removed after it
struct TempFolder {
  explicit TempFolder(const std::string& name)
      : path(fs::temp_directory_path() / (name + "-" + std::to_string(getpid()))) {
    fs::remove_all(path);
  }
  ~TempFolder() { fs::remove_all(path); }
  fs::path path;
};

std::vector<fs::path> files_in(const fs::path& dir) {
  std::vector<fs::path> out;
  if (fs::exists(dir))
    for (const auto& e : fs::directory_iterator(dir)) out.push_back(e.path());
  return out;
}

TEST(ProgramCache, ABinaryIsReadBackOnlyUnderItsOwnKeyAndWhole) {
  TempFolder dir("talus-program-cache");
  const std::string key = program_cache_key("kernel source", "-cl-std=CL1.2", "pocl", "cpu");
  const std::string binary(
      "\x7f"
      "ELF binary \0 with a zero",
      25);
  EXPECT_FALSE(read_program_binary(dir.path.string(), key));  // nothing saved yet
  ASSERT_TRUE(save_program_binary(dir.path.string(), key, binary));
  EXPECT_EQ(read_program_binary(dir.path.string(), key), binary);
  // any part of the key changed is another program
  for (const std::string& other :
       {program_cache_key("kernel source ", "-cl-std=CL1.2", "pocl", "cpu"),
        program_cache_key("kernel source", "-cl-std=CL1.2 -DX", "pocl", "cpu"),
        program_cache_key("kernel source", "-cl-std=CL1.2", "pocl 6", "cpu"),
        program_cache_key("kernel source", "-cl-std=CL1.2", "pocl", "gpu")})
    EXPECT_FALSE(read_program_binary(dir.path.string(), other));
  // a damaged file is a miss, not an error
  const std::vector<fs::path> saved = files_in(dir.path / "kernels");
  ASSERT_EQ(saved.size(), 1u);
  std::string bytes;
  {
    std::ifstream in(saved[0], std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  bytes[bytes.size() / 2] ^= 0x40;
  std::ofstream(saved[0], std::ios::binary) << bytes;
  EXPECT_FALSE(read_program_binary(dir.path.string(), key));
  std::ofstream(saved[0], std::ios::binary) << "short";
  EXPECT_FALSE(read_program_binary(dir.path.string(), key));
  // no folder: the cache is off
  EXPECT_FALSE(read_program_binary("", key));
  EXPECT_FALSE(save_program_binary("", key, binary));
}

// the scan of a fresh random array on `dev`, checked against the host's
void expect_scan_works(Device& dev, const std::string& label) {
  std::mt19937 rng(std::random_device{}());
  std::uniform_int_distribution<int> value(0, 100);
  std::vector<int> in(5000);
  for (int& x : in) x = value(rng);
  std::vector<int> want(in.size() + 1, 0);
  for (size_t k = 0; k < in.size(); ++k) want[k + 1] = want[k] + in[k];
  DeviceScan scan(dev);
  Buffer<int> d_in(dev, 1), d_out(dev, 1);
  d_in.upload(in);
  scan.exclusive(d_in, d_out, in.size());
  EXPECT_EQ(d_out.download(in.size() + 1), want) << label;
}

// a Device saves its programs' binaries in TALUS_CACHE_DIR/kernels; the next Device creates its
// programs from them (the file is not written again) and they compute what the source's do; over
// a damaged file it builds the source and saves a whole binary again, which the Device after it
// takes. (A binary's size is PoCL's to choose: it holds the kernels PoCL had compiled by then.)
TEST(ProgramCache, ADeviceBuildsFromTheSavedBinaryAndFromSourceOverADamagedOne) {
  TempFolder dir("talus-program-cache-device");
  ScopedEnv env("TALUS_CACHE_DIR", dir.path.c_str());
  {
    Device first;
    expect_scan_works(first, "built from source");
  }
  const std::vector<fs::path> saved = files_in(dir.path / "kernels");
  ASSERT_EQ(saved.size(), 1u) << "the scan's program, saved once";
  // a Device that takes the saved binary writes nothing
  const auto expect_hit = [&](const char* label) {
    const auto written = fs::last_write_time(saved[0]);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    {
      Device next;
      expect_scan_works(next, label);
    }
    EXPECT_EQ(fs::last_write_time(saved[0]), written) << label << ": a hit writes nothing";
    EXPECT_EQ(files_in(dir.path / "kernels").size(), 1u) << label;
  };
  expect_hit("created from the saved binary");
  // damaged: built from source and saved again, whole, as the next Device shows
  std::ofstream(saved[0], std::ios::binary) << "not a program binary";
  {
    Device rebuilt;
    expect_scan_works(rebuilt, "rebuilt over a damaged file");
  }
  EXPECT_GT(fs::file_size(saved[0]), 1000u);
  expect_hit("created from the binary saved over the damaged one");
}

}  // namespace
}  // namespace talus
