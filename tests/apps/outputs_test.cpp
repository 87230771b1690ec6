// apps/outputs.hpp: every command that writes a folder starts it without a previous summary.json
// and writes its summary last with the talus and the command line that made it (issue 15); synth
// records them in the answer key, not in the data, whose loop must not read its effects.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "apps/outputs.hpp"
#include "host/error.hpp"
#include "host/version.hpp"
#include "tests/apps/cli_test_util.hpp"

namespace talus {
namespace {

namespace fs = std::filesystem;

nlohmann::json read_json(const fs::path& file) {
  std::ifstream in(file);
  return nlohmann::json::parse(in);
}

// a folder holding an old summary.json the command must not leave behind if it fails midway
fs::path folder_with_old_summary(const std::string& name) {
  fs::path dir = fs::temp_directory_path() / ("talus_outputs_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "summary.json") << R"({"stale": true})";
  return dir;
}

void expect_provenance(const nlohmann::json& j, const std::string& words) {
  EXPECT_EQ(j.value("talus_version", ""), talus_version());
  EXPECT_EQ(j.value("git_commit", ""), git_commit());
  EXPECT_NE(j.value("command_line", "").find(words), std::string::npos) << j.dump();
  EXPECT_FALSE(j.contains("stale"));
}

// pile and soil: a finished command's summary carries its provenance
TEST(Outputs, PileAndSoilSummariesSayWhichTalusMadeThemAndHow) {
  const fs::path pile = folder_with_old_summary("pile");
  ASSERT_EQ(
      test::run_talus("", "pile --level D400 --max-time 1 --quiet --out " + pile.string()).code, 0);
  expect_provenance(read_json(pile / "summary.json"), "pile --level D400 --max-time 1");
  const fs::path soil = folder_with_old_summary("soil");
  ASSERT_EQ(test::run_talus("", "soil --test collapse --level D400 --out " + soil.string()).code,
            0);
  expect_provenance(read_json(soil / "summary.json"), "soil --test collapse --level D400");
}

// bad input is refused before the folder is touched (the old run is kept whole); a command killed
// after it started its folder leaves no summary, old or new, so the folder cannot pass for a
// finished one
TEST(Outputs, BadInputKeepsTheOldFolderAndAKilledCommandLeavesNoSummary) {
  const fs::path dir = folder_with_old_summary("killed");
  const auto bad = test::run_talus(
      "", "pile --level D400 --profile /proc/nope.json --quiet --out " + dir.string());
  EXPECT_EQ(bad.code, 2) << bad.err;
  EXPECT_TRUE(fs::exists(dir / "summary.json"));
  // a D200 pile settles for about 40 s here: killed after 3 s, it is midway
  const auto killed =
      test::run_talus("timeout -s KILL 3", "pile --level D200 --quiet --out " + dir.string());
  EXPECT_NE(killed.code, 0);
  EXPECT_FALSE(fs::exists(dir / "summary.json"));
}

// SIGINT and SIGTERM stop a command between steps (host/interrupt.hpp): exit 128 + the signal,
// one line naming what it was doing and how far it had come, no summary.json and no temporary file
TEST(Outputs, AnInterruptStopsBetweenStepsAndSaysWhere) {
  auto no_temporary_files = [](const fs::path& dir) {
    for (const auto& e : fs::recursive_directory_iterator(dir))
      EXPECT_EQ(e.path().string().find(".tmp"), std::string::npos) << e.path();
  };
  // a D200 pile settles for about 40 s here: Ctrl-C after 3 s
  const fs::path pile = folder_with_old_summary("interrupted_pile");
  const auto sigint = test::run_talus("timeout --preserve-status -s INT 3",
                                      "pile --level D200 --quiet --out " + pile.string());
  EXPECT_EQ(sigint.code, 130) << sigint.err;
  EXPECT_NE(sigint.err.find("interrupted by SIGINT during pile D200 at"), std::string::npos)
      << sigint.err;
  EXPECT_FALSE(fs::exists(pile / "summary.json"));
  no_temporary_files(pile);
  // a D200 dig from a pile it builds: a scheduler's SIGTERM after 5 s
  const fs::path run = folder_with_old_summary("interrupted_run");
  const auto sigterm = test::run_talus(
      "timeout --preserve-status -s TERM 5",
      "run --scenario hd27 --fidelity D200 --no-pile-cache --quiet --out " + run.string());
  EXPECT_EQ(sigterm.code, 143) << sigterm.err;
  EXPECT_NE(sigterm.err.find("interrupted by SIGTERM during"), std::string::npos) << sigterm.err;
  EXPECT_FALSE(fs::exists(run / "summary.json"));
  no_temporary_files(run);
}

// every command that runs long stops on Ctrl-C (issue 15): exit 130, its last line on stderr the
// one that says where it stopped, no summary.json in its folder and no temporary file. Each is
// interrupted 3 s after it starts, inside its pile, settling, test, cycle or candidate search
TEST(Outputs, EveryLongCommandStopsOnSigintWithOneLine) {
  const fs::path base = fs::temp_directory_path() / "talus_outputs_sigint";
  fs::remove_all(base);
  fs::create_directories(base);
  const std::string b = base.string();
  // two short measured-like runs for diagnose
  for (const char* sc : {"flat-lift", "load-carry"}) {
    const std::string d = b + "/data-" + sc;
    ASSERT_EQ(test::run_talus("", std::string("synth --scenario ") + sc +
                                      " --effect hydraulic_lag --quiet --out " + d +
                                      " --answer-key " + d + ".key.json")
                  .code,
              0);
  }
  struct Command {
    std::string name, args, out;  // out: the folder or file it writes ("" none)
  };
  const std::vector<Command> commands = {
      {"pile", "pile --level D200 --out " + b + "/pile", b + "/pile"},
      {"repose", "repose --diameter 0.1 --out " + b + "/repose", b + "/repose"},
      {"soil", "soil --test shear --level D200 --out " + b + "/soil", b + "/soil"},
      {"cut", "cut --level D200 --out " + b + "/cut", b + "/cut"},
      {"bench dem", "bench dem --json " + b + "/dem.json", b + "/dem.json"},
      {"bench dig",
       "bench dig --scenario hd27 --level D200 --seconds 5 --no-pile-cache --json " + b +
           "/dig.json",
       b + "/dig.json"},
      {"run", "run --scenario hd27 --fidelity D200 --out " + b + "/run", b + "/run"},
      {"sweep", "sweep --scenario fb35 --fidelity D200 --samples 3 --out " + b + "/sweep",
       b + "/sweep"},
      {"synth",
       "synth --scenario hd27 --fidelity D200 --out " + b + "/synth --answer-key " + b + "/k.json",
       b + "/synth"},
      {"diagnose",
       "diagnose --data " + b + "/data-flat-lift " + b + "/data-load-carry --out " + b + "/diag",
       b + "/diag"}};
  for (const Command& c : commands) {
    SCOPED_TRACE(c.name);
    // a pile cache of its own: cached piles would shorten the runs before the signal; sized for
    // this 2-core machine's CPU device (each command runs well past 3 s here)
    const auto r = test::run_talus(
        "TALUS_CACHE_DIR=" + b + "/cache timeout --preserve-status -s INT 3", c.args);
    EXPECT_EQ(r.code, 130) << r.err;
    // the last line says so; what came before is the command's own progress
    std::string last = r.err.substr(0, r.err.find_last_not_of('\n') + 1);
    last = last.substr(last.find_last_of('\n') + 1);
    EXPECT_EQ(last.rfind("talus: interrupted by SIGINT during ", 0), 0u) << r.err;
    if (fs::is_directory(c.out)) {
      EXPECT_FALSE(fs::exists(fs::path(c.out) / "summary.json"));
      for (const auto& e : fs::recursive_directory_iterator(c.out))
        EXPECT_EQ(e.path().string().find(".tmp"), std::string::npos) << e.path();
    } else {
      EXPECT_FALSE(fs::exists(c.out)) << "a JSON written by an interrupted command";
    }
  }
  fs::remove_all(base);
}

// SIGKILL cannot be caught: every command that writes a folder is killed 3 s after it starts,
// inside its pile, settling, test, cycle or candidate search, and the folder must hold no
// completion mark, neither its own nor the previous run's (summary.json; diagnose's is
// diagnosis.json), so nothing can take it for a finished one
TEST(Outputs, EveryFolderCommandKilledMidwayLeavesNoCompletionMark) {
  const fs::path base = fs::temp_directory_path() / "talus_outputs_sigkill";
  fs::remove_all(base);
  fs::create_directories(base);
  const std::string b = base.string();
  // two short measured-like runs for diagnose
  for (const char* sc : {"flat-lift", "load-carry"}) {
    const std::string d = b + "/data-" + sc;
    ASSERT_EQ(test::run_talus("", std::string("synth --scenario ") + sc +
                                      " --effect hydraulic_lag --quiet --out " + d +
                                      " --answer-key " + d + ".key.json")
                  .code,
              0);
  }
  struct Command {
    std::string name, args, mark;  // mark: the file that says the folder is complete
  };
  const std::vector<Command> commands = {
      {"pile", "pile --level D200", "summary.json"},
      {"repose", "repose --diameter 0.1", "summary.json"},
      {"soil", "soil --test shear --level D200", "summary.json"},
      {"cut", "cut --level D200", "summary.json"},
      {"run", "run --scenario hd27 --fidelity D200", "summary.json"},
      {"sweep", "sweep --scenario fb35 --fidelity D200 --samples 3", "summary.json"},
      {"synth", "synth --scenario hd27 --fidelity D200", "summary.json"},
      {"diagnose", "diagnose --data " + b + "/data-flat-lift " + b + "/data-load-carry",
       "diagnosis.json"}};
  for (const Command& c : commands) {
    SCOPED_TRACE(c.name);
    const fs::path out = base / ("out-" + c.name);
    fs::create_directories(out);
    std::ofstream(out / c.mark) << R"({"stale": true})";
    // a pile cache of its own, so that no cached pile shortens the command before the signal
    const auto r = test::run_talus("TALUS_CACHE_DIR=" + b + "/cache timeout -s KILL 3",
                                   c.args + " --quiet --out " + out.string());
    EXPECT_NE(r.code, 0) << "finished before it was killed: " << r.err;
    EXPECT_FALSE(fs::exists(out / c.mark));
  }
  fs::remove_all(base);
}

// output estimated beyond the free space is refused before it is written, with the estimate, the
// free space and the fix in one line (talus run checks its snapshots this way after the first)
TEST(Outputs, OutputThatWouldNotFitIsRefusedWithItsEstimate) {
  EXPECT_NO_THROW(app::check_room(1.0e9, 2'000'000'000u, "snapshots", "take fewer"));
  try {
    app::check_room(2.5e9, 1'000'000'000u, "--snapshot-interval 0.01: 100 more snapshots",
                    "take fewer");
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_STREQ(
        e.what(),
        "--snapshot-interval 0.01: 100 more snapshots would write about 2.5 GB, where 1 GB "
        "is free; take fewer");
  }
}

// synth: the data's summary comes last and carries no command line (it names the effects); the
// answer key has the provenance
TEST(Outputs, SynthKeepsItsCommandLineInTheAnswerKey) {
  const fs::path dir = folder_with_old_summary("synth");
  const fs::path key = fs::temp_directory_path() / "talus_outputs_synth.key.json";
  const auto r =
      test::run_talus("", "synth --scenario flat-lift --effect hydraulic_lag --quiet --out " +
                              dir.string() + " --answer-key " + key.string());
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json data = read_json(dir / "summary.json");
  EXPECT_FALSE(data.contains("command_line")) << data.dump();
  EXPECT_FALSE(data.contains("stale"));
  expect_provenance(read_json(key), "--effect hydraulic_lag");
}

}  // namespace
}  // namespace talus
