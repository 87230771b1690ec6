// Discovery of a term outside the candidates (issue 17), blind and end to end on the load-carry
// scenario: `talus synth` makes two runs (one to calibrate, one held out) with an effect written
// only in tests/apps/hidden_effects.c, drawn at random from six families at random magnitudes,
// and `talus diagnose` gets the data alone; and one family on pile data (HD27-G400), a loss of the
// digging phase, for the phase features. Fresh seeds every run (TALUS_TEST_SEED repeats one).
// The documentation run (docs/discovery.md) sets TALUS_DISCOVERY_DRAWS=20 and
// TALUS_DISCOVERY_FREE_DRAWS=10; CI runs the defaults below (4 and 2).
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <random>
#include <set>
#include <string>

#include "tests/host/temp_dir.hpp"

namespace {

namespace fs = std::filesystem;
using talus::test::TempDir;
const std::string kTalus = std::string(TALUS_BINARY_DIR) + "/talus";
const std::string kHidden = TALUS_HIDDEN_EFFECTS;

int exit_code(const std::string& cmd) {
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

unsigned test_seed() {
  if (const char* s = std::getenv("TALUS_TEST_SEED")) return static_cast<unsigned>(std::stoul(s));
  return std::random_device{}();
}

int env_count(const char* name, int fallback) {
  const char* s = std::getenv(name);
  return s ? std::stoi(s) : fallback;
}

// one hidden effect: its --effect, the target the correction must act on, and the features that
// are the effect's own (any one of them in the discovered expression counts as the right feature)
struct Hidden {
  std::string spec, target;
  std::set<std::string> features;
};

// The families and their magnitudes, each large enough to show above the default sensor noise in
// load-carry and within a real machine's range:
//  leakage     speed lost in the direction of motion ∝ |F| (the pressure): lift 1-3e-7 (m/s)/N
//              (0.017-0.05 m/s at its 170 kN), tilt 4-12e-7 (m/s)/N (at its 30 kN). Its own
//              features: the force with the command's sign or with the command, or the force alone
//  dead_band   0.02-0.05 m/s on the lift only: load-carry commands the tilt at ±0.15 m/s alone,
//              where a dead band δ sign(u) and a proportional loss (δ/0.15) u are the same
//              function of the data, so no regression can tell them apart. Its own features:
//              sign(u) and the command clipped at ±δ₀ (the dictionary's dead bands)
//  load_delay  a delay k |F|: lift 0.6-1.5e-6 s/N, tilt 3-8e-6 s/N (0.1-0.25 s). Its own features:
//              the delayed differences, with or without the force
//  speed_loss  k u |u| on the drive, 0.02-0.06 s/m (0.18-0.54 m/s at 3 m/s). Its own features: the
//              command's square or the command (load-carry drives at +3 and −2 m/s only, where the
//              two differ in their ratio alone)
//  load_gain   f_tilt or f_traction read (1 + k |f_lift|), 0.5-2e-6 /N (9-35 % at 175 kN). Its own
//              feature: the load times the reading
//  inertia     a mass of 1,000-3,000 kg the model lacks (7-20 % of the wa320's 15,175 kg: a
//              counterweight or payload error), a force −k dv/dt on the frames: 3-9 kN of traction
//              at load-carry's 3 m/s²; the tractive-force target's (since 2026-12-01). Its own
//              feature: the speed's delayed difference (−0.1 s times the acceleration)
Hidden draw_hidden(std::mt19937_64& rng) {
  auto uniform = [&](double a, double b) {
    return std::uniform_real_distribution<double>(a, b)(rng);
  };
  const bool tilt = uniform(0.0, 1.0) < 0.5;
  const std::string cylinder = tilt ? "cylinder=1" : "cylinder=0";
  const std::string speed = tilt ? "tilt speed" : "lift speed";
  auto num = [](double v) {
    char s[32];
    std::snprintf(s, sizeof s, "%.4g", v);
    return std::string(s);
  };
  switch (std::uniform_int_distribution<int>(0, 5)(rng)) {
    case 0:
      return {
          "leakage:k=" + num(tilt ? uniform(4e-7, 1.2e-6) : uniform(1e-7, 3e-7)) + "," + cylinder,
          speed,
          {"force_sign_command", "abs_force_command", "force"}};
    case 1:
      return {"dead_band:k=" + num(uniform(0.02, 0.05)) + ",cylinder=0",
              "lift speed",
              {"sign_command", "dead_band_001", "dead_band_002", "dead_band_004"}};
    case 2:
      return {"load_delay:k=" + num(tilt ? uniform(3e-6, 8e-6) : uniform(0.6e-6, 1.5e-6)) + "," +
                  cylinder,
              speed,
              {"abs_force_delay_02", "delay_01", "delay_02", "delay_04"}};
    case 3:
      return {"speed_loss:k=" + num(uniform(0.02, 0.06)),
              "drive speed",
              {"command_squared", "command"}};
    case 4:
      return {"inertia:k=" + num(uniform(1000.0, 3000.0)), "tractive force", {"delay_01"}};
    default: {
      const bool traction = uniform(0.0, 1.0) < 0.5;
      return {
          "load_gain:k=" + num(uniform(0.5e-6, 2e-6)) + (traction ? ",channel=1" : ",channel=0"),
          traction ? "f_traction reading" : "f_tilt reading",
          {"abs_force_reading"}};
    }
  }
}

// two load-carry runs by a varying operator with default noise (the second held out), diagnosed
nlohmann::json synthesise_and_diagnose(const fs::path& base, const std::string& effect_args,
                                       unsigned seed, const std::string& diagnose_args = "") {
  for (int k = 0; k < 2; ++k) {
    const std::string cmd =
        kTalus + " synth --scenario load-carry --noise default --vary-inputs 0.1 --quiet --seed " +
        std::to_string(seed + k) + effect_args + " --out " +
        (base / ("run" + std::to_string(k))).string() + " 2>/dev/null";
    EXPECT_EQ(exit_code(cmd), 0) << cmd;
  }
  const fs::path json = base / "diagnosis.json";
  const std::string cmd = kTalus + " diagnose --quiet --data " + (base / "run0").string() + " " +
                          (base / "run1").string() + " --json " + json.string() + diagnose_args +
                          " > " + (base / "report.md").string();
  EXPECT_EQ(exit_code(cmd), 0) << cmd;
  return nlohmann::json::parse(std::ifstream(json));
}

// did the diagnosis discover the hidden effect: a correction of the right target with one of its
// features, cutting the held-out excess by half or more (the rule that keeps it)
bool discovered(const nlohmann::json& j, const Hidden& h, std::string& what) {
  const auto& d = j["discovered"];
  if (d.is_null()) {
    what = "nothing discovered; found " + j["effects_found"].dump();
    return false;
  }
  what = d["target"].get<std::string>() + ": " + d["expression"].get<std::string>() +
         ", held-out cut " + std::to_string(d["held_out_error_cut"].get<double>()) +
         ", held-out mean error " +
         std::to_string(d["error_before_held_out"]["mean"].get<double>()) + " -> " +
         std::to_string(d["error_after_held_out"]["mean"].get<double>());
  // a term counts with the features the data cannot tell from it (its aliases, |r| >= 0.99 over the
  // regression's rows): the discovered expression names them beside it
  bool feature = false;
  for (const auto& c : d["coefficients"]) {
    feature = feature || h.features.count(c["feature"].get<std::string>());
    for (const auto& a : c["aliases"]) feature = feature || h.features.count(a.get<std::string>());
  }
  return d["target"] == h.target && feature && d["held_out_error_cut"].get<double>() >= 0.5;
}

TEST(DiscoveryTest, FindsTheRightTermForEffectsOutsideTheCandidates) {
  const unsigned seed = test_seed();
  std::mt19937_64 rng(seed);
  const int draws = env_count("TALUS_DISCOVERY_DRAWS", 4);
  int found = 0;
  for (int draw = 0; draw < draws; ++draw) {
    const Hidden h = draw_hidden(rng);
    const unsigned run_seed = static_cast<unsigned>(rng());
    const TempDir scratch("talus_discovery_" + std::to_string(run_seed));
    const fs::path& base = scratch.path();
    const auto j = synthesise_and_diagnose(
        base, " --effect-plugin " + kHidden + " --effect " + h.spec, run_seed);
    std::string what;
    const bool ok = discovered(j, h, what);
    found += ok;
    // one line per draw: the documentation run's table is made of these
    std::cerr << "discovery draw " << draw << " (seed " << run_seed << "): " << h.spec << " -> "
              << (ok ? "FOUND " : "MISSED ") << what << "\n";
  }
  RecordProperty("found", found);
  // the bar: 80 % of the draws, held by the documentation run's 20 (docs/discovery.md:
  // 19 of 20 in the fifth run). CI's four draws need two: at a rate of 0.95 it fails by chance
  // about once in 2,000 runs, and a discovery that lost half its rate would fail it one time in
  // three
  const int needed = draws >= 10 ? (8 * draws + 9) / 10 : (draws + 1) / 2;
  EXPECT_GE(found, needed) << "TALUS_TEST_SEED=" << seed << ": " << found << " of " << draws
                           << " discovered";
}

TEST(DiscoveryTest, ALiftLossOfTheDiggingPhaseIsFoundOnPileData) {
  // the hidden dig_loss: the lift gets (1 − k) of its command inside HD27's digging phase (the
  // plug-in reads it from its context; data/scenarios/hd27.json: 1.1-8.0 s), k in 0.15-0.4, two
  // HD27-G400 digs on fresh piles by an operator who varies the inputs 10 %, default noise; the
  // second held out, hydraulic_lag the one candidate (which cannot explain it), two model piles.
  // The correction must act on the lift with the phase feature [dig]·u_lift as a term or as the
  // alias of one (on HD27 the lift moves only inside the dig, so [dig]·u and u are the same
  // function of these data and the report says so), its coefficient within 10 % of −k, and cut the
  // held-out excess by half. Measured first (2026-12-01, out/s47/phase): k = 0.15, 0.18, 0.2, 0.25,
  // 0.3, 0.4 found as −0.15, −0.18, −0.201, −0.251, −0.302, −0.4, cuts 98-100 %, 11 s a diagnosis
  const unsigned seed = test_seed();
  std::mt19937_64 rng(seed);
  const double k = std::uniform_real_distribution<double>(0.15, 0.4)(rng);
  const std::string context =
      "TALUS_TEST_SEED=" + std::to_string(seed) + ", k " + std::to_string(k);
  const TempDir scratch("talus_discovery_phase_" + std::to_string(seed));
  const fs::path& base = scratch.path();
  // the data's piles from one of a million blocks above 9, never the model's 2-3
  const unsigned first_pile = 10 + static_cast<unsigned>(rng() % 1000000) * 2;
  std::string data;
  for (unsigned r = 0; r < 2; ++r) {
    const fs::path run = base / ("run" + std::to_string(r));
    const std::string cmd =
        kTalus + " synth --scenario hd27 --fidelity G400 --noise default --vary-inputs 0.1" +
        " --quiet --seed " + std::to_string(seed + r) + " --pile-seed " +
        std::to_string(first_pile + r) + " --effect-plugin " + kHidden +
        " --effect dig_loss:k=" + std::to_string(k) + " --out " + run.string() + " 2>/dev/null";
    ASSERT_EQ(exit_code(cmd), 0) << cmd;
    data += " " + run.string();
  }
  const fs::path json = base / "diagnosis.json";
  const std::string cmd = kTalus + " diagnose --quiet --data" + data +
                          " --fidelity G400 --pile-ensemble 2 --pile-seed 2" +
                          " --candidates hydraulic_lag --json " + json.string() + " > /dev/null";
  ASSERT_EQ(exit_code(cmd), 0) << cmd;
  const auto j = nlohmann::json::parse(std::ifstream(json));
  const auto& d = j["discovered"];
  ASSERT_FALSE(d.is_null()) << context << ": nothing discovered; found "
                            << j["effects_found"].dump();
  std::cerr << "phase draw: " << context << " -> " << d["expression"].get<std::string>() << "\n";
  EXPECT_EQ(d["target"], "lift speed") << context;
  bool phase = false;
  for (const auto& c : d["coefficients"]) {
    bool names = c["feature"] == "digging_times";
    for (const auto& a : c["aliases"]) names = names || a == "digging_times";
    if (!names) continue;
    phase = true;
    EXPECT_NEAR(c["coefficient"].get<double>(), -k, 0.1 * k) << context;
  }
  EXPECT_TRUE(phase) << context << ": " << d["expression"];
  EXPECT_GE(d["held_out_error_cut"].get<double>(), 0.5) << context;
}

TEST(DiscoveryTest, DiscoversNothingInEffectFreeData) {
  // --discover: the discovery runs even though the candidates leave nothing beyond noise
  const unsigned seed = test_seed();
  std::mt19937_64 rng(seed);
  const int draws = env_count("TALUS_DISCOVERY_FREE_DRAWS", 2);
  for (int draw = 0; draw < draws; ++draw) {
    const unsigned run_seed = static_cast<unsigned>(rng());
    const TempDir scratch("talus_discovery_free_" + std::to_string(run_seed));
    const fs::path& base = scratch.path();
    const auto j = synthesise_and_diagnose(base, "", run_seed, " --discover");
    EXPECT_TRUE(j["discovery"]["ran"].get<bool>());
    EXPECT_TRUE(j["discovered"].is_null())
        << "TALUS_TEST_SEED=" << seed << " draw " << draw << ": " << j["discovered"].dump();
    EXPECT_TRUE(j["effects_found"].empty()) << j["effects_found"].dump();
    std::cerr << "effect-free draw " << draw << " (seed " << run_seed << "): "
              << (j["discovered"].is_null() ? "nothing discovered"
                                            : j["discovered"]["expression"].dump())
              << "\n";
  }
}

TEST(DiscoveryTest, TheDiscoveredCorrectionRunsAsAnEffect) {
  // what diagnose reports as the effect reads back into `talus run --effect`, and changes the run
  const TempDir scratch("talus_discovery_run_" + std::to_string(::getpid()));
  const fs::path& base = scratch.path();
  const std::string spec = "learned_actuator_correction:actuator=lift,force_sign_command=-2e-7";
  ASSERT_EQ(exit_code(kTalus + " run --scenario load-carry --quiet --effect " + spec + " --out " +
                      (base / "with").string() + " > /dev/null 2>&1"),
            0);
  ASSERT_EQ(exit_code(kTalus + " run --scenario load-carry --quiet --out " +
                      (base / "without").string() + " > /dev/null 2>&1"),
            0);
  const auto with = nlohmann::json::parse(std::ifstream(base / "with" / "summary.json"));
  const auto without = nlohmann::json::parse(std::ifstream(base / "without" / "summary.json"));
  EXPECT_EQ(with["effects"][0]["name"], "learned_actuator_correction") << with["effects"].dump();
  EXPECT_NE(with["work_J"].get<double>(), without["work_J"].get<double>());
}

}  // namespace
