// Reading the vehicle's JSON data files: every value is an object {"value": ..., "source": "..."}
// (machine files) and every failure is one talus::InputError naming the file, the field and the fix.
#pragma once
#include <nlohmann/json.hpp>
#include <string>

#include "vehicle/rigid_body.hpp"

namespace talus::vehicle {

class DataFile {
 public:
  // parse; InputError if the file is missing or not JSON
  explicit DataFile(const std::string& path);
  const nlohmann::json& root() const { return root_; }
  const std::string& path() const { return path_; }
  // the member `key` of object j at `where` (a dotted path for messages); InputError if absent
  const nlohmann::json& member(const nlohmann::json& j, const std::string& where, const std::string& key) const;
  // a sourced quantity: j[key] = {"value": ..., "source": "..."}; returns the value
  const nlohmann::json& quantity(const nlohmann::json& j, const std::string& where, const std::string& key) const;
  double number(const nlohmann::json& j, const std::string& where, const std::string& key) const;
  Vec3 vec3(const nlohmann::json& j, const std::string& where, const std::string& key) const;
  std::string text(const nlohmann::json& j, const std::string& where, const std::string& key) const;
  // plain (unsourced) finite number, for scenario files
  double plain_number(const nlohmann::json& j, const std::string& where, const std::string& key) const;
  [[noreturn]] void fail(const std::string& field, const std::string& problem, const std::string& fix) const;

 private:
  std::string path_;
  nlohmann::json root_;
};

// a data file by name or path: an existing path as given, else <dir>/<name>.json under the source
// tree, the current directory or TALUS_DATA_DIR (host/data_files.hpp)
std::string find_data_file(const std::string& name_or_path, const std::string& subdir);

}  // namespace talus::vehicle
