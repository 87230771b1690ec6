#include "host/program_cache.hpp"

#include <filesystem>
#include <system_error>
#include <utility>

#include "host/binary.hpp"
#include "host/error.hpp"
#include "host/files.hpp"

namespace talus {

namespace {
const SealedFormat kProgramFormat{"TALUSBIN", 1, "program binary",
                                  "delete it, the kernels are built from source again"};

std::string file_of(const std::string& dir, const std::string& key) {
  return (std::filesystem::path(dir) / "kernels" / (key_file_name(key) + ".bin")).string();
}
}  // namespace

std::string program_cache_key(const std::string& source, const std::string& options,
                              const std::string& platform, const std::string& device) {
  // each part named, so two keys that differ only in where a part ends cannot coincide
  ByteWriter w;
  for (const auto& [name, part] : {std::pair{"platform", &platform}, std::pair{"device", &device},
                                   std::pair{"options", &options}, std::pair{"source", &source}}) {
    w.str(name);
    w.str(*part);
  }
  return w.bytes();
}

std::optional<std::string> read_program_binary(const std::string& dir, const std::string& key) {
  if (dir.empty()) return std::nullopt;
  const std::string file = file_of(dir, key);
  std::error_code ec;
  if (!std::filesystem::exists(file, ec)) return std::nullopt;
  try {
    // the reader views the bytes: they live as long as it
    const std::string bytes = read_file_bytes(file, "a program binary");
    ByteReader r = open_sealed(bytes, kProgramFormat, file);
    // another program under the same hash is a miss
    if (r.str("key") != key) return std::nullopt;
    return r.str("binary");
  } catch (const Error&) {
    // damaged or of another version: built from source and saved over
    return std::nullopt;
  }
}

bool save_program_binary(const std::string& dir, const std::string& key,
                         const std::string& binary) {
  if (dir.empty() || binary.empty()) return false;
  const std::string file = file_of(dir, key);
  std::error_code ec;
  std::filesystem::create_directories(std::filesystem::path(file).parent_path(), ec);
  if (ec) return false;
  ByteWriter w;
  begin_sealed(w, kProgramFormat);
  w.str(key);
  w.str(binary);
  end_sealed(w);
  try {
    write_file_atomically(file, w.bytes());
  } catch (const Error&) {
    return false;
  }
  return true;
}

}  // namespace talus
