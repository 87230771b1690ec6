// talus bench dig: the command line the acceptance check uses, its JSON keys, and its
// refusals before any pile is built.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>

#include "tests/apps/cli_test_util.hpp"

namespace talus {
namespace {

// HD27 at D400 for 0.2 s from dig_start: level, particles, real-time factor, ms per step and
// the stages (name -> ms per step), the particle sweeps among them
TEST(CmdBench, DigWritesTheCostBreakdown) {
  const auto json = std::filesystem::temp_directory_path() / "talus_bench_dig.json";
  std::filesystem::remove(json);
  const test::Outcome o = test::run_talus(
      "", "bench dig --scenario hd27 --level D400 --seconds 0.2 --quiet --json " + json.string());
  ASSERT_EQ(o.code, 0) << o.err;
  std::ifstream in(json);
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j.at("level"), "D400");
  EXPECT_EQ(j.at("scenario"), "HD27");
  EXPECT_GT(j.at("particles").get<int>(), 500);
  EXPECT_GT(j.at("realtime_factor").get<double>(), 0.0);
  EXPECT_GT(j.at("ms_per_step").get<double>(), 0.0);
  EXPECT_EQ(j.at("steps").get<int>(), 10);
  ASSERT_TRUE(j.at("stages").is_object());
  EXPECT_GT(j.at("stages").at("particle_sweeps").get<double>(), 0.0);
  double sum = 0.0;
  for (const auto& [name, ms] : j.at("stages").items()) sum += ms.get<double>();
  EXPECT_NEAR(sum, j.at("profiled_ms_per_step").get<double>(),
              0.1 * j.at("profiled_ms_per_step").get<double>());
}

// talus bench dem --plot draws the levels' throughput against particle size
TEST(CmdBench, DemPlotsThroughputAgainstParticleSize) {
  const auto png = std::filesystem::temp_directory_path() / "talus_bench_dem.png";
  std::filesystem::remove(png);
  const test::Outcome o = test::run_talus(
      "", "bench dem --levels D400 --no-settle10k --steps 2 --quiet --plot " + png.string());
  ASSERT_EQ(o.code, 0) << o.err;
  EXPECT_GT(std::filesystem::file_size(png), 1000u);
  // an unwritable plot path is refused before any pile is settled
  const test::Outcome bad = test::run_talus(
      "", "bench dem --levels D400 --quiet --plot /proc/talus-no-such-folder/t.png");
  EXPECT_EQ(bad.code, 2) << bad.err;
  EXPECT_NE(bad.err.find("--plot"), std::string::npos) << bad.err;
}

// bad input is refused at once (exit 2), naming what to fix: a scenario without a pile, a JSON
// path that cannot be written, a measurement longer than the dig
TEST(CmdBench, DigRefusesBadInputBeforeBuildingThePile) {
  test::Outcome o = test::run_talus("", "bench dig --scenario load-carry --quiet");
  EXPECT_EQ(o.code, 2) << o.err;
  EXPECT_NE(o.err.find("has no pile"), std::string::npos) << o.err;
  o = test::run_talus("",
                      "bench dig --level D400 --quiet --json /proc/talus-no-such-folder/cost.json");
  EXPECT_EQ(o.code, 2) << o.err;
  EXPECT_NE(o.err.find("--json /proc/talus-no-such-folder/cost.json"), std::string::npos) << o.err;
  o = test::run_talus("", "bench dig --level D400 --seconds 60 --quiet");
  EXPECT_EQ(o.code, 2) << o.err;
  EXPECT_NE(o.err.find("--seconds"), std::string::npos) << o.err;
  o = test::run_talus("", "bench dig --level D37 --quiet");
  EXPECT_EQ(o.code, 2) << o.err;
}

}  // namespace
}  // namespace talus
