#include "host/files.hpp"

#include <unistd.h>

#include <array>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "host/error.hpp"

namespace talus {

void make_output_dir(const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw InputError("--out " + dir + ": cannot create the folder (" + ec.message() + ")");
  // a folder that exists may still refuse files: find out now, not after the run
  check_writable((std::filesystem::path(dir) / ".talus-write-check").string(), "--out");
}

std::string temporary_name(const std::string& path) {
  // unique per process and machine, so two runs writing the same file cannot mix their halves,
  // not even MPI ranks on two machines sharing a folder (the pile cache)
  std::array<char, 256> host{};
  if (::gethostname(host.data(), host.size() - 1) != 0) host[0] = '\0';
  return path + ".tmp" + std::to_string(::getpid()) +
         (host[0] ? std::string(".") + host.data() : std::string());
}

void check_writable(const std::string& path, const std::string& flag) {
  const std::string tmp = temporary_name(path);
  std::ofstream probe(tmp, std::ios::binary);
  if (!probe)
    throw InputError(flag + " " + path +
                     ": cannot write there (does the folder exist, and may you write in it?); "
                     "choose a writable path before the run starts");
  probe.close();
  std::error_code ec;
  std::filesystem::remove(tmp, ec);
}

void move_into_place(const std::string& tmp, const std::string& path) {
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    throw Error(path + ": cannot move the finished file into place (" + ec.message() + ")");
  }
}

void write_file_atomically(const std::string& path, const std::string& content) {
  std::string tmp = temporary_name(path);
  std::error_code ec;
  {
    std::ofstream out(tmp, std::ios::binary);
    if (!out) throw Error(path + ": cannot write (check the folder exists and is writable)");
    out << content;
    out.close();
    if (!out) {
      std::filesystem::remove(tmp, ec);
      throw Error(path + ": write failed (disk full?); the previous file, if any, is untouched");
    }
  }
  move_into_place(tmp, path);
}

void write_json(const std::string& path, const nlohmann::json& j) {
  write_file_atomically(path, j.dump(2) + "\n");
}

std::string read_file_bytes(const std::string& path, const std::string& why_needed) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream bytes;
  if (in) bytes << in.rdbuf();
  if (!in || in.bad())
    throw InputError(path + ": cannot read the file (" + why_needed +
                     "); check the name or path and that you may read it");
  return bytes.str();
}

nlohmann::json read_json_file(const std::string& path, const std::string& why_needed) {
  std::ifstream in(path);
  if (!in)
    throw InputError(path + ": cannot open the file (" + why_needed + "); check the name or path");
  try {
    return nlohmann::json::parse(in);
  } catch (const nlohmann::json::parse_error& e) {
    throw InputError(path + ": not valid JSON (" + e.what() +
                     "); fix the syntax at the byte given");
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path + ": not readable as JSON (" + e.what() +
                     "); write numbers within ±1.8e308");
  }
}

std::string default_cache_dir() {
  // the XDG base directory specification's order, with talus's own variable first
  if (const char* dir = std::getenv("TALUS_CACHE_DIR"); dir && *dir) return dir;
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg)
    return (std::filesystem::path(xdg) / "talus").string();
  if (const char* home = std::getenv("HOME"); home && *home)
    return (std::filesystem::path(home) / ".cache" / "talus").string();
  return "";
}

}  // namespace talus
