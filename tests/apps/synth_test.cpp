// `talus synth` end to end: field-like data that loads as a measured run, carries no trace of the
// effects that made it, keeps its answer key outside, and is reproducible by its seeds.
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "sim2real/measured.hpp"

namespace {

namespace fs = std::filesystem;
const std::string kTalus = std::string(TALUS_BINARY_DIR) + "/talus";

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

int exit_code(const std::string& cmd) {
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST(SynthTest, MeasuredRunWithoutTheAnswerAndReproducibleBySeed) {
  const fs::path base = fs::temp_directory_path() / "talus_synth";
  fs::remove_all(base);
  fs::create_directories(base);
  const std::string args = " synth --scenario flat-lift --effect sensor_bias:channel=f_lift,bias=20000 --quiet";
  ASSERT_EQ(exit_code(kTalus + args + " --seed 7 --out " + (base / "a").string() + " 2>/dev/null"), 0);
  ASSERT_EQ(exit_code(kTalus + args + " --seed 7 --out " + (base / "b").string() + " 2>/dev/null"), 0);
  ASSERT_EQ(exit_code(kTalus + args + " --seed 8 --out " + (base / "c").string() + " 2>/dev/null"), 0);

  // a measured run: loads, at 100 Hz, with the scenario's operator inputs
  const auto run = talus::sim2real::load_measured_run(base / "a");
  EXPECT_EQ(run.meta.scenario, "flat-lift");
  EXPECT_EQ(run.run.summary.fidelity.value_or(""), "field");
  EXPECT_FALSE(run.meta.drive.empty());
  // nothing in the data names the effect
  for (const auto& e : fs::directory_iterator(base / "a")) {
    const std::string text = slurp(e.path());
    EXPECT_EQ(text.find("sensor_bias"), std::string::npos) << e.path();
    EXPECT_EQ(text.find("effect"), std::string::npos) << e.path();
  }
  // the answer key beside the data names it
  const auto key = nlohmann::json::parse(std::ifstream(base / "a.answer.json"));
  EXPECT_EQ(key["effects"][0]["name"], "sensor_bias");
  EXPECT_EQ(key["noise_seed"], 7);
  // the same seeds give the same data; another noise seed other noise
  EXPECT_EQ(slurp(base / "a" / "timeseries.csv"), slurp(base / "b" / "timeseries.csv"));
  EXPECT_NE(slurp(base / "a" / "timeseries.csv"), slurp(base / "c" / "timeseries.csv"));
}

TEST(SynthTest, AnswerKeyInsideTheDataAndBadNoiseAreBadInput) {
  const fs::path base = fs::temp_directory_path() / "talus_synth_bad";
  fs::remove_all(base);
  const std::string common = kTalus + " synth --scenario flat-lift --quiet --out " + (base / "d").string();
  EXPECT_EQ(exit_code(common + " --answer-key " + (base / "d" / "key.json").string() + " 2>/dev/null"), 2);
  EXPECT_EQ(exit_code(common + " --noise f_lfit=100 2>/dev/null"), 2);
  EXPECT_EQ(exit_code(common + " --noise f_lift=-1 2>/dev/null"), 2);
  EXPECT_FALSE(fs::exists(base / "d" / "timeseries.csv"));  // nothing written for bad input
}

TEST(SynthTest, QuietIsQuietForADig) {
  // a pile scenario (type G, about a second): nothing on stderr, not the run's lines naming the
  // work folder synth deletes afterwards
  const fs::path base =
      fs::temp_directory_path() / ("talus_synth_quiet_" + std::to_string(::getpid()));
  fs::remove_all(base);
  fs::create_directories(base);
  const std::string cmd = kTalus +
                          " synth --scenario hd27 --fidelity G400 --noise default --vary-inputs "
                          "0.1 --quiet --seed 3 --out " +
                          (base / "d").string() + " 2> " + (base / "stderr.txt").string();
  ASSERT_EQ(exit_code(cmd), 0) << cmd;
  EXPECT_EQ(slurp(base / "stderr.txt"), "");
  EXPECT_TRUE(fs::exists(base / "d" / "summary.json"));
  for (const auto& entry : fs::directory_iterator(base))  // the work folder is gone
    EXPECT_EQ(entry.path().filename().string().rfind("d.work-", 0), std::string::npos)
        << entry.path();
  fs::remove_all(base);
}

}  // namespace
