// Program binaries kept between runs: the OpenCL programs talus builds from its embedded kernels,
// saved as the driver's binaries in <cache>/kernels and created from them in the next process.
//
// Why: PoCL keeps its compiled kernels itself (POCL_CACHE_DIR), but it finds them only after
// preprocessing the whole source with clang at every build, a quarter of a one-second G400 run
// (`perf`, 2026-11-29); a program created from its binary skips the front end. The key is every
// byte the binary depends on (the source after the shared headers, the build options, the
// platform's and device's names and versions and the driver's version), stored in the file and
// compared, so a new kernel source or driver is a miss, never a stale binary. Whatever goes wrong
// (no cache folder, a damaged file, a driver that refuses the binary) falls back to building the
// source: the cache only ever saves time (docs/embedding.md "Caches").
#pragma once
#include <optional>
#include <string>

namespace talus {

// the bytes a program's binary depends on (what the cache compares)
std::string program_cache_key(const std::string& source, const std::string& options,
                              const std::string& platform, const std::string& device);
// the binary saved under `key` in `dir` (empty dir: the cache is off), if one is there whole
std::optional<std::string> read_program_binary(const std::string& dir, const std::string& key);
// saves `binary` under `key` (a file written whole or not at all); false when it cannot be
bool save_program_binary(const std::string& dir, const std::string& key, const std::string& binary);

}  // namespace talus
