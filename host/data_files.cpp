#include "host/data_files.hpp"

#include <cstdlib>
#include <filesystem>
#include <system_error>

#include "host/error.hpp"

namespace talus {

namespace fs = std::filesystem;

namespace {

// a folder that looks like talus's data/: the machines and scenarios are there
bool is_data_folder(const fs::path& p) {
  std::error_code ec;
  return fs::is_directory(p / "machines", ec) && fs::is_directory(p / "scenarios", ec);
}

// the running program's folder (Linux: /proc/self/exe); empty when it cannot be read
fs::path program_folder() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  return ec ? fs::path() : exe.parent_path();
}

}  // namespace

std::vector<std::string> data_search_paths() {
  std::vector<std::string> roots;
  // the user's choice, then the working folder's data/
  if (const char* env = std::getenv("TALUS_DATA_DIR")) roots.emplace_back(env);
  roots.emplace_back("data");
  // beside the program: the nearest folder up from it with data/ or share/talus/data/
  for (fs::path dir = program_folder(); !dir.empty(); dir = dir.parent_path()) {
    if (is_data_folder(dir / "data")) {
      roots.push_back((dir / "data").string());
      break;
    }
    if (is_data_folder(dir / "share" / "talus" / "data")) {
      roots.push_back((dir / "share" / "talus" / "data").string());
      break;
    }
    if (dir == dir.root_path()) break;
  }
  return roots;
}

std::string locate_data_file(const std::string& relative) {
  for (const auto& root : data_search_paths()) {
    const fs::path p = fs::path(root) / relative;
    std::error_code ec;
    if (fs::exists(p, ec)) return p.string();
  }
  return {};
}

std::string find_data_file(const std::string& relative) {
  std::string found = locate_data_file(relative);
  if (!found.empty()) return found;
  std::string searched;
  for (const auto& root : data_search_paths()) searched += " " + root + "/" + relative;
  throw InputError("data file '" + relative + "' not found (looked in" + searched +
                   "); set TALUS_DATA_DIR to the folder holding talus's data/");
}

}  // namespace talus
