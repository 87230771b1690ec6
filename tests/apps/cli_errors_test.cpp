// The command line's contract for failures: one message on stderr naming what is wrong and
// how to fix it, exit code 1 for a runtime failure and 2 for bad input (apps/talus.cpp).
#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "tests/apps/cli_test_util.hpp"

namespace {

using talus::test::kTalus;
using talus::test::Outcome;

Outcome run(const std::string& env, const std::string& args) {
  return talus::test::run_talus(env, args);
}

TEST(CliErrors, NoOpenClPlatformSaysHowToInstallPocl) {
  auto out_dir = std::filesystem::temp_directory_path() / "talus_no_platform";
  // an ICD search path with no vendor files: the loader finds no platform
  Outcome o = run("OCL_ICD_VENDORS=/nonexistent-talus-icd", "pile --level D400 --quiet --out " + out_dir.string());
  EXPECT_EQ(o.code, 1) << o.err;
  EXPECT_NE(o.err.find("no OpenCL platform"), std::string::npos) << o.err;
  EXPECT_NE(o.err.find("pocl-opencl-icd"), std::string::npos) << o.err;
}

TEST(CliErrors, UnknownLevelIsBadInputListingTheKnownOnes) {
  Outcome o = run("", "pile --level D75 --out /tmp/talus_unused");
  EXPECT_EQ(o.code, 2) << o.err;
  EXPECT_NE(o.err.find("D100"), std::string::npos) << o.err;
}

TEST(CliErrors, MalformedProfileNamesFileAndField) {
  auto path = (std::filesystem::temp_directory_path() / "talus_bad_profile_cli.json").string();
  std::ofstream(path) << R"({"width_m": -1, "rear_wall_x_m": 5, "profile_xz_m": [[0, 0], [1, 1]]})";
  Outcome o = run("", "pile --level D400 --profile " + path + " --out /tmp/talus_unused");
  EXPECT_EQ(o.code, 2) << o.err;
  EXPECT_NE(o.err.find(path), std::string::npos) << o.err;
  EXPECT_NE(o.err.find("width_m"), std::string::npos) << o.err;
}

// every numeric flag refuses NaN and infinity before anything runs, naming the flag: CLI11's range
// checks compare, and every comparison with NaN is false (`repose --diameter nan` hung the device
// in the contact colouring; `repose --friction nan` exited 0 with a 0.85 deg heap)
TEST(CliErrors, NonFiniteNumbersAreBadInputNamingTheFlag) {
  const std::string out = " --out " + (std::filesystem::temp_directory_path() / "talus_unused_nan").string();
  const char* cases[][2] = {
      {"repose --diameter nan", "--diameter"},
      {"repose --dt nan", "--dt"},
      {"repose --friction nan", "--friction"},
      {"repose --rolling inf", "--rolling"},
      {"repose --wall-speed nan", "--wall-speed"},
      {"pile --level D400 --max-time nan", "--max-time"},
      {"run --scenario hd27 --fidelity D400 --snapshot-interval nan", "--snapshot-interval"},
      {"run --scenario hd27 --fidelity D400 --damping-time nan", "--damping-time"},
      {"sweep --fidelity D400 --approach nan", "--approach"},
      {"sweep --fidelity D400 --max-time inf", "--max-time"},
      {"synth --scenario flat-lift --vary-inputs nan", "--vary-inputs"},
  };
  for (const auto& c : cases) {
    const Outcome o = run("", std::string(c[0]) + out);
    EXPECT_EQ(o.code, 2) << c[0] << ": " << o.err;
    EXPECT_NE(o.err.find(c[1]), std::string::npos) << c[0] << ": " << o.err;
    EXPECT_NE(o.err.find("finite number"), std::string::npos) << c[0] << ": " << o.err;
  }
  // the flags without --out: bench and the metric flags of compare
  for (const char* args : {"bench dem --settle-dt nan", "compare --sim a --ref b --l-norm nan",
                           "compare --sim a --ref b --dig-start nan", "compare --sim a --ref b --force-constant inf"}) {
    const Outcome o = run("", args);
    EXPECT_EQ(o.code, 2) << args << ": " << o.err;
    EXPECT_NE(o.err.find("finite number"), std::string::npos) << args << ": " << o.err;
  }
}

// every output path is checked before any simulation starts (a D200 dig would otherwise fail at
// its end, minutes later, and lose everything): --json of run, sweep and soil, synth's answer key,
// an --out that cannot be made; each refusal names the flag and comes within seconds
TEST(CliErrors, UnwritableOutputsAreRefusedBeforeTheRun) {
  const char* cases[][2] = {
      {"--json",
       "run --scenario hd27 --fidelity D200 --quiet --out /tmp/talus_unused_out --json "
       "/proc/talus-no-such-folder/s.json"},
      {"--json",
       "soil --test shear --level D200 --out /tmp/talus_unused_out --json "
       "/proc/talus-no-such-folder/s.json"},
      {"--json",
       "sweep --scenario fb35 --fidelity D400 --samples 2 --out /tmp/talus_unused_out --json "
       "/proc/talus-no-such-folder/s.json"},
      {"--answer-key",
       "synth --scenario load-carry --out /tmp/talus_unused_synth --answer-key "
       "/proc/talus-no-such-folder/k.json"},
      {"--out", "run --scenario load-carry --out /proc/talus-no-such-folder"},
  };
  for (const auto& c : cases) {
    const auto start = std::chrono::steady_clock::now();
    const Outcome o = run("", c[1]);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    EXPECT_EQ(o.code, 2) << c[1] << "\n" << o.err;
    EXPECT_NE(o.err.find(c[0]), std::string::npos) << c[1] << "\n" << o.err;
    EXPECT_LT(seconds, 10.0) << c[1];  // refused, not simulated first
  }
  EXPECT_FALSE(std::filesystem::exists("/tmp/talus_unused_synth"))
      << "synth left its run without a key";
}

// an unknown subcommand is named with the list of known ones; a range error names the flag and
// the value in a short line (CLI11's own checks printed DBL_MAX as a 309-digit bound)
TEST(CliErrors, UnknownSubcommandAndRangeErrorsSayWhatIsWrong) {
  Outcome o = run("", "bogus");
  EXPECT_EQ(o.code, 2) << o.err;
  EXPECT_NE(o.err.find("unknown subcommand 'bogus'"), std::string::npos) << o.err;
  EXPECT_NE(o.err.find("run"), std::string::npos) << o.err;
  o = run("", "run --scenario hd27 --dt -1 --out /tmp/talus_unused_range");
  EXPECT_EQ(o.code, 2) << o.err;
  EXPECT_NE(o.err.find("--dt: must be a finite number from 0.0001 to 0.05 s, got '-1'"),
            std::string::npos)
      << o.err;
  EXPECT_LT(o.err.size(), 200u) << o.err;
  o = run("", "pile --settle-iterations 0 --out /tmp/talus_unused_range");
  EXPECT_EQ(o.code, 2) << o.err;
  EXPECT_NE(o.err.find("--settle-iterations"), std::string::npos) << o.err;
  o = run("", "compare --sim a --ref b --l-norm 0");
  EXPECT_EQ(o.code, 2) << o.err;
  EXPECT_NE(o.err.find("--l-norm"), std::string::npos) << o.err;
  // the diagnosis's thread count: a whole number from 0 (every hardware thread) to 1024
  for (const char* threads : {"-1", "2000", "nan", "two"}) {
    o = run("", std::string("diagnose --data /tmp --threads ") + threads);
    EXPECT_EQ(o.code, 2) << threads << ": " << o.err;
    EXPECT_NE(o.err.find("--threads"), std::string::npos) << o.err;
  }
}

// a formwork withdrawal speed asks for a free face: with the default held face it is refused
// before the pile is filled, naming the flag that settles the pile free
TEST(CliErrors, AFormworkSpeedWithAHeldFaceNamesFreeFace) {
  for (const char* command : {"run --scenario hd27 --form-speed 0.5 --out /tmp/talus_unused_form",
                              "pile --form-speed 0.5 --out /tmp/talus_unused_form"}) {
    const Outcome o = run("", command);
    EXPECT_EQ(o.code, 2) << command << ": " << o.err;
    EXPECT_NE(o.err.find("--form-speed"), std::string::npos) << o.err;
    EXPECT_NE(o.err.find("--free-face"), std::string::npos) << o.err;
  }
}

// a vehicle-only scenario: its flags are checked though it uses no particles (--fidelity D37 and
// --sweep bogus were ignored), and a payload the machine cannot hold is refused naming the file
// and field (1e12 kg ran to exit 0 with the machine at 90 degrees of pitch)
TEST(CliErrors, VehicleScenarioFlagsAndPayloadAreChecked) {
  Outcome o = run("", "run --scenario load-carry --fidelity D37 --out /tmp/talus_unused_vehicle");
  EXPECT_EQ(o.code, 2) << o.err;
  EXPECT_NE(o.err.find("D37"), std::string::npos) << o.err;
  o = run("", "run --scenario load-carry --sweep bogus --out /tmp/talus_unused_vehicle");
  EXPECT_EQ(o.code, 2) << o.err;
  EXPECT_NE(o.err.find("--sweep"), std::string::npos) << o.err;
  const auto path = (std::filesystem::temp_directory_path() / "talus_heavy_scenario.json").string();
  std::ofstream(path)
      << R"({"name": "heavy", "machine": "wa320", "duration": 1, "timestep": 0.005, "payload": 1e12,
                           "drive": [[0, 0]], "lift": [[0, 0]], "tilt": [[0, 0]]})";
  o = run("", "run --scenario " + path + " --out /tmp/talus_unused_vehicle");
  EXPECT_EQ(o.code, 2) << o.err;
  EXPECT_NE(o.err.find(path + ": field 'payload'"), std::string::npos) << o.err;
  EXPECT_NE(o.err.find("static tipping load"), std::string::npos) << o.err;
}

