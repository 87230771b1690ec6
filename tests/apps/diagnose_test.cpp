// `talus diagnose` end to end on the load-carry scenario (the machine alone, 0.4 s a simulation):
// data made by `talus synth` with an effect the loop is not told about, then the loop given only
// the data folders. The answer key stays outside and only this test reads it.
#include <sys/wait.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "tests/host/temp_dir.hpp"

namespace {

namespace fs = std::filesystem;
using talus::test::TempDir;
const std::string kTalus = std::string(TALUS_BINARY_DIR) + "/talus";
const std::string kPlugin = std::string(TALUS_BINARY_DIR) + "/libtalus_example_effect.so";

int exit_code(const std::string& cmd) {
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// the seed of the random draws: TALUS_TEST_SEED when set (to repeat a failure), else fresh
unsigned test_seed() {
  if (const char* s = std::getenv("TALUS_TEST_SEED")) return static_cast<unsigned>(std::stoul(s));
  return std::random_device{}();
}

struct Draw {
  std::string effect;   // built-in name
  std::string channel;  // for sensor_bias and sensor_delay
  std::string spec;     // --effect NAME:key=value
};

// one built-in effect at a random magnitude that shows above the default sensor noise in
// load-carry (the lower ends were chosen so; docs/sim2real.md lists the rates measured over many
// draws). Channel-bound effects draw among the channels the paper's seven metrics read, for a
// delay among those read by a mean absolute error (a bias or delay on a channel the metrics do not
// read cannot cut their mean error, and the trajectory's DTW forgives a delay by design)
Draw draw_effect(std::mt19937_64& rng) {
  auto uniform = [&](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
  const std::vector<std::string> names = {"engine_power_sharing", "hydraulic_lag",   "pump_flow_limit",
                                          "cylinder_friction",    "wheel_slip_sensor", "tyre_rolling_resistance",
                                          "sensor_bias",          "sensor_delay"};
  // each channel with its largest bias and the fraction of it the smallest is. The bucket tip's
  // from 0.7 m: its bias shows in one of the seven metrics (E_x, 0.078 a metre) beside the others'
  // noise, and below about 0.55 m the mean cannot fall by 30 % even when the bias is removed
  // exactly (seed 260450722: -0.53 m on bucket_tip_x named, E_x cut from 0.042 to 0.003, the mean
  // from 0.0190 to 0.0135, 29 %)
  struct Channel {
    std::string name;
    double max_bias, min_fraction;
  };
  const std::vector<Channel> channels = {{"f_lift", 100e3, 0.3},     {"f_tilt", 100e3, 0.3},
                                         {"f_traction", 20e3, 0.3},  {"v_drive", 0.5, 0.3},
                                         {"bucket_tip_x", 1.0, 0.7}, {"bucket_tip_z", 1.0, 0.7},
                                         {"power", 20e3, 0.3}};
  Draw d;
  d.effect = names[std::uniform_int_distribution<size_t>(0, names.size() - 1)(rng)];
  const Channel& drawn =
      channels[std::uniform_int_distribution<size_t>(0, channels.size() - 1)(rng)];
  // f_lift, f_tilt, f_traction, v_drive: the first four
  const std::string delayed = channels[std::uniform_int_distribution<size_t>(0, 3)(rng)].name;
  auto num = [](double v) { return std::to_string(v); };
  if (d.effect == "engine_power_sharing") d.spec = d.effect + ":efficiency=" + num(uniform(0.5, 0.9));
  if (d.effect == "hydraulic_lag") d.spec = d.effect + ":time_constant=" + num(uniform(0.15, 1.0));
  if (d.effect == "pump_flow_limit") d.spec = d.effect + ":max_flow=" + num(uniform(2e-3, 4.5e-3));
  if (d.effect == "cylinder_friction") d.spec = d.effect + ":force=" + num(uniform(5e3, 30e3));
  if (d.effect == "wheel_slip_sensor") d.spec = d.effect + ":slip_at_limit=" + num(uniform(0.1, 0.5));
  if (d.effect == "tyre_rolling_resistance") d.spec = d.effect + ":coefficient=" + num(uniform(0.02, 0.15));
  if (d.effect == "sensor_bias") {
    d.channel = drawn.name;
    const double sign = uniform(0.0, 1.0) < 0.5 ? -1.0 : 1.0;
    d.spec = d.effect + ":channel=" + drawn.name +
             ",bias=" + num(sign * uniform(drawn.min_fraction, 1.0) * drawn.max_bias);
  }
  if (d.effect == "sensor_delay") {
    d.channel = delayed;
    // from 0.2 s: a 0.13 s delay of f_tilt is named but cuts the mean error by only 28 % (seed
    // 395389667), the noise's share of the error being as large as the delay's
    d.spec = d.effect + ":channel=" + delayed + ",delay=" + num(uniform(0.2, 0.5));
  }
  return d;
}

// two repetitions of load-carry by a varying operator, with default noise: one to calibrate on,
// one to validate on
void synthesise(const fs::path& base, const std::string& effect_args, unsigned seed) {
  for (int k = 0; k < 2; ++k) {
    const std::string cmd = kTalus + " synth --scenario load-carry --noise default --vary-inputs 0.1 --quiet --seed " +
                            std::to_string(seed + k) + effect_args + " --out " + (base / ("run" + std::to_string(k))).string() +
                            " 2>/dev/null";
    ASSERT_EQ(exit_code(cmd), 0) << cmd;
  }
}

nlohmann::json diagnose(const fs::path& base, const std::string& extra_args = "") {
  const fs::path json = base / "diagnosis.json";
  const std::string cmd = kTalus + " diagnose --quiet --data " + (base / "run0").string() + " " + (base / "run1").string() +
                          " --json " + json.string() + extra_args + " > " + (base / "report.md").string();
  EXPECT_EQ(exit_code(cmd), 0) << cmd;
  return nlohmann::json::parse(std::ifstream(json));
}

TEST(DiagnoseTest, NamesARandomBuiltInEffectAndCutsTheMeanErrorByAThird) {
  const unsigned seed = test_seed();
  std::mt19937_64 rng(seed);
  // TALUS_TEST_EFFECT=NAME draws until that effect comes up (its magnitude stays random): for
  // checking one effect over many seeds
  const char* only = std::getenv("TALUS_TEST_EFFECT");
  Draw d = draw_effect(rng);
  while (only && d.effect != only) d = draw_effect(rng);
  RecordProperty("seed", std::to_string(seed));
  const std::string context = "TALUS_TEST_SEED=" + std::to_string(seed) + ", effect " + d.spec;
  std::cerr << "diagnose test: " << context << "\n";
  const TempDir scratch("talus_diagnose_blind_" + std::to_string(seed));
  const fs::path& base = scratch.path();
  synthesise(base, " --effect " + d.spec, seed);
  const auto j = diagnose(base);

  // the effect named (with its channel), and the paper's mean error cut by at least 30 %
  ASSERT_GE(j["effects_found"].size(), 1u) << context;
  EXPECT_EQ(j["effects_found"][0]["name"], d.effect) << context;
  if (!d.channel.empty()) {
    EXPECT_EQ(j["effects_found"][0]["params"]["channel"], d.channel) << context;
  }
  const double before = j["error_before"]["mean"], after = j["error_after"]["mean"];
  EXPECT_LE(after, 0.7 * before) << context << ": mean error " << before << " -> " << after;
  // the machine alone is smooth in its parameters: the window of the effect found (a single of
  // one parameter; a pair is fitted jointly, without a window) holds one minimum, so BOBYQA
  // refines it rather than the window's parabola standing in for it (docs/sim2real.md section 3)
  for (const auto& f : j["rounds"][0]["fitted"]) {
    if (f["effect"] != j["effects_found"][0] || f["parameters"] != 1) continue;
    EXPECT_EQ(f["window_local_minima"], 1) << context;
    EXPECT_FALSE(f["trend_estimate"].get<bool>()) << context;
  }
}

TEST(DiagnoseTest, AddsNothingToEffectFreeDataWithNoise) {
  const unsigned seed = test_seed();
  const TempDir scratch("talus_diagnose_noise_" + std::to_string(seed));
  const fs::path& base = scratch.path();
  synthesise(base, "", seed);
  const auto j = diagnose(base, " --out " + (base / "out").string());
  EXPECT_TRUE(j["effects_found"].empty()) << "TALUS_TEST_SEED=" << seed << ": " << j["effects_found"].dump();
  EXPECT_FALSE(j["unexplained"].get<bool>()) << "TALUS_TEST_SEED=" << seed;
  EXPECT_EQ(j["error_before"]["mean"], j["error_after"]["mean"]);
  // --out: the report, the JSON, the tables and a channel figure per run
  for (const char* file : {"report.md", "diagnosis.json", "errors-before.csv", "errors-after.csv",
                           "0-load-carry-field-channels.png", "1-load-carry-field-channels.png"})
    EXPECT_GT(fs::file_size(base / "out" / file), 100u) << file;
  // --candidates: an unknown label (or none) is bad input, refused before the folder is touched:
  // exit 2, the finished diagnosis kept
  const std::string data = " --data " + (base / "run0").string() + " " + (base / "run1").string();
  for (const char* bad : {"hydraulic_lag,sensor_bias", ","}) {
    const std::string cmd = kTalus + " diagnose --quiet" + data + " --candidates '" + bad +
                            "' --out " + (base / "out").string() + " > /dev/null 2> " +
                            (base / "err.txt").string();
    EXPECT_EQ(exit_code(cmd), 2) << cmd;
    EXPECT_TRUE(fs::exists(base / "out" / "diagnosis.json")) << bad;
    std::ifstream err(base / "err.txt");
    const std::string text((std::istreambuf_iterator<char>(err)), std::istreambuf_iterator<char>());
    EXPECT_NE(text.find("--candidates"), std::string::npos) << text;
  }
  // a named few are what the JSON says was searched
  const auto some = diagnose(base, " --candidates 'hydraulic_lag,sensor_bias[f_lift]'");
  EXPECT_EQ(some["candidates"], nlohmann::json({"hydraulic_lag", "sensor_bias[f_lift]"}));
  EXPECT_TRUE(some["effects_found"].empty());
}

TEST(DiagnoseTest, AnEffectOutsideTheCandidatesIsUnexplainedOrAClearlyWorseFit) {
  // the example plug-in's flow_relief (not a candidate: the loop is not given the plug-in), strong
  // enough that the boom slows visibly under the loaded bucket
  const unsigned seed = test_seed();
  std::mt19937_64 rng(seed);
  const double speed = std::uniform_real_distribution<double>(0.06, 0.1)(rng);
  const double droop = std::uniform_real_distribution<double>(4.0, 8.0)(rng);
  const std::string spec = "flow_relief:speed=" + std::to_string(speed) + ",droop=" + std::to_string(droop);
  const std::string context = "TALUS_TEST_SEED=" + std::to_string(seed) + ", effect " + spec;
  const TempDir scratch("talus_diagnose_plugin_" + std::to_string(seed));
  const fs::path& base = scratch.path();
  synthesise(base, " --effect-plugin " + kPlugin + " --effect " + spec, seed);
  const auto j = diagnose(base);
  // the effect shows (else the test would test nothing)
  ASSERT_GE(j["excess_before"].get<double>(), 0.5) << context;
  // never a confident wrong answer: a candidate it adds fits clearly worse than a candidate that is
  // the cause (which cuts the mean error by 30 % or more), or it says unexplained. The discovery
  // (issue 17) may find a term instead: a correction of the cylinders the relief valve slows,
  // which then explains half of the held-out excess or more
  const double before = j["error_before"]["mean"], after = j["error_after"]["mean"];
  bool candidate = false;
  for (const auto& f : j["effects_found"])
    candidate = candidate || f["name"].get<std::string>().rfind("learned_", 0) != 0;
  if (candidate || j["discovered"].is_null()) {
    EXPECT_TRUE(j["unexplained"].get<bool>() || after > 0.7 * before)
        << context << ": found " << j["effects_found"].dump() << ", mean error " << before << " -> "
        << after;
  }
  if (!j["discovered"].is_null()) {
    const std::string target = j["discovered"]["target"];
    EXPECT_TRUE(target == "lift speed" || target == "tilt speed")
        << context << ": " << j["discovered"].dump();
    EXPECT_GE(j["discovered"]["held_out_error_cut"].get<double>(), 0.5) << context;
  }
}

TEST(DiagnoseTest, TwoEffectsOfSimilarSizeAreFoundTogether) {
  // the case: cylinder friction of about 12 kN with a traction-sensor bias of about +6 kN,
  // where the best single candidate removes just under half of the held-out excess; the pair
  // search must add both
  const unsigned seed = test_seed();
  std::mt19937_64 rng(seed);
  const double force = std::uniform_real_distribution<double>(10e3, 14e3)(rng);
  const double bias = std::uniform_real_distribution<double>(5e3, 7e3)(rng);
  const std::string context = "TALUS_TEST_SEED=" + std::to_string(seed) + ", friction " +
                              std::to_string(force) + " N, bias " + std::to_string(bias) + " N";
  const TempDir scratch("talus_diagnose_pair_" + std::to_string(seed));
  const fs::path& base = scratch.path();
  synthesise(base,
             " --effect cylinder_friction:force=" + std::to_string(force) +
                 " --effect sensor_bias:channel=f_traction,bias=" + std::to_string(bias),
             seed);
  const auto j = diagnose(base);
  std::set<std::string> names;
  for (const auto& f : j["effects_found"]) names.insert(f["name"].get<std::string>());
  EXPECT_TRUE(names.count("cylinder_friction")) << context << ": " << j["effects_found"].dump();
  EXPECT_TRUE(names.count("sensor_bias")) << context << ": " << j["effects_found"].dump();
  const double before = j["error_before"]["mean"], after = j["error_after"]["mean"];
  EXPECT_LE(after, 0.7 * before) << context;
}

TEST(DiagnoseTest, FiveEffectsOfComparableSizeAreFoundThreeTogether) {
  // five sensor biases of comparable size (three to seven times each channel's noise; random
  // signs): no single one removes half of the held-out excess, and no pair (over the 15 draws
  // measured when this was built, docs/sim2real.md step 5: the best single 21-23 %, the best pair
  // 37-48 %, the best set of three 57-62 %), so the round must take a pair provisionally, search a
  // third candidate on top and add the three together. Only the sensor biases are candidates:
  // this tests the joint search and its members' screen, not the choice among other effects
  const unsigned seed = test_seed();
  std::mt19937_64 rng(seed);
  auto biased = [&](double lo, double hi) {
    const double sign = std::uniform_real_distribution<double>(0.0, 1.0)(rng) < 0.5 ? -1.0 : 1.0;
    return sign * std::uniform_real_distribution<double>(lo, hi)(rng);
  };
  const std::vector<std::pair<std::string, double>> biases = {{"f_lift", biased(18e3, 22e3)},
                                                              {"f_tilt", biased(16e3, 20e3)},
                                                              {"f_traction", biased(5.5e3, 6.5e3)},
                                                              {"v_drive", biased(0.072, 0.088)},
                                                              {"power", biased(5e3, 6e3)}};
  std::string effects, context = "TALUS_TEST_SEED=" + std::to_string(seed) + ", biases";
  for (const auto& [channel, bias] : biases) {
    effects += " --effect sensor_bias:channel=" + channel + ",bias=" + std::to_string(bias);
    context += " " + channel + " " + std::to_string(bias);
  }
  const TempDir scratch("talus_diagnose_set_" + std::to_string(seed));
  const fs::path& base = scratch.path();
  synthesise(base, effects, seed);
  // up to three rounds: the set of three in round 1, the two biases it leaves after it, and all
  // of them refitted together
  const auto j = diagnose(base,
                          " --max-effects 3 --candidates 'sensor_bias[f_lift],sensor_bias[f_tilt],"
                          "sensor_bias[f_traction],sensor_bias[v_drive],sensor_bias[power]'");
  const auto& round = j["rounds"][0];
  // the case needs a set of three: no pair clears the bar. A draw whose best pair does (none of
  // the 15 measured; the pair's share about 2.4 of its standard deviations below the bar) needs no
  // set: then the pair is what the round must add, and no set of three is searched
  ASSERT_FALSE(round["pairs"].empty()) << context << ": " << round.dump();
  const bool pair_enough = round["pairs"][0]["explained"].get<double>() >= 0.5;
  // round 1: three biases added together (two where a pair was enough), each on a channel that
  // carries one, each channel once
  ASSERT_TRUE(round["added"].get<bool>()) << context << ": " << round["triples"].dump();
  if (pair_enough) {
    EXPECT_TRUE(round["triples"].empty()) << context;
  } else {
    ASSERT_FALSE(round["triples"].empty()) << context;
    EXPECT_GE(round["triples"][0]["explained"].get<double>(), 0.5) << context;
  }
  const std::size_t members = pair_enough ? 2 : 3;
  std::set<std::string> first_round;
  for (std::size_t k = 0; k < members && k < j["effects_found"].size(); ++k) {
    const auto& f = j["effects_found"][k];
    ASSERT_EQ(f["name"], "sensor_bias") << context << ": " << f.dump();
    first_round.insert(f["params"]["channel"].get<std::string>());
  }
  EXPECT_EQ(first_round.size(), members) << context << ": " << j["effects_found"].dump();
  // in the end all five, each channel once, refitted together and each within 5 % of its bias
  // (a set's fit is pulled by the biases it lacks: power follows the force and speed readings,
  // so a set without f_lift fitted f_traction 11 % low, seed 3709446671, and the refit of all
  // five brought it within 1 %; docs/sim2real.md step 5). A learned correction the discovery
  // might add is not a bias and not counted: all five must be found as sensor biases
  std::set<std::string> channels;
  double worst = 0.0;  // the largest relative error of a bias found, printed for the docs' tally
  for (const auto& f : j["effects_found"]) {
    if (f["name"].get<std::string>().rfind("learned_", 0) == 0) continue;
    ASSERT_EQ(f["name"], "sensor_bias") << context;
    const std::string channel = f["params"]["channel"];
    const auto truth = std::find_if(biases.begin(), biases.end(),
                                    [&](const auto& b) { return b.first == channel; });
    ASSERT_NE(truth, biases.end()) << context << ": " << f.dump();
    EXPECT_TRUE(channels.insert(channel).second) << context << ": " << channel << " twice";
    const double error = std::abs(f["params"]["bias"].get<double>() / truth->second - 1.0);
    worst = std::max(worst, error);
    EXPECT_LE(error, 0.05) << context << ": " << f.dump();
  }
  std::cerr << "five biases: " << context << ": " << members << " in round 1, "
            << j["rounds"].size() << " rounds, the worst bias " << 100.0 * worst << " % off\n";
  EXPECT_EQ(channels.size(), biases.size()) << context << ": " << j["effects_found"].dump();
}

TEST(DiagnoseTest, EffectsFoundInTwoRoundsAreRefittedTogether) {
  // cylinder friction of about 20 kN with an f_lift sensor bias of about 25 kN: the friction is
  // found first and fitted with the bias missing, so it takes up part of the bias (25 kN, the top
  // of its scan, for 20 kN: seed 5 of the session that built this), and the bias found in round 2
  // on top of it comes out low (21.9 kN). Refitted together they must both come back within 5 %.
  // Where the friction alone explains just under half (18.8 and 24.5 kN, seed 2263243748: 49 %)
  // the pair search adds both in round 1, fitted jointly already: no refit, the same 5 %
  const unsigned seed = test_seed();
  std::mt19937_64 rng(seed);
  const double force = std::uniform_real_distribution<double>(18e3, 22e3)(rng);
  const double bias = std::uniform_real_distribution<double>(23e3, 27e3)(rng);
  const std::string context = "TALUS_TEST_SEED=" + std::to_string(seed) + ", friction " +
                              std::to_string(force) + " N, f_lift bias " + std::to_string(bias) +
                              " N";
  const TempDir scratch("talus_diagnose_refit_" + std::to_string(seed));
  const fs::path& base = scratch.path();
  synthesise(base,
             " --effect cylinder_friction:force=" + std::to_string(force) +
                 " --effect sensor_bias:channel=f_lift,bias=" + std::to_string(bias),
             seed);
  const auto j = diagnose(base, " --max-effects 2");
  // found in two rounds: the refit ran after the second, and was kept
  int rounds_adding = 0;
  const nlohmann::json* refit = nullptr;
  for (const auto& r : j["rounds"]) {
    rounds_adding += r["added"].get<bool>() ? 1 : 0;
    if (!r["refit"].is_null()) refit = &r["refit"];
  }
  if (rounds_adding >= 2) {
    ASSERT_NE(refit, nullptr) << context << ": " << j["rounds"].dump();
    EXPECT_TRUE((*refit)["kept"].get<bool>()) << context << ": " << refit->dump();
    EXPECT_LT((*refit)["log_ratio_after"].get<double>(), (*refit)["log_ratio_before"].get<double>())
        << context;
  } else {
    EXPECT_EQ(refit, nullptr) << context << ": a refit after a round that added a pair alone";
  }
  // the effects found carry the refitted values, each within 5 % of the truth
  double found_force = 0.0, found_bias = 0.0;
  for (const auto& f : j["effects_found"]) {
    if (f["name"] == "cylinder_friction") found_force = f["params"]["force"].get<double>();
    if (f["name"] == "sensor_bias" && f["params"]["channel"] == "f_lift")
      found_bias = f["params"]["bias"].get<double>();
  }
  EXPECT_NEAR(found_force, force, 0.05 * force) << context << ": " << j["effects_found"].dump();
  EXPECT_NEAR(found_bias, bias, 0.05 * bias) << context << ": " << j["effects_found"].dump();
}

// the judgement of the sensitivity spread after round `round` (nullptr when there was none)
const nlohmann::json* judgement_after(const nlohmann::json& j, int round) {
  for (const auto& s : j["sensitivity"])
    if (s["after"] == "round " + std::to_string(round)) return &s;
  return nullptr;
}

// a candidate whose simulation is chaotic in its parameter (tests/apps/hidden_effects.c,
// chaotic_bias: a traction offset of 60-90 kN, beyond sensor_bias's ±20 kN, whose 2.5 kN
// realisation changes with any change of the offset), given to the loop: its fit can never
// reproduce the data's realisation, so what it leaves (two realisations' difference, variance
// 3.1 σ² of f_traction) is beyond the sensor noise, and within the spread the simulation shows at
// the fitted offset ± its uncertainty. The loop must add it and call what is left explained
constexpr int kChaoticRound = 1;
std::string chaotic_draw(std::mt19937_64& rng) {
  return "chaotic_bias:bias=" +
         std::to_string(std::uniform_real_distribution<double>(60e3, 90e3)(rng));
}

TEST(DiagnoseTest, WhatTheSimulationsSensitivityToAFittedParameterLeavesIsNotUnexplained) {
  const unsigned seed = test_seed();
  std::mt19937_64 rng(seed);
  const std::string spec = chaotic_draw(rng);
  const std::string context = "TALUS_TEST_SEED=" + std::to_string(seed) + ", effect " + spec;
  const TempDir scratch("talus_diagnose_chaotic_" + std::to_string(seed));
  const fs::path& base = scratch.path();
  const std::string plugin = std::string(" --effect-plugin ") + TALUS_SENSITIVE_EFFECT;
  synthesise(base, plugin + " --effect " + spec, seed);
  const auto j = diagnose(base, " --max-effects 1" + plugin);
  ASSERT_GE(j["effects_found"].size(), 1u) << context << ": " << j["rounds"].dump();
  EXPECT_EQ(j["effects_found"][0]["name"], "chaotic_bias") << context;
  const nlohmann::json* judged = judgement_after(j, kChaoticRound);
  ASSERT_NE(judged, nullptr) << context << ": " << j["sensitivity"].dump();
  // the case shows: some run is beyond noise without the sensitivity spread (else this tests
  // nothing), and every run is within it with it
  double worst_without = 0.0, worst_with = 0.0;
  for (const auto& r : (*judged)["runs"]) {
    worst_without = std::max(worst_without, r["excess_without"].get<double>());
    worst_with = std::max(worst_with, r["excess_with"].get<double>());
  }
  ASSERT_GE(worst_without, 0.5) << context << ": " << judged->dump();
  EXPECT_TRUE((*judged)["used"].get<bool>()) << context << ": " << judged->dump();
  EXPECT_LT(worst_with, 0.5) << context << ": " << judged->dump();
  EXPECT_FALSE(j["unexplained"].get<bool>()) << context;
  EXPECT_FALSE(j["discovery"]["ran"].get<bool>()) << context;  // nothing left to discover
  // its cost: 2 simulations for the curvature of one parameter on the calibration run, and 2 (the
  // design's points) per run judged
  EXPECT_EQ((*judged)["curvature_simulations"].get<int>(), 2) << context;
  EXPECT_EQ((*judged)["design_points"].get<int>(), 2) << context;
}

TEST(DiagnoseTest, AMissingEffectBesideTheSimulationsSensitivityIsStillUnexplained) {
  // the same chaotic candidate, and on top an effect that is no candidate (the hidden plug-in's
  // valve dead band on the lift, 2.5-3.5 mm/s, tests/apps/hidden_effects.c; a baseline excess of
  // 2-6 per run, less than the offset's 11-19, so the offset is added first; at 4.5 mm/s a
  // held-out run's 9 left the offset 49 %, seed 102): after the
  // chaotic bias is added, what is left must stay beyond the sensitivity spread, so the loop
  // goes on to the discovery (and says unexplained unless a correction explains it)
  const unsigned seed = test_seed();
  std::mt19937_64 rng(seed);
  const std::string spec = chaotic_draw(rng);
  const std::string missing =
      "dead_band:k=" + std::to_string(std::uniform_real_distribution<double>(0.0025, 0.0035)(rng)) +
      ",cylinder=0";
  const std::string context =
      "TALUS_TEST_SEED=" + std::to_string(seed) + ", effects " + spec + " and " + missing;
  const TempDir scratch("talus_diagnose_chaotic_missing_" + std::to_string(seed));
  const fs::path& base = scratch.path();
  const std::string plugin = std::string(" --effect-plugin ") + TALUS_SENSITIVE_EFFECT;
  synthesise(base,
             plugin + " --effect " + spec + " --effect-plugin " + TALUS_HIDDEN_EFFECTS +
                 " --effect " + missing,
             seed);
  const auto j = diagnose(base, " --max-effects 1" + plugin);
  std::set<std::string> names;
  for (const auto& f : j["effects_found"]) names.insert(f["name"].get<std::string>());
  ASSERT_TRUE(names.count("chaotic_bias")) << context << ": " << j["rounds"].dump();
  const nlohmann::json* judged = judgement_after(j, kChaoticRound);
  ASSERT_NE(judged, nullptr) << context << ": " << j["sensitivity"].dump();
  EXPECT_TRUE((*judged)["used"].get<bool>()) << context << ": " << judged->dump();
  double worst_with = 0.0;
  for (const auto& r : (*judged)["runs"])
    worst_with = std::max(worst_with, r["excess_with"].get<double>());
  EXPECT_GE(worst_with, 0.5) << context << ": " << judged->dump();
  EXPECT_TRUE(j["discovery"]["ran"].get<bool>()) << context;
  EXPECT_TRUE(j["unexplained"].get<bool>() || !j["discovered"].is_null()) << context;
}

// the chaos check (docs/sim2real.md section 4, item 5) end to end: the calibration run is dug on
// the very pile the model digs (HD27-G400, pile 1, one pile), with moist soil of 1-5 kPa; the
// held-out run is load-carry, which has no soil, so the share is counted on the calibration run.
// There the fitted cohesion usually explains the run: the same grains at the start, so the
// cohesion's mean effect on the forces stands out. But on the next pile (2) the grains'
// arrangement moves the dig far more than the cohesion does: the addition is refused and nothing
// is added. Measured with 700, 1500, 5000 and 15000 Pa: the reference piles' share -3 to +12 %.
// The dig is chaotic in the cohesion too, even on one pile (2945.57 Pa against 2950 Pa moves
// f_lift by 0.8 kN rms, against 2900 Pa by 6.8 kN; the bucket's content a weight, the default
// before 9e456b7): in 1 of 57 draws measured then (seed 523734056, 2945.57 Pa; docs/sim2real.md)
// no scanned value came near enough and the fit explained 28 %. Such a fit is not an addition
// (below half), so there is no check to run: that draw asserts nothing was added and the test
// draws again, at most kChaosDraws times, until one reaches the check it is about. With the
// content a body (the default since 9e456b7) 1 of 20 draws (seed 101) dug data within noise of
// the model without cohesion: no round at all, and the test draws again too. Since the zone's
// floor is its failure plane (f10394b) the dig is more chaotic in the cohesion: over seeds 1-12
// and 663386212 (the CI failure of 57a236f) 11 of 23 draws reached the check (every check
// refused the fit); the others' fits explained 14-44 %, or no scanned value beat the model
// without cohesion at all (best 2.90 against 2.70). Ten draws leave 0.52^10 = 0.15 % of seeds
// without a check
TEST(DiagnoseTest, AFitOfThePileTheDataWereDugOnIsRefusedByTheChaosCheck) {
  constexpr int kChaosDraws = 10;
  const unsigned seed = test_seed();
  std::mt19937_64 rng(seed);
  bool checked = false;
  for (int draw = 0; draw < kChaosDraws && !checked; ++draw) {
    const double cohesion = std::uniform_real_distribution<double>(1e3, 5e3)(rng);
    const std::string context = "TALUS_TEST_SEED=" + std::to_string(seed) + ", draw " +
                                std::to_string(draw) + ", cohesion " + std::to_string(cohesion) +
                                " Pa";
    const TempDir scratch("talus_diagnose_chaos_" + std::to_string(seed) + "_" +
                          std::to_string(draw));
    const fs::path& base = scratch.path();
    const std::string synth = kTalus + " synth --noise default --quiet --seed ";
    const unsigned data_seed = seed + 2 * static_cast<unsigned>(draw);
    const std::string dig = synth + std::to_string(data_seed) +
                            " --scenario hd27 --fidelity G400 --pile-seed 1 --effect "
                            "soil_cohesion:cohesion=" +
                            std::to_string(cohesion) + " --out " + (base / "run0").string();
    const std::string carry = synth + std::to_string(data_seed + 1) +
                              " --scenario load-carry --out " + (base / "run1").string();
    for (const std::string& cmd : {dig, carry})
      ASSERT_EQ(exit_code(cmd + " 2>/dev/null"), 0) << cmd;
    const auto j = diagnose(base,
                            " --fidelity G400 --pile-seed 1 --pile-ensemble 1 --validation 1 "
                            "--max-effects 1 --candidates soil_cohesion");
    // whatever the fit explains, a fit of the model's own pile is never added
    EXPECT_TRUE(j["effects_found"].empty()) << context << ": " << j["effects_found"].dump();
    // data within noise of the model without the cohesion leave nothing to search: draw again
    if (j.at("rounds").empty()) {
      EXPECT_EQ(j.at("excess_before").get<double>(), 0.0) << context;
      std::cout << context << ": the data are within noise of the model, no round; drawing again\n";
      continue;
    }
    const auto& round = j["rounds"][0];
    // a chaotic response can leave every point of the scan worse than the model without the
    // cohesion (seed 663386212: best 2.90 against 2.70 without): no fit, so nothing to check
    if (round["fitted"].empty()) {
      EXPECT_TRUE(round["chaos_checks"].empty()) << context << ": " << round.dump();
      std::cout << context
                << ": no scanned cohesion beat the model without it, no fit; drawing again\n";
      continue;
    }
    EXPECT_EQ(round["fitted"][0]["explained_on"], "calibration") << context;
    // a fit below half is no addition, so nothing to check: draw again
    if (round["fitted"][0]["explained"].get<double>() < 0.5) {
      EXPECT_TRUE(round["chaos_checks"].empty()) << context << ": " << round.dump();
      std::cout << context << ": the fit explained "
                << round["fitted"][0]["explained"].get<double>() << ", no check; drawing again\n";
      continue;
    }
    // the check digs the calibration run on the reference pile without and with it: refused
    ASSERT_FALSE(round["chaos_checks"].empty()) << context << ": " << round.dump();
    const auto& check = round["chaos_checks"][0];
    EXPECT_FALSE(check["passed"].get<bool>()) << context << ": " << check.dump();
    EXPECT_LT(check["explained"].get<double>(), 0.5) << context;
    EXPECT_EQ(check["simulations"], 2) << context;
    checked = true;
  }
  EXPECT_TRUE(checked) << "TALUS_TEST_SEED=" << seed << ": no draw of " << kChaosDraws
                       << " gave a fit that explains half of its own pile's dig";
}

// issue 17's parameter recovery on pile data, blind and CI-sized: cylinder friction drawn in
// 8-16 kN, kDigs HD27-G400 digs on fresh piles by an operator who varies the inputs 10 %, with
// default sensor noise; the last one held out; friction and hydraulic lag (the distractor the
// eight-pile study met most) the candidates, eight model piles. The friction must be named alone
// (a pair may be added in one round), fitted within kRecovery of the truth, and the paper's mean
// error must fall. The bar is 1.5 times the worst of forty draws of this design (19.4 %; 35 of
// them within the 10 %: docs/sim2real.md section 5, "A blind pile test in CI")
TEST(DiagnoseTest, CylinderFrictionIsRecoveredFromFourDigsOnFreshPiles) {
  constexpr double kRecovery = 0.30;
  constexpr unsigned kDigs = 4;
  const unsigned seed = test_seed();
  RecordProperty("seed", std::to_string(seed));
  std::mt19937_64 rng(seed);
  const double force = std::uniform_real_distribution<double>(8e3, 16e3)(rng);
  const std::string context =
      "TALUS_TEST_SEED=" + std::to_string(seed) + ", friction " + std::to_string(force) + " N";
  std::cerr << "diagnose pile test: " << context << "\n";
  const TempDir scratch("talus_diagnose_pile_" + std::to_string(seed));
  const fs::path& base = scratch.path();
  // the data's piles: kDigs consecutive seeds from one of a million blocks above 9, so never the
  // model's 2-9 (a type-G pile is its voxels and this seed's grains: nothing is cached)
  const unsigned first_pile = 10 + static_cast<unsigned>(rng() % 1000000) * kDigs;
  std::string data;
  for (unsigned k = 0; k < kDigs; ++k) {
    const fs::path run = base / ("run" + std::to_string(k));
    const std::string cmd =
        kTalus +
        " synth --scenario hd27 --fidelity G400 --noise default --vary-inputs 0.1 --quiet" +
        " --seed " + std::to_string(seed + k) + " --pile-seed " + std::to_string(first_pile + k) +
        " --effect cylinder_friction:force=" + std::to_string(force) + " --out " + run.string() +
        " 2>/dev/null";
    ASSERT_EQ(exit_code(cmd), 0) << cmd;
    data += " " + run.string();
  }
  const fs::path json = base / "diagnosis.json";
  const std::string cmd = kTalus + " diagnose --quiet --data" + data +
                          " --fidelity G400 --pile-ensemble 8 --pile-seed 2 --max-effects 1" +
                          " --candidates 'hydraulic_lag,cylinder_friction' --json " +
                          json.string() + " > /dev/null";
  ASSERT_EQ(exit_code(cmd), 0) << cmd;
  const auto j = nlohmann::json::parse(std::ifstream(json));
  ASSERT_EQ(j["effects_found"].size(), 1u) << context << ": " << j["effects_found"].dump();
  EXPECT_EQ(j["effects_found"][0]["name"], "cylinder_friction") << context;
  const double fitted = j["effects_found"][0]["params"].value("force", 0.0);
  EXPECT_LE(std::abs(fitted - force), kRecovery * force)
      << context << ": fitted " << fitted << " N (" << 100.0 * (fitted - force) / force << " %)";
  const double before = j["error_before"]["mean"], after = j["error_after"]["mean"];
  EXPECT_LT(after, before) << context << ": mean error " << before << " -> " << after;
}

TEST(DiagnoseTest, AValueBelowTheScansFirstCentreIsFitted) {
  // the case: a plug-in effect whose true value (here k of drive_drag, in [0, 0.2] s/m)
  // lies so near zero that the scan's first centre, 0.011, fits worse than no effect at all
  // (below 0.0055, 0.011 is farther from k than zero is); only the points the scan adds towards
  // zero (0.0028, 0.0007, 0.0002) come near it. Measured first (docs/sim2real.md section 3, 20
  // draws in [0.002, 0.005]): every one named, the median error 0.4 %, the worst 10.7 % (k =
  // 0.0025, where the noise weighs most); drawn here from 0.0025, where the draws were measured
  // densely, and the bar is twice the worst
  constexpr double kNearZeroRecovery = 0.2;
  const unsigned seed = test_seed();
  std::mt19937_64 rng(seed);
  const double k = std::uniform_real_distribution<double>(0.0025, 0.005)(rng);
  const std::string context =
      "TALUS_TEST_SEED=" + std::to_string(seed) + ", k " + std::to_string(k);
  const TempDir scratch("talus_diagnose_near_zero_" + std::to_string(seed));
  const fs::path& base = scratch.path();
  const std::string plugin = std::string(" --effect-plugin ") + TALUS_FIT_EFFECTS;
  synthesise(base, plugin + " --effect drive_drag:k=" + std::to_string(k), seed);
  const auto j = diagnose(base, plugin + " --candidates drive_drag");
  ASSERT_GE(j["effects_found"].size(), 1u) << context;
  ASSERT_EQ(j["effects_found"][0]["name"], "drive_drag") << context;
  EXPECT_NEAR(j["effects_found"][0]["params"]["k"].get<double>(), k, kNearZeroRecovery * k)
      << context << ": fitted " << j["effects_found"][0].dump();
}

TEST(DiagnoseTest, FitsOfTwoAndThreeParametersRunToConvergence) {
  // two plug-in candidates of two and three parameters (the lift's, tilt's and drive's command
  // losses, each acting on its own command, so the data decide each one), drawn in [0.05, 0.3]:
  // every parameter must come back within kConvergedRecovery. BOBYQA alone stopped at its first
  // short step, far from the optimum; restarted until a restart gains nothing, and each parameter
  // then probed alone across steps of the objective (sim2real/diagnose minimise), every
  // parameter of 28 draws came back within 1.41 % and 27 seeds of this test passed
  // (docs/sim2real.md section 3 has the draws)
  constexpr double kConvergedRecovery = 0.05;
  const unsigned seed = test_seed();
  std::mt19937_64 rng(seed);
  auto loss = [&] { return std::uniform_real_distribution<double>(0.05, 0.3)(rng); };
  const std::string plugin = std::string(" --effect-plugin ") + TALUS_FIT_EFFECTS;
  struct Case {
    std::string effect;
    std::vector<std::string> parameters;
  };
  const std::vector<Case> cases = {{"cylinder_losses", {"lift", "tilt"}},
                                   {"command_losses", {"lift", "tilt", "drive"}}};
  for (const Case& c : cases) {
    std::vector<double> truth;
    std::string spec = c.effect + ":";
    for (const std::string& p : c.parameters) {
      truth.push_back(loss());
      spec += (truth.size() > 1 ? "," : "") + p + "=" + std::to_string(truth.back());
    }
    const std::string context = "TALUS_TEST_SEED=" + std::to_string(seed) + ", " + spec;
    const TempDir scratch("talus_diagnose_" + c.effect + "_" + std::to_string(seed));
    const fs::path& base = scratch.path();
    synthesise(base, plugin + " --effect " + spec, seed);
    const auto j = diagnose(base, plugin + " --max-effects 1 --candidates " + c.effect);
    ASSERT_GE(j["effects_found"].size(), 1u) << context;
    ASSERT_EQ(j["effects_found"][0]["name"], c.effect) << context;
    for (std::size_t i = 0; i < truth.size(); ++i)
      EXPECT_NEAR(j["effects_found"][0]["params"][c.parameters[i]].get<double>(), truth[i],
                  kConvergedRecovery * truth[i])
          << context << ": " << c.parameters[i] << " fitted " << j["effects_found"][0].dump();
  }
}

TEST(DiagnoseTest, TheThreadCountDoesNotChangeTheDiagnosis) {
  // a plug-in effect that makes a command NaN in half its range joins the candidates; the loop
  // reports it and still names the built-in effect in the data. Diagnosed on two threads and on
  // three (more than this machine's cores, so tasks finish out of order and split differently):
  // the same diagnosis, bit for bit, failures and their order included (one round keeps it short;
  // one thread against many is Parallel.*'s, in tests/host/parallel_test.cpp, at a fraction of the
  // cost: a serial diagnosis alone took 65 s of CI's time)
  const unsigned seed = test_seed();
  std::mt19937_64 rng(seed);
  const double force = std::uniform_real_distribution<double>(15e3, 25e3)(rng);
  const std::string context = "TALUS_TEST_SEED=" + std::to_string(seed);
  const TempDir scratch("talus_diagnose_broken_" + std::to_string(seed));
  const fs::path& base = scratch.path();
  synthesise(base, " --effect cylinder_friction:force=" + std::to_string(force), seed);
  const std::string args =
      std::string(" --max-effects 1 --effect-plugin ") + TALUS_BROKEN_EFFECT + " --threads ";
  auto j = diagnose(base, args + "2");
  auto k = diagnose(base, args + "3");
  ASSERT_GE(j["effects_found"].size(), 1u) << context;
  EXPECT_EQ(j["effects_found"][0]["name"], "cylinder_friction") << context;
  bool reported = false;
  for (const auto& f : j["rounds"][0]["failed"]) reported = reported || f["candidate"] == "broken";
  EXPECT_TRUE(reported) << context << ": " << j["rounds"][0].dump();
  // the wall time is the one field that may differ
  ASSERT_TRUE(j.contains("wall_s") && k.contains("wall_s"));
  j.erase("wall_s");
  k.erase("wall_s");
  EXPECT_EQ(j.dump(), k.dump()) << context;
}

}  // namespace
