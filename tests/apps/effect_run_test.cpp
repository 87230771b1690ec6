// `talus run --effect ... --effect-plugin ...` end to end on the machine alone (flat-lift): the
// time series carries the effect, the summary names it, bad effects are bad input.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

namespace {

const std::string kTalus = std::string(TALUS_BINARY_DIR) + "/talus";

// timeseries.csv as rows of numbers (header skipped)
std::vector<std::vector<double>> read_rows(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::string line;
  std::getline(in, line);
  std::vector<std::vector<double>> rows;
  while (std::getline(in, line)) {
    std::vector<double> row;
    std::stringstream cells(line);
    std::string cell;
    while (std::getline(cells, cell, ',')) row.push_back(std::stod(cell));
    rows.push_back(row);
  }
  return rows;
}

// exit code of a command line (-1 when it did not exit)
int exit_code(const std::string& cmd) {
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::filesystem::path run_flat_lift(const std::string& name, const std::string& effects) {
  const auto dir = std::filesystem::temp_directory_path() / name;
  std::filesystem::remove_all(dir);
  const std::string cmd = kTalus + " run --scenario flat-lift --quiet " + effects + " --out " + dir.string() + " 2>/dev/null";
  EXPECT_EQ(exit_code(cmd), 0) << cmd;
  return dir;
}

TEST(EffectRunTest, SensorBiasShiftsTheLiftForceChannelOnly) {
  const auto plain = run_flat_lift("talus_effect_run_plain", "");
  const auto biased = run_flat_lift("talus_effect_run_bias", "--effect sensor_bias:channel=f_lift,bias=1000");
  const auto a = read_rows(plain / "timeseries.csv"), b = read_rows(biased / "timeseries.csv");
  ASSERT_EQ(a.size(), 1401u);
  ASSERT_EQ(b.size(), a.size());
  // columns: t, f_lift, f_tilt, f_traction, v_drive, d_lift, ..., power (last)
  for (size_t k = 0; k < a.size(); ++k) {
    ASSERT_NEAR(b[k][1] - a[k][1], 1000.0, 1e-6 * std::abs(a[k][1]) + 1e-6) << "row " << k;
    for (size_t c = 0; c + 1 < a[k].size(); ++c) {
      if (c != 1) {
        ASSERT_EQ(b[k][c], a[k][c]) << "row " << k << " column " << c;
      }
    }
  }
  const auto summary = nlohmann::json::parse(std::ifstream(biased / "summary.json"));
  EXPECT_EQ(summary["effects"], nlohmann::json::parse(R"([{"name":"sensor_bias","params":{"bias":1000.0,"channel":"f_lift"}}])"));
  const auto none = nlohmann::json::parse(std::ifstream(plain / "summary.json"));
  EXPECT_EQ(none["effects"], nlohmann::json::array());
}

// the digging path: the logged sensors go through the effects, the particles and the machine do not
// notice a sensor effect (the same loaded mass, every other channel bit-identical)
TEST(EffectRunTest, DiggingRunLogsWhatTheSensorsReport) {
  auto dig = [](const std::string& name, const std::string& effects) {
    const auto dir = std::filesystem::temp_directory_path() / name;
    std::filesystem::remove_all(dir);
    const std::string cmd = kTalus + " run --scenario hd27 --fidelity D400 --snapshot-interval 0 --quiet " + effects +
                            " --out " + dir.string() + " 2>/dev/null";
    EXPECT_EQ(exit_code(cmd), 0) << cmd;
    return dir;
  };
  const auto plain = dig("talus_effect_dig_plain", "");
  const auto biased = dig("talus_effect_dig_bias", "--effect sensor_bias:channel=f_tilt,bias=-2000");
  const auto a = read_rows(plain / "timeseries.csv"), b = read_rows(biased / "timeseries.csv");
  ASSERT_EQ(a.size(), 901u);
  ASSERT_EQ(b.size(), a.size());
  for (size_t k = 0; k < a.size(); ++k) {
    ASSERT_NEAR(b[k][2] - a[k][2], -2000.0, 1e-6 * std::abs(a[k][2]) + 1e-6) << "row " << k;
    for (size_t c = 0; c + 1 < a[k].size(); ++c) {
      if (c != 2) {
        ASSERT_EQ(b[k][c], a[k][c]) << "row " << k << " column " << c;
      }
    }
  }
  const auto sa = nlohmann::json::parse(std::ifstream(plain / "summary.json"));
  const auto sb = nlohmann::json::parse(std::ifstream(biased / "summary.json"));
  EXPECT_EQ(sa["loaded_mass_kg"], sb["loaded_mass_kg"]);
  EXPECT_EQ(sb["effects"][0]["name"], "sensor_bias");
}

TEST(EffectRunTest, PluginEffectRunsAndIsListed) {
  const auto dir = run_flat_lift("talus_effect_run_plugin", std::string("--effect-plugin ") + TALUS_EXAMPLE_EFFECT_PLUGIN +
                                                                " --effect flow_relief:speed=0.1 --effect hydraulic_lag");
  const auto summary = nlohmann::json::parse(std::ifstream(dir / "summary.json"));
  ASSERT_EQ(summary["effects"].size(), 2u);
  EXPECT_EQ(summary["effects"][0]["name"], "flow_relief");
  EXPECT_EQ(summary["effects"][0]["plugin"], TALUS_EXAMPLE_EFFECT_PLUGIN);
  EXPECT_EQ(summary["effects"][1]["params"]["time_constant"], 0.2);
}

TEST(EffectRunTest, BadEffectsAreBadInput) {
  const std::string out = " --out /tmp/talus_effect_run_bad 2>/dev/null";
  EXPECT_EQ(exit_code(kTalus + " run --scenario flat-lift --effect hydraulic_lag:time_constant=9" + out), 2);
  EXPECT_EQ(exit_code(kTalus + " run --scenario flat-lift --effect rain" + out), 2);
  EXPECT_EQ(exit_code(kTalus + " run --scenario flat-lift --effect-plugin /nonexistent/lib.so" + out), 2);
  // soil cohesion needs particles: flat-lift has none
  EXPECT_EQ(exit_code(kTalus + " run --scenario flat-lift --effect soil_cohesion" + out), 2);
}

}  // namespace
