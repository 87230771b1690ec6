// `talus run` end to end: the output contract of SPEC §2.4 for the machine alone and for digging.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "terrain/multiscale_terrain.hpp"

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
  // which talus made it and how: version, commit, the command line as typed
  EXPECT_FALSE(summary.at("talus_version").get<std::string>().empty());
  EXPECT_FALSE(summary.at("git_commit").get<std::string>().empty());
  EXPECT_NE(summary.at("command_line").get<std::string>().find("run --scenario flat-lift --out"),
            std::string::npos);
  // lifting 3.5 t and the 2.6 t boom and bucket by metres: work in the hundreds of kJ
  EXPECT_GT(summary["work_J"].get<double>(), 1e5);
  EXPECT_FALSE(std::filesystem::exists(dir / "timeseries.csv.tmp"));
}

// a run killed while it rewrites a folder leaves no summary.json (the run's completion mark,
// written last; the old one is removed when the run starts), so compare refuses the folder rather
// than pair the old summary with new files
TEST(VehicleRunTest, AKilledRunLeavesNoSummaryAndCompareRefusesIt) {
  const auto dir = std::filesystem::temp_directory_path() / "talus_run_killed";
  std::filesystem::remove_all(dir);
  const std::string first =
      kTalus + " run --scenario load-carry --quiet --out " + dir.string() + " 2>/dev/null";
  ASSERT_EQ(std::system(first.c_str()), 0) << first;
  ASSERT_TRUE(std::filesystem::exists(dir / "summary.json"));
  // the HD27 D200 pile takes most of a minute to settle: killed (SIGKILL) two seconds in
  const std::string killed = "timeout -s KILL 2 " + kTalus +
                             " run --scenario hd27 --fidelity D200 --quiet --out " + dir.string() +
                             " 2>/dev/null";
  const int status = std::system(killed.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 137);  // timeout's code for a KILLed command
  EXPECT_FALSE(std::filesystem::exists(dir / "summary.json"));
  const auto err = std::filesystem::temp_directory_path() / "talus_run_killed.err";
  const std::string compare = kTalus + " compare --sim " + dir.string() + " --ref " + dir.string() +
                              " >/dev/null 2>" + err.string();
  const int compared = std::system(compare.c_str());
  EXPECT_EQ(WEXITSTATUS(compared), 2);
  std::stringstream message;
  message << std::ifstream(err).rdbuf();
  EXPECT_NE(message.str().find("did not finish"), std::string::npos) << message.str();
}

// an interval beyond the run (1e308, "never") takes the start's snapshot only; it overflowed the
// step count and took one every step
TEST(DiggingRunTest, ASnapshotIntervalBeyondTheRunTakesOnlyTheStart) {
  const auto dir = std::filesystem::temp_directory_path() / "talus_run_snapshots_never";
  std::filesystem::remove_all(dir);
  const std::string cmd =
      kTalus + " run --scenario hd27 --fidelity D400 --snapshot-interval 1e308 --quiet --out " +
      dir.string() + " 2>/dev/null";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  EXPECT_TRUE(std::filesystem::exists(dir / "snapshots" / "particles_0.vtp"));
  EXPECT_FALSE(std::filesystem::exists(dir / "snapshots" / "particles_1.vtp"));
}

