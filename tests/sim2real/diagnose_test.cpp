// The loop's parts that need no simulation campaign: the candidate set and its signatures, the
// mean row of an error table, and the JSON contract. The loop itself runs end to end in
// tests/apps/diagnose_test.cpp (blind identification, no false positive, an effect outside the set).
#include "sim2real/diagnose.hpp"

#include <gtest/gtest.h>

#include <algorithm>

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

TEST(Diagnose, MeanRowAveragesAbsoluteValues) {
  TableRow a{"a", {0.1, 0.2, 0.3, 0.4, 0.5, -0.2, 0.1}, 0.3};
  TableRow b{"b", {0.3, 0.2, 0.1, 0.0, 0.1, 0.2, -0.3}, 0.1};
  const TableRow m = mean_row({a, b}, "mean");
  EXPECT_DOUBLE_EQ(m.e.e_x, 0.2);
  EXPECT_DOUBLE_EQ(m.e.e_m, 0.2);  // |−0.2| and |0.2|
  EXPECT_DOUBLE_EQ(m.e.e_w, 0.2);
  EXPECT_DOUBLE_EQ(m.mean, 0.2);
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
  const auto j = diagnosis_json(d);
  ASSERT_EQ(j["effects_found"].size(), 1u);
  EXPECT_EQ(j["effects_found"][0]["name"], "hydraulic_lag");
  EXPECT_DOUBLE_EQ(j["effects_found"][0]["params"]["time_constant"].get<double>(), 0.3);
  for (const char* key : {"E_x", "E_v", "E_tr", "E_l", "E_t", "E_M", "E_W", "mean"}) {
    EXPECT_TRUE(j["error_before"].contains(key)) << key;
    EXPECT_TRUE(j["error_after"].contains(key)) << key;
  }
  EXPECT_DOUBLE_EQ(j["error_after"]["mean"].get<double>(), 0.05);
  EXPECT_FALSE(j["unexplained"].get<bool>());
}

}  // namespace
}  // namespace talus::sim2real
