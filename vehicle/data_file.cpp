#include "vehicle/data_file.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>

#include "host/data_files.hpp"
#include "host/error.hpp"
#include "host/files.hpp"

namespace talus::vehicle {

DataFile::DataFile(const std::string& path)
    : path_(path), root_(read_json_file(path, "a talus data file")) {
  if (!root_.is_object()) fail("(top level)", "is not a JSON object", "wrap the file's fields in { }");
}

void DataFile::fail(const std::string& field, const std::string& problem, const std::string& fix) const {
  throw InputError(path_ + ": field '" + field + "' " + problem + "; " + fix);
}

const nlohmann::json& DataFile::member(const nlohmann::json& j, const std::string& where, const std::string& key) const {
  const std::string field = where.empty() ? key : where + "." + key;
  if (!j.is_object() || !j.contains(key)) fail(field, "is missing", "add it (see data/machines/wa320.json for the layout)");
  return j.at(key);
}

const nlohmann::json& DataFile::quantity(const nlohmann::json& j, const std::string& where, const std::string& key) const {
  const std::string field = where.empty() ? key : where + "." + key;
  const auto& q = member(j, where, key);
  if (!q.is_object() || !q.contains("value")) fail(field, "has no \"value\"", "write it as {\"value\": ..., \"source\": \"...\"}");
  const bool sourced = (q.contains("source") && q.at("source").is_string() && !q.at("source").get<std::string>().empty()) ||
                       (q.contains("note") && q.at("note").is_string() && !q.at("note").get<std::string>().empty());
  if (!sourced) fail(field, "has no \"source\"", "say where the value comes from (paper, class data, or the estimate's reasoning)");
  return q.at("value");
}

double DataFile::number(const nlohmann::json& j, const std::string& where, const std::string& key) const {
  const auto& v = quantity(j, where, key);
  if (!v.is_number() || !std::isfinite(v.get<double>())) {
    fail(where + "." + key + ".value", "is not a finite number", "give a number in SI units");
  }
  return v.get<double>();
}

Vec3 DataFile::vec3(const nlohmann::json& j, const std::string& where, const std::string& key) const {
  const auto& v = quantity(j, where, key);
  if (!v.is_array() || v.size() != 3 || !v[0].is_number() || !v[1].is_number() || !v[2].is_number()) {
    fail(where + "." + key + ".value", "is not three numbers", "give [x, y, z] in metres");
  }
  return Vec3(v[0].get<double>(), v[1].get<double>(), v[2].get<double>());
}

std::string DataFile::text(const nlohmann::json& j, const std::string& where, const std::string& key) const {
  const auto& v = member(j, where, key);
  if (!v.is_string()) fail(where + "." + key, "is not a string", "give a name in quotes");
  return v.get<std::string>();
}

double DataFile::plain_number(const nlohmann::json& j, const std::string& where, const std::string& key) const {
  const auto& v = member(j, where, key);
  if (!v.is_number() || !std::isfinite(v.get<double>())) {
    fail(where.empty() ? key : where + "." + key, "is not a finite number", "give a number in SI units");
  }
  return v.get<double>();
}

std::string find_data_file(const std::string& name_or_path, const std::string& subdir) {
  namespace fs = std::filesystem;
  if (fs::exists(name_or_path) && fs::is_regular_file(name_or_path)) return name_or_path;
  // a shipped name: data/<subdir>/<name>.json where host/data_files looks for data
  return locate_data_file(subdir + "/" + name_or_path + ".json");
}

}  // namespace talus::vehicle