// the main job at the coarsest level: the HD27 pile scenario at D400 end to end, with every output
// the issue names (the physics of the run is tested in tests/digging/digging_test.cpp)
TEST(DiggingRunTest, Hd27AtD400WritesTheRunContractSnapshotsAndFigures) {
  const auto dir = std::filesystem::temp_directory_path() / "talus_run_hd27_d400";
  std::filesystem::remove_all(dir);
  const std::string cmd = kTalus + " run --scenario hd27 --fidelity D400 --snapshot-interval 3 --quiet --out " +
                          dir.string() + " 2>/dev/null";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  // 9 s at 100 Hz from 20 ms steps (samples between steps interpolated)
  std::ifstream csv(dir / "timeseries.csv");
  std::string line;
  int rows = -1;
  while (std::getline(csv, line)) ++rows;
  EXPECT_EQ(rows, 901);
  const auto summary = nlohmann::json::parse(std::ifstream(dir / "summary.json"));
  for (const char* key :
       {"scenario", "fidelity", "particles", "loaded_mass_kg", "work_J", "sim_time_s",
        "wall_time_s", "realtime_factor", "dig_start_s", "dig_end_s", "pile_from_cache"}) {
    EXPECT_TRUE(summary.contains(key)) << key;
  }
  EXPECT_EQ(summary["scenario"], "HD27");
  EXPECT_EQ(summary["fidelity"], "D400");
  EXPECT_NEAR(summary["particles"].get<double>(), 800, 0.15 * 800);  // paper Table 3
  // a type-D run's particles are its pile's, the same at every step
  EXPECT_EQ(summary["particles_most"].get<double>(), summary["particles"].get<double>());
  EXPECT_EQ(summary["particles_mean"].get<double>(), summary["particles"].get<double>());
  EXPECT_GT(summary["loaded_mass_kg"].get<double>(), 0.0);
  EXPECT_GT(summary["work_J"].get<double>(), 0.0);
  // the coupled step's bucket sweep, the default chain (--bucket-sweep)
  EXPECT_EQ(summary["coupling"]["bucket_sweep"], "serial");
  // snapshots at 0, 3, 6, 9 s and their ParaView collection; the pile scan; the figures
  for (int k = 0; k < 4; ++k)
    EXPECT_TRUE(std::filesystem::exists(dir / "snapshots" / ("particles_" + std::to_string(k) + ".vtp"))) << k;
  for (const char* file : {"particles.pvd", "scan.csv", "channels.png", "trajectory.png", "power.png", "side.png"})
    EXPECT_GT(std::filesystem::file_size(dir / file), 100u) << file;
  // the soil's force on the bucket, one row a step (450 of 20 ms), each finite, with its parts
  // by the bucket's faces
  std::ifstream soil(dir / "bucket_soil.csv");
  std::getline(soil, line);
  EXPECT_EQ(line,
            "t,fx,fy,fz,mx,my,mz,fx_below,fy_below,fz_below,fx_inside,fy_inside,fz_inside,"
            "fx_across,fy_across,fz_across");
  int steps = 0;
  double lift_below = 0.0, push_across = 0.0;
  while (std::getline(soil, line)) {
    std::istringstream cells(line);
    std::vector<double> row;
    for (std::string cell; std::getline(cells, cell, ',');) {
      row.push_back(std::stod(cell));
      EXPECT_TRUE(std::isfinite(row.back())) << line;
    }
    ASSERT_EQ(row.size(), 16u) << line;
    lift_below = std::max(lift_below, row[9]);
    push_across = std::max(push_across, std::abs(row[13]));
    ++steps;
  }
  EXPECT_EQ(steps, 450);
  // the load in the bucket every 0.1 s from the start (91 samples of 9 s), the last the
  // summary's load, an empty bucket at the start and a loaded one after the fill
  std::ifstream load(dir / "load.csv");
  std::getline(load, line);
  EXPECT_EQ(line, "t,loaded_kg");
  std::vector<std::pair<double, double>> samples;
  while (std::getline(load, line)) {
    const size_t comma = line.find(',');
    ASSERT_NE(comma, std::string::npos) << line;
    samples.emplace_back(std::stod(line.substr(0, comma)), std::stod(line.substr(comma + 1)));
  }
  ASSERT_EQ(samples.size(), 91u);
  for (size_t k = 0; k < samples.size(); ++k) {
    EXPECT_NEAR(samples[k].first, 0.1 * static_cast<double>(k), 1e-9) << k;
    EXPECT_GE(samples[k].second, 0.0) << k;
  }
  EXPECT_EQ(samples.front().second, 0.0);
  // (the CSV's 9 digits against the summary's 17)
  EXPECT_NEAR(samples.back().second, summary["loaded_mass_kg"].get<double>(),
              1e-8 * summary["loaded_mass_kg"].get<double>());
  // HD27-D400's dig: by 3.5 s the soil under the bottom has borne the bucket up by 62 kN and the
  // faces across the cutting direction taken 163 kN at the most (Digging.
  // ItsLogsGoThroughASavedStateBitForBit); a tenth of that is far above what a wrong split leaves
  EXPECT_GT(lift_below, 6e3);
  EXPECT_GT(push_across, 16e3);
}