// a POCL_CACHE_DIR PoCL cannot write is named (it read "no OpenCL platform found" or a failed
// kernel build, exit 1)
TEST(CliErrors, AnUnwritablePoclCacheIsNamed) {
  const std::string file =
      (std::filesystem::temp_directory_path() / "talus_pocl_cache_file").string();
  std::ofstream(file) << "not a folder";
  for (const std::string& dir : {std::string("/proc/nope"), file}) {
    const Outcome o =
        run("POCL_CACHE_DIR=" + dir, "pile --level D400 --quiet --out /tmp/talus_unused_pocl");
    EXPECT_EQ(o.code, 2) << o.err;
    EXPECT_NE(o.err.find("POCL_CACHE_DIR=" + dir), std::string::npos) << o.err;
  }
}

// flags whose value sets a step count or a physical load have a stated range: beyond it a run
// overflowed its step count (exit 0 with one sample), ran for days, or answered nonsense with exit
// 0 (a bulk density of -174 kg/m^3, a repose angle of 0). Each is refused at once, exit 2, with the
// flag, its range and unit, and the value
TEST(CliErrors, StepCountsAndLoadsOutsideTheirRangeAreRefused) {
  const std::vector<std::array<std::string, 2>> cases = {
      {"--dt", "run --scenario hd27 --dt 1e-30 --out /tmp/talus_unused_range"},
      {"--dt", "run --scenario hd27 --dt 1e30 --out /tmp/talus_unused_range"},
      {"--dt", "repose --dt 1e-30 --out /tmp/talus_unused_range"},
      {"--diameter", "repose --diameter 1e30 --out /tmp/talus_unused_range"},
      {"--wall-speed", "repose --wall-speed 1e-3 --out /tmp/talus_unused_range"},
      {"--speed", "cut --speed 1e-30 --out /tmp/talus_unused_range"},
      {"--travel", "cut --travel 1e30 --out /tmp/talus_unused_range"},
      {"--normal-stress", "soil --test shear --normal-stress 1e30 --out /tmp/talus_unused_range"},
      {"--max-time", "pile --max-time 1e-30 --out /tmp/talus_unused_range"},
      {"--max-time", "sweep --max-time 1e-30 --out /tmp/talus_unused_range"},
      {"--settle-dt", "bench dem --settle-dt 1e30"},
      // a near-zero normaliser made every error of the table astronomical
      {"--force-constant", "compare --sim a --ref b --force-constant 1e-300"},
      {"--l-norm", "compare --sim a --ref b --l-norm 1e-300"},
      {"--seconds", "bench dig --seconds 1e30"},
      {"--rolling", "run --scenario hd27 --rolling 1e30 --out /tmp/talus_unused_range"},
      // a contact damped for longer than a grain takes to land never settles within a dig
      {"--damping-time", "run --scenario hd27 --damping-time 1e30 --out /tmp/talus_unused_range"},
      {"--damping-time", "run --scenario hd27 --damping-time 1e-30 --out /tmp/talus_unused_range"},
      {"--interface-damping-time",
       "cut --level G400 --interface-damping-time 1e-30 --out /tmp/talus_unused_range"},
      {"--friction", "soil --test shear --friction 50 --out /tmp/talus_unused_range"},
      {"--form-speed", "run --scenario hd27 --form-speed 1e-4 --out /tmp/talus_unused_range"},
      {"--approach", "sweep --approach 1e30 --out /tmp/talus_unused_range"},
      {"--sweep-tolerance",
       "run --scenario hd27 --sweep-tolerance -1 --out /tmp/talus_unused_range"},
      {"--sweep-tolerance", "bench dig --sweep-tolerance 1e30"}};
  for (const auto& c : cases) {
    const Outcome o = run("", c[1]);
    EXPECT_EQ(o.code, 2) << c[1] << "\n" << o.err;
    EXPECT_NE(o.err.find(c[0] + ": must be a finite number "), std::string::npos) << c[1] << "\n"
                                                                                  << o.err;
    EXPECT_NE(o.err.find(" to "), std::string::npos) << o.err;
  }
  // a seed: a whole number, refused (naming the flag) when it is not one
  for (const char* seed : {"-3", "x", "1.5"}) {
    const Outcome o = run("", std::string("bench dem --levels D400 --settle-seed ") + seed);
    EXPECT_EQ(o.code, 2) << seed << ": " << o.err;
    EXPECT_NE(o.err.find("--settle-seed"), std::string::npos) << seed << ": " << o.err;
  }
  // a count: CLI11's range, named by the flag
  const Outcome ensemble = run("", "diagnose --data /tmp --pile-ensemble 17");
  EXPECT_EQ(ensemble.code, 2) << ensemble.err;
  EXPECT_NE(ensemble.err.find("--pile-ensemble: Value 17 not in range 1 to 16"), std::string::npos)
      << ensemble.err;
  // the one-group threshold: a whole number of rows, not negative
  for (const char* rows : {"-1", "x", "1.5"})
    for (const char* bench :
         {"bench dem --levels D400 --one-group-rows ", "bench dig --one-group-rows "}) {
      const Outcome o = run("", std::string(bench) + rows);
      EXPECT_EQ(o.code, 2) << bench << rows << ": " << o.err;
      EXPECT_NE(o.err.find("--one-group-rows"), std::string::npos)
          << bench << rows << ": " << o.err;
    }
  // the serially walked system's blocks: a whole number in 0-1024
  for (const char* lanes : {"-1", "1025", "x", "2.5"})
    for (const char* bench :
         {"bench dem --levels D400 --serial-lanes ", "bench dig --serial-lanes "}) {
      const Outcome o = run("", std::string(bench) + lanes);
      EXPECT_EQ(o.code, 2) << bench << lanes << ": " << o.err;
      EXPECT_NE(o.err.find("--serial-lanes"), std::string::npos) << bench << lanes << ": " << o.err;
    }
  // the parts of a large system: a whole number in 0-63
  for (const char* parts : {"-1", "64", "x", "1.5"})
    for (const char* bench :
         {"bench dem --levels D400 --sweep-parts ", "bench dig --sweep-parts "}) {
      const Outcome o = run("", std::string(bench) + parts);
      EXPECT_EQ(o.code, 2) << bench << parts << ": " << o.err;
      EXPECT_NE(o.err.find("--sweep-parts"), std::string::npos) << bench << parts << ": " << o.err;
    }
  // the PGS relaxation: a number in (0, 2), refused before any pile is built or folder made
  for (const char* omega : {"0", "0.001", "2", "1.99999999", "-0.5", "nan", "x"})
    for (const char* cmd : {"bench dem --levels D400 --relaxation ", "bench dig --relaxation ",
                            "run --scenario hd27 --out /tmp/talus_cli_relaxation --relaxation "}) {
      const Outcome o = run("", std::string(cmd) + omega);
      EXPECT_EQ(o.code, 2) << cmd << omega << ": " << o.err;
      EXPECT_NE(o.err.find("--relaxation"), std::string::npos) << cmd << omega << ": " << o.err;
      EXPECT_FALSE(std::filesystem::exists("/tmp/talus_cli_relaxation")) << cmd << omega;
    }
  // the type-G seed diameter: a fraction in (0, 1], at a G level only
  for (const char* seed : {"0", "0.09", "1e-9", "-0.5", "1.5", "nan", "x"}) {
    const Outcome o = run("", std::string("run --scenario hd27 --fidelity G400 --out "
                                          "/tmp/talus_cli_seed --seed-diameter ") +
                                  seed);
    EXPECT_EQ(o.code, 2) << seed << ": " << o.err;
    EXPECT_NE(o.err.find("--seed-diameter"), std::string::npos) << seed << ": " << o.err;
    EXPECT_FALSE(std::filesystem::exists("/tmp/talus_cli_seed")) << seed;
  }
  // ... at a type-D level, or for a scenario without a pile (each told what would fix it)
  const std::pair<const char*, const char*> misplaced[] = {
      {"run --scenario hd27 --fidelity D400", "give --fidelity G400"},
      {"run --scenario load-carry --fidelity G400", "has no pile"}};
  for (const auto& [cmd, fix] : misplaced) {
    const Outcome o = run("", std::string(cmd) + " --out /tmp/talus_cli_seed --seed-diameter 0.5");
    EXPECT_EQ(o.code, 2) << cmd << ": " << o.err;
    EXPECT_NE(o.err.find("--seed-diameter"), std::string::npos) << cmd << ": " << o.err;
    EXPECT_NE(o.err.find(fix), std::string::npos) << cmd << ": " << o.err;
    EXPECT_FALSE(std::filesystem::exists("/tmp/talus_cli_seed")) << cmd;
  }
  // the bucket's content by its weight alone, a factor on the cutting edge's resistance, the
  // soil under the bucket giving way, the aggregate's interfaces' damping time, the zone's
  // excavation reach, its floor of voxel columns, the surface's avalanche and the bucket's
  // resting load kept in the DEM: a pile scenario at a G level only
  for (const char* option :
       {" --no-content-inertia", " --edge-resistance 0", " --no-bucket-support",
        " --interface-damping-time 0.01", " --excavation-reach 0.6", " --merge-speed 4",
        " --no-failure-plane-floor", " --repose-angle 20", " --avalanche-rate 30",
        " --no-rest-in-bucket"}) {
    for (const char* cmd :
         {"run --scenario hd27 --fidelity D400", "run --scenario load-carry --fidelity G400"}) {
      const Outcome o = run("", std::string(cmd) + " --out /tmp/talus_cli_seed" + option);
      EXPECT_EQ(o.code, 2) << cmd << option << ": " << o.err;
      EXPECT_NE(o.err.find(std::string(option).substr(1, 17)), std::string::npos)
          << cmd << option << ": " << o.err;
      EXPECT_FALSE(std::filesystem::exists("/tmp/talus_cli_seed")) << cmd << option;
    }
  }
  // the particle sweeps' residual tolerance: a type-D level's (a G level's zone runs its N_it)
  for (const char* cmd : {"run --scenario hd27 --fidelity G400 --out /tmp/talus_cli_seed",
                          "bench dig --scenario hd27 --level G200 --json /tmp/talus_cli_seed"}) {
    const Outcome o = run("", std::string(cmd) + " --sweep-tolerance 0.001");
    EXPECT_EQ(o.code, 2) << cmd << ": " << o.err;
    EXPECT_NE(o.err.find("--sweep-tolerance"), std::string::npos) << cmd << ": " << o.err;
    EXPECT_NE(o.err.find("give a D level"), std::string::npos) << cmd << ": " << o.err;
    EXPECT_FALSE(std::filesystem::exists("/tmp/talus_cli_seed")) << cmd;
  }
  // outside its range
  const Outcome edge = run("",
                           "run --scenario hd27 --fidelity G400 --out /tmp/talus_cli_seed "
                           "--edge-resistance 12");
  EXPECT_EQ(edge.code, 2) << edge.err;
  EXPECT_NE(edge.err.find("--edge-resistance"), std::string::npos) << edge.err;
  const Outcome reach = run("",
                            "run --scenario hd27 --fidelity G400 --out /tmp/talus_cli_seed "
                            "--excavation-reach -1");
  EXPECT_EQ(reach.code, 2) << reach.err;
  EXPECT_NE(reach.err.find("--excavation-reach"), std::string::npos) << reach.err;
  for (const char* speed : {"0", "-1", "nan"}) {
    const Outcome merge = run("", std::string("run --scenario hd27 --fidelity G400 --out "
                                              "/tmp/talus_cli_seed --merge-speed ") +
                                      speed);
    EXPECT_EQ(merge.code, 2) << speed << ": " << merge.err;
    EXPECT_NE(merge.err.find("--merge-speed"), std::string::npos) << merge.err;
    EXPECT_FALSE(std::filesystem::exists("/tmp/talus_cli_seed")) << speed;
  }
  const Outcome damping = run("",
                              "run --scenario hd27 --fidelity G400 --out /tmp/talus_cli_seed "
                              "--interface-damping-time 0.7");
  EXPECT_EQ(damping.code, 2) << damping.err;
  EXPECT_NE(damping.err.find("--interface-damping-time"), std::string::npos) << damping.err;
  for (const char* option : {" --repose-angle 70", " --repose-angle 4", " --avalanche-rate -1"}) {
    const Outcome o = run("", std::string("run --scenario hd27 --fidelity G400 --out "
                                          "/tmp/talus_cli_seed") +
                                  option);
    EXPECT_EQ(o.code, 2) << option << ": " << o.err;
    EXPECT_NE(o.err.find(std::string(option).substr(1, 13)), std::string::npos) << o.err;
  }
  EXPECT_FALSE(std::filesystem::exists("/tmp/talus_cli_seed"));
  // the blade test takes it at a G level only
  const Outcome cut =
      run("", "cut --level D400 --interface-damping-time 0.01 --out /tmp/talus_cli_seed");
  EXPECT_EQ(cut.code, 2) << cut.err;
  EXPECT_NE(cut.err.find("--interface-damping-time at D400"), std::string::npos) << cut.err;
  EXPECT_FALSE(std::filesystem::exists("/tmp/talus_cli_seed"));
  // the coloured bucket sweep: a pile scenario at a type-D level only, and a known word
  for (const char* cmd : {"run --scenario hd27 --fidelity G400", "run --scenario load-carry"}) {
    const Outcome o =
        run("", std::string(cmd) + " --out /tmp/talus_cli_seed --bucket-sweep coloured");
    EXPECT_EQ(o.code, 2) << cmd << ": " << o.err;
    EXPECT_NE(o.err.find("--bucket-sweep coloured"), std::string::npos) << cmd << ": " << o.err;
    EXPECT_NE(o.err.find("D level"), std::string::npos) << cmd << ": " << o.err;
    EXPECT_FALSE(std::filesystem::exists("/tmp/talus_cli_seed")) << cmd;
  }
  for (const char* cmd : {"run --scenario hd27 --out /tmp/talus_cli_seed",
                          "bench dig --scenario hd27 --json /tmp/talus_cli_seed"}) {
    const Outcome o = run("", std::string(cmd) + " --bucket-sweep parallel");
    EXPECT_EQ(o.code, 2) << cmd << ": " << o.err;
    EXPECT_NE(o.err.find("--bucket-sweep: unknown bucket sweep 'parallel'; use 'serial' or "
                         "'coloured'"),
              std::string::npos)
        << cmd << ": " << o.err;
    EXPECT_FALSE(std::filesystem::exists("/tmp/talus_cli_seed")) << cmd;
  }
  // the Jacobi sweep has no relaxation to take
  const Outcome jacobi = run(
      "", "run --scenario hd27 --out /tmp/talus_cli_relaxation --sweep jacobi --relaxation 1.3");
  EXPECT_EQ(jacobi.code, 2) << jacobi.err;
  EXPECT_NE(jacobi.err.find("--relaxation"), std::string::npos) << jacobi.err;
  EXPECT_FALSE(std::filesystem::exists("/tmp/talus_cli_relaxation"));
  // the speculative reach takes its two words alone: a bool's 0/1 or a typo is refused, naming
  // the flag and the words it takes, before any folder is made
  for (const char* reach : {"1", "0", "bogus", "Pair"})
    for (const char* cmd : {"bench dem --levels D400 --steps 1 --no-settle10k --reach ",
                            "bench dig --seconds 0.01 --reach ",
                            "run --scenario hd27 --out /tmp/talus_cli_reach --reach "}) {
      const Outcome o = run("", std::string(cmd) + reach);
      EXPECT_EQ(o.code, 2) << cmd << reach << ": " << o.err;
      EXPECT_NE(o.err.find("--reach"), std::string::npos) << cmd << reach << ": " << o.err;
      EXPECT_NE(o.err.find("{pair,fastest}"), std::string::npos) << cmd << reach << ": " << o.err;
      EXPECT_FALSE(std::filesystem::exists("/tmp/talus_cli_reach")) << cmd << reach;
    }
}

