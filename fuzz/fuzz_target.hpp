// The shared part of talus's fuzz targets (docs/reliability.md, "Fuzzing"): each target hands
// libFuzzer's bytes to one of the file loaders as a file, and holds the loader to its contract:
// it returns, or it throws talus::InputError (one clear message naming the file). Anything else
// is a finding: another exception type escaping (a raw nlohmann::json error, std::out_of_range,
// a bad_alloc from a size read from the file), a crash, or what the sanitizers catch in the
// fuzzing build (address, undefined behaviour).
//
// The same sources build twice: with clang's -fsanitize=fuzzer for fuzzing (fuzz/run.sh), and
// with the project's compiler against fuzz/corpus_main.cpp, which replays a saved corpus (ctest
// fuzz.*, every CI run).
#pragma once
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>
#include <typeinfo>

#include "host/error.hpp"

namespace talus::fuzz {

// a folder of this process's own under the temporary folder, for the files a loader reads;
// removed when the process exits normally
struct ScratchFolder {
  std::filesystem::path path =
      std::filesystem::temp_directory_path() / ("talus-fuzz-" + std::to_string(::getpid()));
  ScratchFolder() { std::filesystem::create_directories(path); }
  ~ScratchFolder() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
};
inline const std::filesystem::path& scratch() {
  static const ScratchFolder folder;
  return folder.path;
}

// writes bytes to a file in the scratch folder and returns its path
inline std::filesystem::path write_input(const std::string& name, const char* data,
                                         std::size_t size) {
  std::filesystem::path path = scratch() / name;
  std::ofstream(path, std::ios::binary | std::ios::trunc)
      .write(data, static_cast<std::streamsize>(size));
  return path;
}

// runs a loader on the input; an InputError is the contract kept, any other exception a finding
// (reported, then abort(): libFuzzer saves the input as a crash, the corpus replay fails)
template <typename Load>
void expect_contract(const char* target, Load&& load) {
  try {
    load();
  } catch (const InputError&) {
    // the contract: bad input is one clear InputError
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: the loader threw %s, not talus::InputError: %s\n", target,
                 typeid(e).name(), e.what());
    std::abort();
  }
}

}  // namespace talus::fuzz
