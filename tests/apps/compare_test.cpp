// End to end: build/talus compare and build/talus table on small synthetic run directories.
#include <sys/wait.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "sim2real/table.hpp"
#include "tests/sim2real/synthetic_runs.hpp"

namespace talus {
namespace {

namespace fs = std::filesystem;

struct Result {
  int exit_code = -1;
  std::string output;  // stdout and stderr together
};

Result talus_cli(const std::string& args) {
  const fs::path exe = fs::path(TALUS_BINARY_DIR) / "talus";
  Result r;
  if (!fs::exists(exe)) {
    r.output = exe.string() + " does not exist; build the 'talus' target";
    return r;
  }
  const std::string command = "'" + exe.string() + "' " + args + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return r;
  char buffer[512];
  while (fgets(buffer, sizeof buffer, pipe)) r.output += buffer;
  const int status = pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

std::string read_text(const fs::path& file) {
  std::ifstream in(file);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(CompareCommandTest, PrintsPaperRowAndWritesJson) {
  const fs::path dir = test::fresh_temp_dir("cli");
  test::write_run(dir / "ref", test::reference_series(), test::reference_summary());
  test::write_run(dir / "sim", test::simulated_series(), test::simulated_summary());
  const Result r = talus_cli("compare --sim '" + (dir / "sim").string() + "' --ref '" +
                             (dir / "ref").string() + "' --json '" + (dir / "row.json").string() +
                             "'");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // the row as the paper prints it: two decimals, mean = 0.6/7 = 0.0857
  EXPECT_NE(r.output.find("| FB35-D50 | 0.05 | 0.05 | 0.00 | 0.10 | 0.20 | -0.10 | 0.10 | 0.09 |"),
            std::string::npos)
      << r.output;

  const auto j = nlohmann::json::parse(read_text(dir / "row.json"));
  for (const char* key : {"E_x", "E_v", "E_tr", "E_l", "E_t", "E_M", "E_W", "mean",
                          "dtw_distance_m", "N", "L_norm_m"}) {
    EXPECT_TRUE(j.contains(key)) << key;
  }
  EXPECT_NEAR(j.at("E_x").get<double>(), 0.05, 1e-9);
  EXPECT_NEAR(j.at("E_l").get<double>(), 0.1, 1e-12);
  EXPECT_NEAR(j.at("E_M").get<double>(), -0.1, 1e-12);
  EXPECT_NEAR(j.at("mean").get<double>(), test::kExpectedMean, 1e-9);
  EXPECT_NEAR(j.at("dtw_distance_m").get<double>(), 601 * 0.03, 1e-9);
  EXPECT_EQ(j.at("N").get<int>(), 601);
  EXPECT_NEAR(j.at("L_norm_m").get<double>(), 0.6, 1e-12);
  EXPECT_FALSE(fs::exists(dir / "row.json.tmp"));
  fs::remove_all(dir);
}

TEST(CompareCommandTest, TableOverRunsWritesCsvAndMarkdown) {
  // a reference folder with one run per scenario, two simulated runs of FB35
  const fs::path dir = test::fresh_temp_dir("cli");
  test::write_run(dir / "refs" / "FB35", test::reference_series(), test::reference_summary());
  test::write_run(dir / "d50", test::simulated_series(), test::simulated_summary("D50"));
  test::write_run(dir / "g200", test::reference_series(), test::simulated_summary("G200"));
  const Result r = talus_cli("table '" + (dir / "d50").string() + "' '" + (dir / "g200").string() +
                             "' --ref '" + (dir / "refs").string() + "' --csv '" +
                             (dir / "t.csv").string() + "' --md '" + (dir / "t.md").string() +
                             "'");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto rows = sim2real::read_table_csv(dir / "t.csv");
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].name, "FB35-D50");
  EXPECT_NEAR(rows[0].mean, test::kExpectedMean, 1e-9);
  // the second run has the reference's time series: only mass and work differ
  EXPECT_EQ(rows[1].name, "FB35-G200");
  EXPECT_NEAR(rows[1].e.e_x, 0.0, 1e-12);
  EXPECT_NEAR(rows[1].e.e_l, 0.0, 1e-12);
  EXPECT_NEAR(rows[1].mean, 0.2 / 7.0, 1e-12);
  EXPECT_NE(read_text(dir / "t.md").find("| FB35-G200 |"), std::string::npos);
  fs::remove_all(dir);
}

TEST(CompareCommandTest, MalformedReferenceExitsWithUsageCode) {
  const fs::path dir = test::fresh_temp_dir("cli");
  test::write_run(dir / "ref", test::reference_series(), test::reference_summary());
  test::write_run(dir / "sim", test::simulated_series(), test::simulated_summary());
  // a reference with most channels missing: the first one missing is named
  std::ofstream(dir / "ref" / "timeseries.csv") << "t,f_lift\n0,1\n0.01,1\n";
  const Result r = talus_cli("compare --sim '" + (dir / "sim").string() + "' --ref '" +
                             (dir / "ref").string() + "'");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("timeseries.csv:1: field 'f_tilt': missing column"), std::string::npos)
      << r.output;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace talus
