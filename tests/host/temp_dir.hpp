// Test helper: a fresh folder under the system's temporary one, removed when the scope ends, so a
// test that stops at a failed ASSERT leaves nothing behind. The name gets the process id, so two
// test binaries running at once never share a folder.
#pragma once
#include <unistd.h>

#include <filesystem>
#include <string>
#include <system_error>

namespace talus::test {

class TempDir {
 public:
  explicit TempDir(const std::string& name)
      : path_(std::filesystem::temp_directory_path() / (name + "-" + std::to_string(::getpid()))) {
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

}  // namespace talus::test
