#include "host/data_files.hpp"

#include <cstdlib>
#include <filesystem>
#include <vector>

#include "host/error.hpp"

namespace talus {

namespace {
// the folders searched for data/, in order
std::vector<std::string> data_roots() {
  std::vector<std::string> roots;
  if (const char* env = std::getenv("TALUS_DATA_DIR")) roots.emplace_back(env);
  roots.emplace_back("data");
  roots.emplace_back(std::string(TALUS_SOURCE_DIR) + "/data");
  return roots;
}
}  // namespace

std::string locate_data_file(const std::string& relative) {
  namespace fs = std::filesystem;
  for (auto& root : data_roots()) {
    fs::path p = fs::path(root) / relative;
    if (fs::exists(p)) return p.string();
  }
  return {};
}

std::string find_data_file(const std::string& relative) {
  std::string found = locate_data_file(relative);
  if (!found.empty()) return found;
  std::string searched;
  for (auto& root : data_roots()) searched += " " + root + "/" + relative;
  throw InputError("data file '" + relative + "' not found (looked in" + searched +
                   "); set TALUS_DATA_DIR to the folder holding talus's data/");
}

}  // namespace talus
