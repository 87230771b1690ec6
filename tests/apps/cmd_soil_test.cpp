// talus soil and talus cut (apps/cmd_soil.cpp, apps/cmd_cut.cpp): the summaries carry the keys
// issue 11's acceptance check reads, the particle CSV has its header, and bad input exits 2.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

namespace {

const std::string kTalus = std::string(TALUS_BINARY_DIR) + "/talus";

int run(const std::string& args) {
  const int status = std::system((kTalus + " " + args + " >/dev/null 2>&1").c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

nlohmann::json summary(const std::filesystem::path& dir) {
  std::ifstream in(dir / "summary.json");
  return nlohmann::json::parse(in);
}

std::string first_line(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  return line;
}

TEST(SoilCommand, ShearAndCollapseWriteTheirAnglesAndParticles) {
  const auto dir = std::filesystem::temp_directory_path() / "talus_soil_cli";
  std::filesystem::remove_all(dir);
  ASSERT_EQ(run("soil --test shear --level D400 --quiet --out " + (dir / "shear").string()), 0);
  const auto s = summary(dir / "shear");
  for (const char* key : {"peak_friction_deg", "critical_friction_deg", "dilatancy_deg"})
    EXPECT_TRUE(s.contains(key) && s[key].is_number()) << key;
  EXPECT_GT(s["peak_friction_deg"].get<double>(), s["critical_friction_deg"].get<double>());
  EXPECT_DOUBLE_EQ(s["rolling_resistance"].get<double>(), 0.02);
  EXPECT_EQ(first_line(dir / "shear" / "particles.csv"), "x,y,z,r,vx,vy,vz");
  EXPECT_TRUE(std::filesystem::exists(dir / "shear" / "shear.png"));

  ASSERT_EQ(run("soil --test collapse --level D400 --rolling 1.0 --quiet --out " + (dir / "collapse").string()), 0);
  const auto c = summary(dir / "collapse");
  EXPECT_GT(c["aspect_ratio"].get<double>(), 0.5);
  EXPECT_GT(c["runout_ratio"].get<double>(), 0.0);
  EXPECT_DOUBLE_EQ(c["rolling_resistance"].get<double>(), 1.0);
}

TEST(SoilCommand, CutWritesForceEquationAndSeries) {
  const auto dir = std::filesystem::temp_directory_path() / "talus_cut_cli";
  std::filesystem::remove_all(dir);
  ASSERT_EQ(run("cut --level D400 --depth 0.6 --travel 0.8 --quiet --out " + dir.string()), 0);
  const auto j = summary(dir);
  EXPECT_GT(j["force_N"].get<double>(), 0.0);
  EXPECT_GT(j["fee_force_N"].get<double>(), 0.0);
  EXPECT_EQ(j["series"]["travel_m"].size(), j["series"]["force_x_N"].size());
  EXPECT_GE(j["series"]["travel_m"].size(), 8u);
  EXPECT_TRUE(std::filesystem::exists(dir / "cut.png"));
  EXPECT_EQ(first_line(dir / "particles.csv"), "x,y,z,r,vx,vy,vz");
}

// at a type-G level the same command cuts the voxels through the aggregate (~1 s): the model is
// named, the equation takes phi + psi = 40 deg, the edge's resistance is reported apart
TEST(SoilCommand, CutAtAMultiscaleLevelNamesItsModel) {
  const auto dir = std::filesystem::temp_directory_path() / "talus_cut_cli_g400";
  std::filesystem::remove_all(dir);
  ASSERT_EQ(run("cut --level G400 --depth 0.6 --quiet --out " + dir.string()), 0);
  const auto j = summary(dir);
  EXPECT_EQ(j["model"].get<std::string>(), "multiscale (type G)");
  EXPECT_DOUBLE_EQ(j["internal_friction_deg"].get<double>(), 40.0);
  EXPECT_GT(j["edge_force_N"].get<double>(), 0.0);
  EXPECT_NEAR(j["force_over_fee"].get<double>(), 1.0, 0.2);
  EXPECT_TRUE(std::filesystem::exists(dir / "cut.png"));
}

TEST(SoilCommand, BadInputIsRefusedWithExitCode2) {
  EXPECT_EQ(run("soil --test triaxial --level D400 --out /tmp/talus_unused"), 2);
  EXPECT_EQ(run("soil --test shear --level D75 --out /tmp/talus_unused"), 2);
  EXPECT_EQ(run("cut --level D400 --depth -1 --out /tmp/talus_unused"), 2);
  // deeper than the bed can be made
  EXPECT_EQ(run("cut --level D400 --depth 50 --out /tmp/talus_unused_cut"), 2);
  // not a number: refused before anything runs (range checks alone let NaN through)
  EXPECT_EQ(run("soil --test shear --level D400 --rolling nan --out /tmp/talus_unused"), 2);
  EXPECT_EQ(run("soil --test collapse --level D400 --aspect nan --out /tmp/talus_unused"), 2);
  EXPECT_EQ(run("cut --level D400 --speed nan --out /tmp/talus_unused"), 2);
  EXPECT_EQ(run("run --scenario hd27 --fidelity D400 --dt nan --out /tmp/talus_unused"), 2);
  EXPECT_EQ(run("run --scenario hd27 --fidelity D400 --rolling inf --out /tmp/talus_unused"), 2);
  EXPECT_EQ(run("run --scenario hd27 --fidelity D400 --form-speed 0.001 --out /tmp/talus_unused"), 2);
}

}  // namespace
