// The loop's parts that need no simulation campaign: the candidate set and its signatures, the
// mean row of an error table, and the JSON contract. The loop itself runs end to end in
// tests/apps/diagnose_test.cpp (blind identification, no false positive, an effect outside the set).
#include "sim2real/diagnose.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "host/error.hpp"
#include "tests/sim2real/synthetic_runs.hpp"

namespace talus::sim2real {
namespace {

TEST(Diagnose, CandidatesExpandChannelOptionsAndCarrySignatures) {
  const auto candidates = candidate_set({});
  auto find = [&](const std::string& label) {
    return std::find_if(candidates.begin(), candidates.end(), [&](const Candidate& c) { return c.label() == label; });
  };
  // five machine effects, wheel slip, a bias and a delay per channel (13 each), soil cohesion
  EXPECT_EQ(candidates.size(), 5u + 1u + 26u + 1u);
  ASSERT_NE(find("engine_power_sharing"), candidates.end());
  EXPECT_TRUE(find("engine_power_sharing")->signature.empty());  // acts on the machine: all channels
  ASSERT_NE(find("sensor_bias[f_lift]"), candidates.end());
  const auto& bias = find("sensor_bias[f_lift]")->signature;
  ASSERT_EQ(bias.size(), 2u);
  EXPECT_EQ(bias[0], static_cast<size_t>(Channel::f_lift));  // the channel it acts on first
  EXPECT_EQ(bias[1], static_cast<size_t>(Channel::power));
  EXPECT_EQ(find("sensor_delay[power]")->signature.size(), 1u);
  EXPECT_EQ(find("wheel_slip_sensor")->signature.front(), static_cast<size_t>(Channel::v_drive));
  ASSERT_NE(find("soil_cohesion"), candidates.end());
  EXPECT_TRUE(find("soil_cohesion")->needs_particles);  // screened out of runs without a pile
  EXPECT_FALSE(find("hydraulic_lag")->needs_particles);
}

TEST(Diagnose, ChosenCandidatesKeepTheSetsOrderAndRefuseUnknownLabels) {
  const auto all = candidate_set({});
  EXPECT_EQ(chosen_candidates(all, {}).size(), all.size());  // none named: every candidate
  // named out of order: kept in the set's order, channel-bound ones by their full label
  const auto chosen =
      chosen_candidates(all, {"soil_cohesion", "sensor_bias[f_lift]", "engine_power_sharing"});
  ASSERT_EQ(chosen.size(), 3u);
  EXPECT_EQ(chosen[0].label(), "engine_power_sharing");
  EXPECT_EQ(chosen[1].label(), "sensor_bias[f_lift]");
  EXPECT_EQ(chosen[2].label(), "soil_cohesion");
  EXPECT_FALSE(
      chosen[1].signature.empty());  // the candidate itself, not a copy without its signature
  // a label that names nothing: one error naming the option, the label and the labels there are
  try {
    chosen_candidates(all, {"engine_power_sharing", "sensor_bias"});
    FAIL() << "an unknown label was accepted";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("--candidates"), std::string::npos) << what;
    EXPECT_NE(what.find("'sensor_bias'"), std::string::npos) << what;
    EXPECT_NE(what.find("sensor_bias[f_lift]"), std::string::npos) << what;
  }
}

TEST(Diagnose, ScanReachesNearZeroOnRangesFromZero) {
  // hydraulic_lag's time constant spans [0, 2] s: the linear centres start at 1/18 of it (0.11 s),
  // the near-zero points go down to 1e-3 of it, so a true 6 ms (0.3 % of the range) has a scan
  // point within a factor of two
  const Candidate lag{"hydraulic_lag", "", {}};
  const auto points = candidate_scan_points(lag, {});
  ASSERT_EQ(points.size(), static_cast<std::size_t>(kScanPoints + 3));
  double smallest = 1.0, nearest = 1e9;
  for (const auto& p : points) {
    ASSERT_EQ(p.size(), 1u);
    EXPECT_GT(p[0], 0.0);
    EXPECT_LT(p[0], 1.0);
    smallest = std::min(smallest, p[0]);
    nearest = std::min(nearest, std::abs(std::log(p[0] / 0.003)));
  }
  EXPECT_LE(smallest, 1e-3);
  EXPECT_LE(nearest, std::log(2.0));
  // engine_power_sharing's efficiency spans [0.5, 1]: no near-zero points
  EXPECT_EQ(candidate_scan_points({"engine_power_sharing", "", {}}, {}).size(),
            static_cast<std::size_t>(kScanPoints));
}

// a plug-in described in memory with one effect of three parameters (hooks that do nothing)
void* create_nothing() { return new int(0); }
void destroy_nothing(void* self) { delete static_cast<int*>(self); }
void set_nothing(void*, int, double) {}
const talus_effect_parameter kThree[] = {{"a", 1.0, 0.0, 2.0, "1", "first"},
                                         {"b", 1.0, 0.1, 10.0, "1", "second"},
                                         {"c", 0.0, -1.0, 1.0, "1", "third"}};
const talus_effect_type kThreeEffect[] = {{"three_parameters", "a test effect", 3, kThree,
                                           create_nothing, destroy_nothing, set_nothing, nullptr,
                                           nullptr, nullptr, nullptr, nullptr}};
const talus_effect_plugin_info kThreeInfo = {TALUS_EFFECT_ABI_VERSION, "test", 1, kThreeEffect};

TEST(Diagnose, EffectsWithThreeParametersAreScannedOnASpaceFillingDesign) {
  const vehicle::EffectPlugins plugins = {
      vehicle::EffectPlugin::from_info(&kThreeInfo, "in-memory")};
  const auto points = candidate_scan_points({"three_parameters", "", {}}, plugins);
  ASSERT_EQ(points.size(), static_cast<std::size_t>(3 * kScanPoints));
  // inside the box, distinct, and every parameter's eighths all visited (a grid of 27 would visit
  // three values per parameter)
  for (int d = 0; d < 3; ++d) {
    std::vector<int> eighths(8, 0);
    for (const auto& p : points) {
      ASSERT_EQ(p.size(), 3u);
      ASSERT_GT(p[d], 0.0);
      ASSERT_LT(p[d], 1.0);
      ++eighths[static_cast<int>(8 * p[d])];
    }
    for (int e = 0; e < 8; ++e) EXPECT_GT(eighths[e], 0) << "parameter " << d << " eighth " << e;
  }
  for (std::size_t i = 0; i < points.size(); ++i)
    for (std::size_t j = i + 1; j < points.size(); ++j) EXPECT_NE(points[i], points[j]);
}

TEST(Diagnose, MeanRowAveragesAbsoluteValues) {
  TableRow a{"a", {0.1, 0.2, 0.3, 0.4, 0.5, -0.2, 0.1}, 0.3};
  TableRow b{"b", {0.3, 0.2, 0.1, 0.0, 0.1, 0.2, -0.3}, 0.1};
  const TableRow m = mean_row({a, b}, "mean");
  EXPECT_DOUBLE_EQ(m.e.e_x, 0.2);
  EXPECT_DOUBLE_EQ(m.e.e_m, 0.2);  // |−0.2| and |0.2|
  EXPECT_DOUBLE_EQ(m.e.e_w, 0.2);
  EXPECT_DOUBLE_EQ(m.mean, 0.2);
  // a run whose measured bucket came back empty (E_M undefined) leaves E_M's mean to the others
  TableRow empty{"empty", {0.5, 0.5, 0.5, 0.5, 0.5, std::nan(""), 0.5}, 0.5};
  const TableRow with_empty = mean_row({a, b, empty}, "mean");
  EXPECT_DOUBLE_EQ(with_empty.e.e_m, 0.2);
  EXPECT_DOUBLE_EQ(with_empty.e.e_x, 0.3);
  EXPECT_NEAR(with_empty.mean, 0.3, 1e-15);
  EXPECT_TRUE(std::isnan(mean_row({empty}, "only").e.e_m));              // no run defines it
  EXPECT_EQ(table_markdown({empty}, 3).find("nan"), std::string::npos);  // printed as n/a
  EXPECT_NE(table_markdown({empty}, 3).find("| n/a |"), std::string::npos);
}

TEST(Diagnose, JsonHasTheIssuesFields) {
  Diagnosis d;
  d.runs = {"a"};
  d.calibration = d.validation = {0};
  d.error_before = {{"a", {0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1}, 0.1}};
  d.error_after = {{"a", {0.05, 0.05, 0.05, 0.05, 0.05, 0.05, 0.05}, 0.05}};
  d.residuals_before.resize(1);
  d.residuals_after.resize(1);
  d.scan_rms_m.resize(1);
  FittedEffect f;
  f.candidate = {"hydraulic_lag", "", {}};
  f.effect = {{"name", "hydraulic_lag"}, {"params", {{"time_constant", 0.3}}}};
  d.found.push_back(f);
  d.candidates = {"hydraulic_lag", "soil_cohesion"};
  // two rounds, the second with a joint refit
  d.rounds.resize(2);
  JointRefit refit;
  refit.before = {"hydraulic_lag:time_constant=0.35", "cylinder_friction:force=9000"};
  refit.after = {"hydraulic_lag:time_constant=0.3", "cylinder_friction:force=10000"};
  refit.kept = true;
  refit.simulations = 12;
  d.rounds[1].refit = refit;
  ChaosCheck check;
  check.effects = {"hydraulic_lag:time_constant=0.002"};
  check.excess_before = 0.8;
  check.excess_with = 0.7;
  check.explained = 0.125;
  check.simulations = 8;
  d.rounds[0].chaos_checks.push_back(check);
  const auto j = diagnosis_json(d);
  // the chaos check of round 1 (refused), none in round 2 or the discovery
  ASSERT_EQ(j["rounds"][0]["chaos_checks"].size(), 1u);
  EXPECT_EQ(j["rounds"][0]["chaos_checks"][0]["effects"][0], "hydraulic_lag:time_constant=0.002");
  EXPECT_FALSE(j["rounds"][0]["chaos_checks"][0]["passed"].get<bool>());
  EXPECT_DOUBLE_EQ(j["rounds"][0]["chaos_checks"][0]["explained"].get<double>(), 0.125);
  EXPECT_EQ(j["rounds"][0]["chaos_checks"][0]["simulations"].get<int>(), 8);
  EXPECT_TRUE(j["rounds"][1]["chaos_checks"].empty());
  EXPECT_TRUE(j["discovery"]["chaos_checks"].empty());
  EXPECT_TRUE(j["rounds"][0]["refit"].is_null());
  EXPECT_TRUE(j["rounds"][1]["refit"]["kept"].get<bool>());
  EXPECT_EQ(j["rounds"][1]["refit"]["after"][1], "cylinder_friction:force=10000");
  EXPECT_EQ(j["rounds"][1]["refit"]["simulations"].get<int>(), 12);
  ASSERT_EQ(j["effects_found"].size(), 1u);
  EXPECT_EQ(j["candidates"], nlohmann::json({"hydraulic_lag", "soil_cohesion"}));
  EXPECT_EQ(j["effects_found"][0]["name"], "hydraulic_lag");
  EXPECT_DOUBLE_EQ(j["effects_found"][0]["params"]["time_constant"].get<double>(), 0.3);
  for (const char* key : {"E_x", "E_v", "E_tr", "E_l", "E_t", "E_M", "E_W", "mean"}) {
    EXPECT_TRUE(j["error_before"].contains(key)) << key;
    EXPECT_TRUE(j["error_after"].contains(key)) << key;
  }
  EXPECT_DOUBLE_EQ(j["error_after"]["mean"].get<double>(), 0.05);
  EXPECT_FALSE(j["unexplained"].get<bool>());
  // no ensemble: the sensor noise alone judged the residual, and the JSON says so
  EXPECT_FALSE(j["model_spread_used"].get<bool>());
  EXPECT_TRUE(j["runs"][0]["model_spread"].is_null());
}

// a run judged against a simulation's spread: diagnosis.json names the piles and each channel's
// mean share of the variance (the residuals' own numbers), and every cell its spread
TEST(Diagnose, JsonReportsTheModelSpreadItUsed) {
  sim2real::Run measured;
  measured.series = test::reference_series();
  measured.summary = test::reference_summary();
  sim2real::Run simulated;
  simulated.series = test::simulated_series();
  simulated.spread = RunSpread{3, {}, 0, {}, {}, {}, {}, {}};
  simulated.spread->variance[Channel::t] = simulated.series[Channel::t];
  for (std::size_t c = 1; c < kChannelCount; ++c)
    simulated.spread->variance.columns[c].assign(simulated.series.size(), c == 1 ? 4e6 : 0.0);
  const std::vector<double> sigma(kChannelCount, 1e3);
  Diagnosis d;
  d.runs = {"a"};
  d.calibration = d.validation = {0};
  d.error_before = d.error_after = {{"a", {0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1}, 0.1}};
  d.residuals_before = {compute_residuals(simulated, measured, sigma)};
  d.residuals_after = d.residuals_before;
  d.scan_rms_m.resize(1);
  const auto j = diagnosis_json(d);
  EXPECT_TRUE(j["model_spread_used"].get<bool>());
  const auto& spread = j["runs"][0]["model_spread"];
  ASSERT_TRUE(spread.is_object());
  EXPECT_EQ(spread["members"].get<int>(), 3);
  // f_lift: (1 + 1/3) 4e6 / (1e6 + (1 + 1/3) 4e6) in every sample; f_tilt has no spread
  EXPECT_NEAR(spread["variance_share_before"]["f_lift"].get<double>(), 16.0 / 19.0, 1e-12);
  EXPECT_EQ(spread["variance_share_after"]["f_tilt"].get<double>(), 0.0);
  const auto& cell = j["residuals_before"][0]["cells"][0];
  EXPECT_EQ(cell["channel"], "f_lift");
  EXPECT_NEAR(cell["spread"].get<double>(), std::sqrt(4.0 / 3.0 * 4e6), 1e-6);
  EXPECT_NEAR(cell["spread_share"].get<double>(), 16.0 / 19.0, 1e-12);
  // white departures (no τ given): every sample counts under the null, and the allowance is κ
  EXPECT_EQ(cell["null_samples"].get<double>(), double(d.residuals_before[0].cells[0].samples));
  EXPECT_EQ(cell["allowance"].get<double>(), kNoiseAllowance);
  EXPECT_EQ(cell["effective_samples"].get<double>(),
            d.residuals_before[0].cells[0].effective_samples);
  // a variance taken as known has no degrees of freedom; an estimated one gives them per channel
  EXPECT_TRUE(spread["variance_dof"].is_null());
  simulated.spread->variance_dof.assign(kChannelCount, 2.0);
  simulated.spread->variance_dof[static_cast<std::size_t>(Channel::power)] = 7.5;
  d.residuals_before = {compute_residuals(simulated, measured, sigma)};
  const auto dof = diagnosis_json(d)["runs"][0]["model_spread"]["variance_dof"];
  EXPECT_EQ(dof["f_lift"].get<double>(), 2.0);
  EXPECT_EQ(dof["power"].get<double>(), 7.5);
  EXPECT_FALSE(dof.contains("t"));
}

// diagnosis.json says per run whether the sensitivity spread judged it, its simulations and the
// excess before and after it (the verdict's judgement, the last), and lists every judgement with
// its parameters' uncertainty and its cost; a judgement that skipped says why
TEST(Diagnose, JsonReportsTheSensitivityJudgements) {
  Diagnosis d;
  d.runs = {"a", "b"};
  d.calibration = {0};
  d.validation = {1};
  d.error_before = d.error_after = {{"a", {0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1}, 0.1},
                                    {"b", {0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1}, 0.1}};
  d.residuals_before.resize(2);
  d.residuals_after.resize(2);
  d.scan_rms_m.resize(2);
  SensitivityJudgement skipped;
  skipped.after = "round 1";
  skipped.reason = "every run is within noise without it";
  skipped.runs = {{false, "within noise without it", 0, 0.1, 0.1},
                  {false, "within noise without it", 0, 0.2, 0.2}};
  SensitivityJudgement used;
  used.after = "round 2";
  used.used = true;
  used.parameters = {{"hydraulic_lag", "time_constant", "s", 0.3, 0.002, 0.299, 0.301}};
  used.curvature_in_range = true;
  used.curvature_simulations = 2;
  used.effective_sample_share = 0.04;
  used.design_points = 2;
  used.runs = {{false, "within noise without it", 0, 0.1, 0.1}, {true, "", 2, 1.7, 0.05}};
  d.sensitivity = {skipped, used};
  const auto j = diagnosis_json(d);
  EXPECT_TRUE(j["sensitivity_used"].get<bool>());
  EXPECT_EQ(j["sensitivity_simulations"].get<int>(), 4);  // 2 for the curvature, 2 for run b
  ASSERT_EQ(j["sensitivity"].size(), 2u);
  EXPECT_EQ(j["sensitivity"][0]["reason"], "every run is within noise without it");
  EXPECT_TRUE(j["sensitivity"][0]["effective_sample_share"].is_null());  // no curvature measured
  EXPECT_FALSE(j["sensitivity"][1].contains("reason"));
  const auto& p = j["sensitivity"][1]["parameters"][0];
  EXPECT_EQ(p["parameter"], "time_constant");
  EXPECT_DOUBLE_EQ(p["low"].get<double>(), 0.299);
  EXPECT_EQ(j["sensitivity"][1]["design_points"].get<int>(), 2);
  EXPECT_DOUBLE_EQ(j["sensitivity"][1]["effective_sample_share"].get<double>(), 0.04);
  // per run: the verdict's judgement
  const auto& a = j["runs"][0]["sensitivity_spread"];
  EXPECT_FALSE(a["used"].get<bool>());
  EXPECT_EQ(a["reason"], "within noise without it");
  const auto& b = j["runs"][1]["sensitivity_spread"];
  EXPECT_TRUE(b["used"].get<bool>());
  EXPECT_EQ(b["simulations"].get<int>(), 2);
  EXPECT_DOUBLE_EQ(b["excess_without"].get<double>(), 1.7);
  EXPECT_DOUBLE_EQ(b["excess_with"].get<double>(), 0.05);
}

}  // namespace
}  // namespace talus::sim2real