// a shard that a crash or a hand cut up holds a value no cycle gives: --collect names the file,
// the line and the field instead of merging a negative mass or a point off the search line into
// the sweep's results
TEST(CliErrors, ADamagedShardIsNamedByFileLineAndField) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "talus_bad_shard";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir / "D400");
  const std::string header =
      "s,loaded_mass_kg,cycle_time_s,work_J,productivity_kg_s,efficiency_kg_per_kJ,completed,"
      "fill_start_s,breakout_s\n";
  std::ofstream(dir / "D400" / "shard-0.csv") << header << "0,3500,12,200000,291,17.5,1,2,9\n";
  std::ofstream(dir / "D400" / "shard-1.csv") << header << "1,-3500,12,200000,291,17.5,1,2,9\n";
  const std::string args =
      "sweep --scenario fb35 --fidelity D400 --samples 2 --collect --out " + dir.string();
  Outcome o = run("", args);
  EXPECT_EQ(o.code, 2) << o.err;
  EXPECT_NE(o.err.find("shard-1.csv: line 2: field 'loaded_mass_kg' is -3500, outside 0-1e+12"),
            std::string::npos)
      << o.err;
  std::ofstream(dir / "D400" / "shard-1.csv") << header << "1.5,3500,12,200000,291,17.5,1,2,9\n";
  o = run("", args);
  EXPECT_EQ(o.code, 2) << o.err;
  EXPECT_NE(o.err.find("shard-1.csv: line 2: field 's' is 1.5, outside 0-1"), std::string::npos)
      << o.err;
  std::filesystem::remove_all(dir);
}

}  // namespace
