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
// `ENV talus bench dig ARGS --quiet --json FILE`, its JSON (null when it failed)
nlohmann::json bench_dig(const std::string& args, const std::string& file,
                         const std::string& env = "") {
  const auto json = std::filesystem::temp_directory_path() / file;
  std::filesystem::remove(json);
  const test::Outcome o =
      test::run_talus(env, "bench dig " + args + " --quiet --json " + json.string());
  EXPECT_EQ(o.code, 0) << o.err;
  if (o.code != 0) return nullptr;
  std::ifstream in(json);
  return nlohmann::json::parse(in);
}

// the stages add up to the profiled step, within 10 % (what falls between two stages)
void expect_stages_add_up(const nlohmann::json& j) {
  double sum = 0.0;
  for (const auto& [name, ms] : j.at("stages").items()) sum += ms.get<double>();
  EXPECT_NEAR(sum, j.at("profiled_ms_per_step").get<double>(),
              0.1 * j.at("profiled_ms_per_step").get<double>());
}

TEST(CmdBench, DigWritesTheCostBreakdown) {
  const nlohmann::json j =
      bench_dig("--scenario hd27 --level D400 --seconds 0.2", "talus_bench_dig.json");
  ASSERT_FALSE(j.is_null());
  EXPECT_EQ(j.at("level"), "D400");
  EXPECT_EQ(j.at("scenario"), "HD27");
  EXPECT_GT(j.at("particles").get<int>(), 500);
  EXPECT_GT(j.at("realtime_factor").get<double>(), 0.0);
  EXPECT_GT(j.at("ms_per_step").get<double>(), 0.0);
  EXPECT_EQ(j.at("steps").get<int>(), 10);
  ASSERT_TRUE(j.at("stages").is_object());
  EXPECT_GT(j.at("stages").at("particle_sweeps").get<double>(), 0.0);
  EXPECT_EQ(j.at("bucket_sweep"), "serial");
  expect_stages_add_up(j);
}

// the coloured bucket sweep (issue 13) is a study of the same command: named in the JSON, the
// bucket rows charged to their own stage
TEST(CmdBench, DigWithTheColouredBucketSweep) {
  const nlohmann::json j =
      bench_dig("--scenario hd27 --level D400 --seconds 0.6 --bucket-sweep coloured",
                "talus_bench_dig_coloured.json");
  ASSERT_FALSE(j.is_null());
  EXPECT_EQ(j.at("bucket_sweep"), "coloured");
  EXPECT_GT(j.at("bucket_contacts").get<double>(), 0.0);
  EXPECT_GT(j.at("stages").at("bucket_rows").get<double>(), 0.0);
  expect_stages_add_up(j);
}

// a system above the one-group threshold on a CPU device is walked in parts and their boundary
// (DemSettings::sweep_parts): here D400's with the threshold at 0, in 2 parts, named in the JSON,
// with a boundary the parts' walks leave to the last
TEST(CmdBench, DigInPartsCountsTheBoundarysRows) {
  const nlohmann::json j =
      bench_dig("--scenario hd27 --level D400 --seconds 0.2 --one-group-rows 0 --sweep-parts 2",
                "talus_bench_dig_parts.json");
  ASSERT_FALSE(j.is_null());
  EXPECT_EQ(j.at("sweep_parts").get<int>(), 2);
  const std::string device = j.at("device").get<std::string>();
  if (device.find("Portable Computing Language") == std::string::npos)
    GTEST_SKIP() << "not PoCL (its sweeps are coloured): " << device;
  EXPECT_GT(j.at("boundary_rows").get<double>(), 0.0);
  EXPECT_LT(j.at("boundary_rows").get<double>(), 0.5 * j.at("contacts").get<double>());
  expect_stages_add_up(j);
}

// at a type-G level (issue 14) the breakdown charges the terrain's own stages (the zone and its
// excavation, spawning and merging, the avalanche) beside the zone's DEM and the machine's solve,
// and counts the zone's particles
TEST(CmdBench, DigAtATypeGLevelChargesTheTerrainsStages) {
  const nlohmann::json j =
      bench_dig("--scenario hd27 --level G400 --seconds 2", "talus_bench_dig_g400.json");
  ASSERT_FALSE(j.is_null());
  EXPECT_EQ(j.at("level"), "G400");
  EXPECT_GT(j.at("particles").get<double>(), 0.0);
  const auto& stages = j.at("stages");
  for (const char* name :
       {"zone_excavation", "spawn_merge", "avalanche", "direct_solve", "particle_sweeps"})
    EXPECT_TRUE(stages.contains(name)) << name;
  // the kinematic bucket's rows are solved inside the particle sweeps (solvers/kinematic_tool_rows)
  EXPECT_FALSE(stages.contains("bucket_rows"));
  expect_stages_add_up(j);
  // the zone runs its level's sweeps: no tolerance applied, whatever the option's default
  EXPECT_EQ(j.at("sweep_tolerance_m_s").get<double>(), 0.0);
}

