// The machine data file: every value carries its source, and malformed files fail with one clear
// InputError that names the file and the field.
#include "vehicle/data_file.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "host/error.hpp"
#include "vehicle/wheel_loader.hpp"

namespace talus::vehicle {
namespace {

// every object with a "value" has a non-empty "source" or "note"
int count_unsourced(const nlohmann::json& j, int& quantities) {
  int bad = 0;
  if (j.is_object()) {
    if (j.contains("value")) {
      ++quantities;
      const bool ok = (j.contains("source") && j["source"].is_string() && !j["source"].get<std::string>().empty()) ||
                      (j.contains("note") && j["note"].is_string());
      bad += !ok;
    }
    for (const auto& [k, v] : j.items()) bad += count_unsourced(v, quantities);
  } else if (j.is_array()) {
    for (const auto& v : j) bad += count_unsourced(v, quantities);
  }
  return bad;
}

TEST(WheelLoaderDataTest, EveryValueHasASource) {
  const DataFile f(find_data_file("wa320", "machines"));
  int quantities = 0;
  EXPECT_EQ(count_unsourced(f.root(), quantities), 0);
  EXPECT_GT(quantities, 80);
}

std::string write_temp(const std::string& name, const std::string& text) {
  const auto p = std::filesystem::temp_directory_path() / name;
  std::ofstream(p) << text;
  return p.string();
}

TEST(WheelLoaderDataTest, MalformedMachineFileNamesFileAndField) {
  // the shipped file with one body's mass removed
  DataFile f(find_data_file("wa320", "machines"));
  nlohmann::json j = f.root();
  j["bodies"][2].erase("mass");
  const std::string path = write_temp("talus_bad_machine.json", j.dump());
  try {
    WheelLoader w(path);
    FAIL() << "no error";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find(path), std::string::npos) << m;
    EXPECT_NE(m.find("bodies[2].mass"), std::string::npos) << m;
  }
  // a value without a source is refused too
  j = f.root();
  j["tyres"]["friction"].erase("source");
  EXPECT_THROW(WheelLoader(write_temp("talus_bad_machine2.json", j.dump())), InputError);
  EXPECT_THROW(WheelLoader(write_temp("talus_bad_machine3.json", "{ not json")), InputError);
}

}  // namespace
}  // namespace talus::vehicle
