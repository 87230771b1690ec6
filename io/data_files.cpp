#include "io/data_files.hpp"

#include <cstdlib>
#include <filesystem>
#include <vector>

#include "host/error.hpp"

namespace talus {

std::string find_data_file(const std::string& relative) {
  namespace fs = std::filesystem;
  std::string searched;
  std::vector<std::string> roots;
  if (const char* env = std::getenv("TALUS_DATA_DIR")) roots.emplace_back(env);
  roots.emplace_back("data");
  roots.emplace_back(std::string(TALUS_SOURCE_DIR) + "/data");
  for (auto& root : roots) {
    fs::path p = fs::path(root) / relative;
    if (fs::exists(p)) return p.string();
    searched += " " + p.string();
  }
  throw InputError("data file '" + relative + "' not found (looked in" + searched +
                   "); set TALUS_DATA_DIR to the folder holding talus's data/");
}

}  // namespace talus