// the damping-time study (issue 11: a halved timestep also halved the contacts' SPOOK damping
// time, two steps): the summary records the damping time the dig used, the default two steps of
// the level's 20 ms, and a changed one changes the dig but not its pile
TEST(DiggingRunTest, ADampingTimeStudyChangesTheDigAloneAndIsRecorded) {
  const auto base = std::filesystem::temp_directory_path() / "talus_run_damping_default";
  const auto study = std::filesystem::temp_directory_path() / "talus_run_damping_study";
  for (const auto& [dir, flag] :
       {std::pair{base, std::string()}, std::pair{study, std::string(" --damping-time 0.01")}}) {
    std::filesystem::remove_all(dir);
    const std::string cmd = kTalus +
                            " run --scenario hd27 --fidelity D400 --snapshot-interval 0 --quiet" +
                            flag + " --out " + dir.string() + " 2>/dev/null";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  }
  const auto a = nlohmann::json::parse(std::ifstream(base / "summary.json"));
  const auto b = nlohmann::json::parse(std::ifstream(study / "summary.json"));
  EXPECT_DOUBLE_EQ(a.at("damping_time_s").get<double>(), 2 * 0.02);
  EXPECT_DOUBLE_EQ(b.at("damping_time_s").get<double>(), 0.01);
  auto text = [](const std::filesystem::path& file) {
    std::ifstream in(file);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  EXPECT_EQ(text(base / "scan.csv"), text(study / "scan.csv"));  // the same settled pile
  EXPECT_NE(text(base / "timeseries.csv"), text(study / "timeseries.csv"));
  EXPECT_NE(a.at("work_J").get<double>(), b.at("work_J").get<double>());
}

// a type-G level runs the same scenario end to end (~2 s): the run contract, the model named in
// the summary, a loaded bucket, the terrain's surface before and after for ParaView, and the
// aggregate step by step
TEST(DiggingRunTest, Hd27AtG400WritesTheRunContractAndTheTerrain) {
  const auto dir = std::filesystem::temp_directory_path() / "talus_run_hd27_g400";
  std::filesystem::remove_all(dir);
  const std::string cmd = kTalus + " run --scenario hd27 --fidelity G400 --quiet --out " +
                          dir.string() + " 2>/dev/null";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  const auto summary = nlohmann::json::parse(std::ifstream(dir / "summary.json"));
  EXPECT_EQ(summary.at("fidelity").get<std::string>(), "G400");
  EXPECT_EQ(summary.at("model").get<std::string>(), "multiscale (type G)");
  EXPECT_GT(summary.at("loaded_mass_kg").get<double>(), 0.0);
  // the particles over the steps: the most at any step's end bounds their mean and the count at
  // the end; the zone's particles come and go, so the mean lies below the most (paper Table 3
  // bounds G400's at about 55: docs/multiscale.md "How many particles")
  const double most = summary.at("particles_most").get<double>();
  EXPECT_GT(most, 0.0);
  EXPECT_LT(summary.at("particles_mean").get<double>(), most);
  EXPECT_GT(summary.at("particles_mean").get<double>(), 0.0);
  EXPECT_EQ(summary.at("coupling").at("merge_speed_m_s").get<double>(), talus::kMergeSpeed);
  for (const char* file :
       {"timeseries.csv", "channels.png", "trajectory.png", "side.png", "terrain.vts",
        "terrain_start.vts", "scan.csv", "aggregate.csv", "load.csv"})
    EXPECT_GT(std::filesystem::file_size(dir / file), 100u) << file;
  std::ifstream vts(dir / "terrain.vts");
  const std::string text((std::istreambuf_iterator<char>(vts)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("StructuredGrid"), std::string::npos);
  EXPECT_NE(text.find("Name=\"compaction\""), std::string::npos);
  // the aggregate's pose: its centre and the unit quaternion of its principal axes, every step
  std::ifstream csv(dir / "aggregate.csv");
  std::string header, row;
  std::getline(csv, header);
  EXPECT_NE(header.find(",cx,cy,cz,"), std::string::npos) << header;
  EXPECT_NE(header.find(",qx,qy,qz,qw,i1,i2,i3"), std::string::npos) << header;
  // then the terrain's support, the held load, the soil's whole force on the bucket, the
  // particles' own in the terrain's DEM, interface B's on the aggregate and the zone's particles'
  // mean velocity
  EXPECT_NE(header.find(",i3,fx_support,fy_support,fz_support,held_mass,fx_soil,fy_soil,fz_soil,"
                        "fx_particles,fy_particles,fz_particles,fx_terrain,fy_terrain,fz_terrain,"
                        "vx_zone,vy_zone,vz_zone"),
            std::string::npos)
      << header;
  int rows = 0, posed = 0, moving = 0;
  while (std::getline(csv, row)) {
    std::vector<double> v;
    std::istringstream cells(row);
    for (std::string cell; std::getline(cells, cell, ',');) v.push_back(std::stod(cell));
    ASSERT_EQ(v.size(), 39u) << row;
    const double norm = std::hypot(std::hypot(v[16], v[17]), std::hypot(v[18], v[19]));
    EXPECT_NEAR(norm, 1.0, 1e-6) << row;
    EXPECT_LE(v[20], v[21]) << row;
    EXPECT_LE(v[21], v[22]) << row;
    ++rows;
    if (v[1] > 0 && v[20] > 0.0) ++posed;  // particles in the zone: a body with inertia
    // particles in the zone that move (the bucket pushes them): a mean velocity of theirs
    if (v[1] > 0 && std::hypot(v[36], v[38]) > 0.0) ++moving;
  }
  EXPECT_GT(rows, 10);
  EXPECT_GT(posed, 0);
  EXPECT_GT(moving, 0);
}

TEST(DiggingRunTest, UnknownFidelityIsBadInput) {
  const std::string cmd = kTalus + " run --scenario hd27 --fidelity D300 --out /tmp/talus_hd27_bad 2>/dev/null";
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 2);
}

// the sweep's cycles are independent: one process, two MPI ranks, or two shards merged by
// --collect give the same results to the last digit (the cycles are bit-identical wherever they run)
TEST(SweepRunTest, OneProcessTwoRanksAndTwoShardsAgree) {
  const auto base = std::filesystem::temp_directory_path() / "talus_sweep";
  std::filesystem::remove_all(base);
  const std::string args = " sweep --scenario fb35 --fidelity D400 --samples 2 --max-time 8 --quiet --out ";
  auto read = [](const std::filesystem::path& p) {
    std::ifstream in(p);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  };
  // one process, with each cycle's time series (--traces: a 100 Hz row from 0 s to the cycle's
  // time T, the third column of sweep.csv)
  ASSERT_EQ(std::system((kTalus + args + (base / "one").string() + " --traces 2>/dev/null").c_str()), 0);
  const std::string one = read(base / "one" / "D400" / "sweep.csv");
  EXPECT_NE(one.find("\n0,"), std::string::npos) << one;
  EXPECT_NE(one.find("\n1,"), std::string::npos) << one;
  std::istringstream rows(one);
  std::string row;
  std::getline(rows, row);  // header
  for (int i = 0; std::getline(rows, row); ++i) {
    std::istringstream cells(row);
    std::string s, mass, time;
    std::getline(cells, s, ',');
    std::getline(cells, mass, ',');
    std::getline(cells, time, ',');
    const std::string trace = read(base / "one" / "D400" / ("cycle-" + std::to_string(i) + ".csv"));
    EXPECT_EQ(trace.rfind("t,f_lift,f_tilt,f_traction,", 0), 0u) << i;
    const long samples = std::count(trace.begin(), trace.end(), '\n') - 1;
    EXPECT_NEAR(static_cast<double>(samples), 100.0 * std::stod(time) + 1.0, 1.0) << i;
  }
  EXPECT_TRUE(std::filesystem::exists(base / "one" / "sweep.png"));
  EXPECT_TRUE(std::filesystem::exists(base / "one" / "summary.json"));
  // two shards, then --collect
  for (const char* shard : {"0/2", "1/2"})
    ASSERT_EQ(std::system((kTalus + args + (base / "shards").string() + " --shard " + shard + " 2>/dev/null").c_str()), 0);
  ASSERT_EQ(std::system((kTalus + args + (base / "shards").string() + " --collect 2>/dev/null").c_str()), 0);
  EXPECT_EQ(read(base / "shards" / "D400" / "sweep.csv"), one);
  // two MPI ranks (mpirun from Debian's openmpi-bin; root needs Open MPI's explicit consent)
  const std::string mpi = "mpirun --allow-run-as-root --oversubscribe -np 2 " + kTalus + args +
                          (base / "mpi").string() + " 2>/dev/null";
  ASSERT_EQ(std::system(mpi.c_str()), 0) << mpi;
  EXPECT_EQ(read(base / "mpi" / "D400" / "sweep.csv"), one);
}

}  // namespace