// a small type-G level steps in the calling thread (PoCL's basic device, which the tool lists
// itself unless POCL_DEVICES says otherwise; terrain/pile device_choice_for), and PoCL's
// threaded device digs the same bits
TEST(CmdBench, ASmallTypeGLevelStepsInTheCallingThreadWithTheSameBits) {
  const std::string args = "--scenario hd27 --level G400 --seconds 2";
  const nlohmann::json own = bench_dig(args, "talus_bench_dig_own.json", "env -u POCL_DEVICES");
  const nlohmann::json threads =
      bench_dig(args, "talus_bench_dig_threads.json", "POCL_DEVICES=pthread");
  ASSERT_FALSE(own.is_null());
  ASSERT_FALSE(threads.is_null());
  const std::string device = own.at("device").get<std::string>();
  if (device.find("Portable Computing Language") == std::string::npos)
    GTEST_SKIP() << "not PoCL: " << device;
  // PoCL's in-thread driver: `basic`, named `cpu-minimal` from PoCL 5
  EXPECT_TRUE(device.find("/ basic") != std::string::npos ||
              device.find("/ cpu-minimal") != std::string::npos)
      << device;
  EXPECT_NE(threads.at("device").get<std::string>(), device);
  EXPECT_EQ(own.at("loaded_mass_kg").get<double>(), threads.at("loaded_mass_kg").get<double>());
  EXPECT_GT(own.at("loaded_mass_kg").get<double>(), 0.0);
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

// talus bench plot: two devices' JSON files in one figure; a file that is not a bench dem
// result is refused naming the file and the field, and nothing is drawn
TEST(CmdBench, PlotDrawsOneLinePerDeviceAndNamesABadField) {
  const auto dir = std::filesystem::temp_directory_path() / "talus_bench_plot";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  auto write = [&](const std::string& name, const nlohmann::json& j) {
    std::ofstream((dir / name).string()) << j.dump();
    return (dir / name).string();
  };
  auto level = [](const char* name, double updates, double speed) {
    return nlohmann::json{
        {"level", name}, {"contact_updates_per_s", updates}, {"realtime_factor", speed}};
  };
  const std::string cpu = write(
      "cpu.json", {{"device", "Portable Computing Language / pthread-x (2 compute units, 5 MiB)"},
                   {"results",
                    {level("D400", 1.1e7, 3.9),
                     level("D200", 2.7e7, 0.033),
                     {{"level", "settle10k"}, {"wall_s", 7.3}}}}});
  const std::string gpu =
      write("gpu.json", {{"device", "NVIDIA CUDA / NVIDIA H100 (132 compute units, 1 MiB)"},
                         {"results", {level("D400", 4.1e7, 15.1), level("D50", 5.4e9, 0.042)}}});
  const std::string png = (dir / "throughput.png").string();
  test::Outcome o = test::run_talus("", "bench plot " + cpu + " " + gpu + " --out " + png);
  ASSERT_EQ(o.code, 0) << o.err;
  EXPECT_GT(std::filesystem::file_size(png), 1000u);
  // a level with a negative rate: the file, the entry and the key
  std::filesystem::remove(png);
  const std::string bad = write("bad.json", {{"results", {level("D200", -1.0, 0.03)}}});
  o = test::run_talus("", "bench plot " + cpu + " " + bad + " --out " + png);
  EXPECT_EQ(o.code, 2) << o.err;
  EXPECT_NE(o.err.find(bad + ": results[0] (D200): 'contact_updates_per_s'"), std::string::npos)
      << o.err;
  EXPECT_FALSE(std::filesystem::exists(png));
  // a labels list that does not match the files
  o = test::run_talus("", "bench plot " + cpu + " " + gpu + " --labels one --out " + png);
  EXPECT_EQ(o.code, 2) << o.err;
  EXPECT_NE(o.err.find("--labels"), std::string::npos) << o.err;
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
  // the coloured bucket sweep is a type-D study
  o = test::run_talus("", "bench dig --level G400 --bucket-sweep coloured --quiet");
  EXPECT_EQ(o.code, 2) << o.err;
  EXPECT_NE(o.err.find("--bucket-sweep coloured at G400"), std::string::npos) << o.err;
}

}  // namespace
}  // namespace talus
