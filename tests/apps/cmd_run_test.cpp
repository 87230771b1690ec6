// `talus run` end to end: the output contract of SPEC §2.4 / issue 3, and the "not yet" for piles.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

namespace {

const std::string kTalus = std::string(TALUS_BINARY_DIR) + "/talus";

TEST(VehicleRunTest, FlatLiftWritesTimeseriesAndSummary) {
  const auto dir = std::filesystem::temp_directory_path() / "talus_run_flat_lift";
  std::filesystem::remove_all(dir);
  const std::string cmd = kTalus + " run --scenario flat-lift --out " + dir.string() + " 2>/dev/null";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  std::ifstream csv(dir / "timeseries.csv");
  std::string header;
  std::getline(csv, header);
  EXPECT_EQ(header,
            "t,f_lift,f_tilt,f_traction,v_drive,d_lift,d_tilt,boom_deg,bucket_deg,pitch_deg,x_vehicle,"
            "bucket_tip_x,bucket_tip_z,power");
  int rows = 0;
  std::string line;
  while (std::getline(csv, line)) ++rows;
  EXPECT_EQ(rows, 1401);  // 14 s at 100 Hz, both ends
  const auto summary = nlohmann::json::parse(std::ifstream(dir / "summary.json"));
  for (const char* key : {"work_J", "sim_time_s", "wall_time_s", "realtime_factor"}) {
    EXPECT_TRUE(summary.contains(key)) << key;
  }
  EXPECT_DOUBLE_EQ(summary["sim_time_s"].get<double>(), 14.0);
  // lifting 3.5 t and the 2.6 t boom and bucket by metres: work in the hundreds of kJ
  EXPECT_GT(summary["work_J"].get<double>(), 1e5);
  EXPECT_FALSE(std::filesystem::exists(dir / "timeseries.csv.tmp"));
}

TEST(VehicleRunTest, PileScenarioSaysNotYet) {
  const auto err = std::filesystem::temp_directory_path() / "talus_run_fb35.err";
  const std::string cmd = kTalus + " run --scenario FB35 --out /tmp/talus_fb35 2>" + err.string();
  EXPECT_NE(std::system(cmd.c_str()), 0);
  std::ifstream in(err);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("not yet: scenario FB35 needs the particle pile (issue 4)"), std::string::npos) << text;
}

}  // namespace
