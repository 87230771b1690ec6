// The discovery's regression (issue 17) on data whose answer is known: the elimination path with
// collinear distractors, the cross-validated sparsity and intervals on fresh random draws, the
// regression data a measured/simulated pair gives, and the JSON. The loop end to end, blind:
// tests/apps/discovery_test.cpp.
#include "sim2real/discovery.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <random>

#include "host/error.hpp"
#include "synthetic_runs.hpp"
#include "vehicle/effect_plugin.hpp"
#include "vehicle/learned_correction.hpp"
#include "vehicle/scenario.hpp"

namespace talus::sim2real {
namespace {

using vehicle::CorrectionKind;

using test::fresh_rng;

// index of a dictionary feature by name
Eigen::Index feature_index(CorrectionKind kind, const std::string& name) {
  const auto& f = vehicle::correction_features(kind);
  for (std::size_t k = 0; k < f.size(); ++k)
    if (name == f[k].name) return static_cast<Eigen::Index>(k);
  ADD_FAILURE() << "no feature " << name;
  return 0;
}

// rows of the actuator dictionary from random states (a command held for 1.5 s at a time, at rest a
// quarter of the time, a force, a power and delayed commands), and y = Σ truth_k φ_k + noise
RegressionData synthetic(std::mt19937_64& rng,
                         const std::vector<std::pair<std::string, double>>& truth, double noise,
                         int rows = 2000) {
  const auto& features = vehicle::correction_features(CorrectionKind::actuator);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::uniform_real_distribution<double> level(-0.2, 0.22), chance(0.0, 1.0);
  RegressionData d;
  d.features.resize(rows, static_cast<Eigen::Index>(features.size()));
  d.residual.resize(rows);
  double u = 0.0;
  std::vector<double> history(100, 0.0);
  for (int r = 0; r < rows; ++r) {
    if (r % 150 == 0) u = chance(rng) < 0.25 ? 0.0 : level(rng);  // a new command every 1.5 s
    history.erase(history.begin());
    history.push_back(u);
    vehicle::CorrectionInputs in;
    in.a = u;
    in.force = 1.5e5 + 4e4 * gauss(rng);
    in.power = 5e4 + 2e4 * gauss(rng);
    in.a_delayed = {history[89], history[79], history[59]};  // 0.1, 0.2, 0.4 s at 100 Hz
    double y = noise * gauss(rng);
    for (std::size_t k = 0; k < features.size(); ++k) {
      d.features(r, static_cast<Eigen::Index>(k)) = features[k].value(in);
    }
    for (const auto& [name, c] : truth)
      y += c * d.features(r, feature_index(CorrectionKind::actuator, name));
    d.residual[r] = y;
    d.fold.push_back(std::min(kFolds - 1, r * kFolds / rows));
    d.run.push_back(0);
  }
  return d;
}

TEST(Discovery, EliminationPathKeepsTheTrueTermsAmongCollinearOnes) {
  std::mt19937_64 rng = fresh_rng();
  // a leakage with pressure: Δu = −2e-7 F sign(u); sign(u), u and u|u| are nearly collinear here
  const RegressionData d = synthetic(rng, {{"force_sign_command", -2e-7}}, 0.005);
  const auto path = elimination_path(d.features, d.residual);
  ASSERT_GE(path.size(), 2u);
  ASSERT_EQ(path[1].size(), 1u);
  EXPECT_EQ(path[1][0], feature_index(CorrectionKind::actuator, "force_sign_command"));
  // every smaller model is a subset of the larger one (one term dropped per step)
  for (std::size_t m = 1; m + 1 < path.size(); ++m)
    for (Eigen::Index k : path[m])
      EXPECT_NE(std::find(path[m + 1].begin(), path[m + 1].end(), k), path[m + 1].end());
}

// the coefficient on `alias` that stands for c times `feature` on these rows (least squares of
// the one column on the other): what a fit naming the alias should find
double in_terms_of(const RegressionData& d, const std::string& feature, const std::string& alias,
                   double c) {
  const Eigen::VectorXd f = d.features.col(feature_index(CorrectionKind::actuator, feature));
  const Eigen::VectorXd a = d.features.col(feature_index(CorrectionKind::actuator, alias));
  return c * f.dot(a) / a.squaredNorm();
}

TEST(Discovery, FitFindsASparseTruthAndItsIntervalsCoverIt) {
  // a dead band with a delay at random magnitudes, 50 draws: the two right terms every time, and
  // the 95 % intervals covering the truth in about 95 % of the coefficients. Commands held for
  // 1.5 s leave sign(u) and the dictionary's dead bands clip(u, ±δ₀) nearly proportional (they
  // differ only on a command held inside ±δ₀), so a dead-band term naming sign(u) as its alias is
  // the right term, and its truth is c sign(u) written in that feature
  std::mt19937_64 rng = fresh_rng();
  std::uniform_real_distribution<double> u(0.5, 1.5);
  int covered = 0, coefficients = 0, right = 0;
  for (int draw = 0; draw < 50; ++draw) {
    const double c1 = -0.04 * u(rng), c2 = 0.6 * u(rng);
    const RegressionData d = synthetic(rng, {{"sign_command", c1}, {"delay_02", c2}}, 0.01);
    const DiscoveredCorrection c = fit_correction({CorrectionKind::actuator, "lift"}, d);
    const auto is_sign = [](const auto& t) {
      return t.feature == "sign_command" ||
             std::find(t.aliases.begin(), t.aliases.end(), "sign_command") != t.aliases.end();
    };
    const bool sign = std::any_of(c.terms.begin(), c.terms.end(), is_sign);
    const bool delay = std::any_of(c.terms.begin(), c.terms.end(),
                                   [](const auto& t) { return t.feature == "delay_02"; });
    if (c.terms.size() != 2 || !sign || !delay) {
      std::cerr << "draw " << draw << ": " << c.expression << "\n";
      continue;
    }
    ++right;
    for (const auto& t : c.terms) {
      const double truth =
          t.feature == "delay_02" ? c2 : in_terms_of(d, "sign_command", t.feature, c1);
      covered += std::abs(t.coefficient - truth) <= t.half_width;
      ++coefficients;
      EXPECT_LE(std::abs(t.coefficient - truth), 3.0 * t.half_width) << c.expression;
      EXPECT_LT(t.half_width, 0.1 * std::abs(truth)) << c.expression;
    }
    EXPECT_LT(c.cv_mse, 0.5 * c.cv_mse_none);
    EXPECT_NE(c.spec.find("learned_actuator_correction:actuator=lift,"), std::string::npos)
        << c.spec;
    // the dead band names sign(u) as its term or as the term's alias
    EXPECT_NE(c.expression.find("sign(u_lift)"), std::string::npos) << c.expression;
  }
  EXPECT_GE(right, 45) << "the right two terms in " << right << " of 50 draws";
  // about 100 coefficients at 95 %: fewer than 85 % covered has a chance of about 1e-4
  std::cerr << covered << " of " << coefficients << " intervals cover the truth\n";
  EXPECT_GE(covered, 85 * coefficients / 100);
}

TEST(Discovery, FeaturesTheDataCannotSeparateAreNamedAsAliases) {
  // the lift under a constant load: f_lift·sign(u) is 1.5e5 sign(u) exactly, so whichever of the
  // two the fit keeps, the other is its alias and the expression says so (commands held outside
  // ±0.01 m/s make a dead band clip(u, ±δ₀) a third such feature: kept, it names both)
  std::mt19937_64 rng = fresh_rng();
  RegressionData d = synthetic(rng, {{"sign_command", -0.03}}, 0.005);
  const Eigen::Index sign = feature_index(CorrectionKind::actuator, "sign_command");
  const Eigen::Index force_sign = feature_index(CorrectionKind::actuator, "force_sign_command");
  d.features.col(force_sign) = 1.5e5 * d.features.col(sign);
  const DiscoveredCorrection c = fit_correction({CorrectionKind::actuator, "lift"}, d);
  ASSERT_EQ(c.terms.size(), 1u) << c.expression;
  const auto& t = c.terms[0];
  std::vector<std::string> named = t.aliases;
  named.push_back(t.feature);
  for (const char* f : {"sign_command", "force_sign_command"})
    EXPECT_NE(std::find(named.begin(), named.end(), f), named.end()) << f << ": " << c.expression;
  EXPECT_NE(c.expression.find("on these runs ≡"), std::string::npos) << c.expression;
  // a feature the data do separate is no alias
  EXPECT_EQ(std::find(t.aliases.begin(), t.aliases.end(), "delay_02"), t.aliases.end());
}

TEST(Discovery, NoiseAloneGivesNoTerms) {
  // over several fresh draws: nothing cuts the held-out error of pure noise by 5 %
  std::mt19937_64 rng = fresh_rng();
  for (int draw = 0; draw < 5; ++draw) {
    const RegressionData d = synthetic(rng, {}, 0.01);
    const DiscoveredCorrection c = fit_correction({CorrectionKind::actuator, "tilt"}, d);
    EXPECT_TRUE(c.terms.empty()) << "draw " << draw << ": " << c.expression;
  }
}

TEST(Discovery, TargetsAreTheActuatorsTheTractionThenTheGivenChannels) {
  const auto t = discovery_targets({"f_traction"});
  ASSERT_EQ(t.size(), 5u);
  EXPECT_EQ(t[0].label(), "drive speed");
  EXPECT_EQ(t[1].option(), "actuator=lift");
  EXPECT_EQ(t[3].label(), "tractive force");
  EXPECT_EQ(t[3].effect_name(), "learned_traction_correction");
  EXPECT_EQ(t[3].option(), "");
  EXPECT_EQ(t[4].effect_name(), "learned_sensor_correction");
  EXPECT_EQ(t[4].option(), "channel=f_traction");
  EXPECT_THROW(discovery_targets({"f_nothing"}), Error);
}

// a measured/simulated pair on a 10 s, 100 Hz time base: the lift stroke rising at 0.2 m/s in
// the simulation and at 0.2 − 0.03 m/s in the data (the command 0.25 m/s is clipped to 0.2 in both)
struct Pair {
  MeasuredRun measured;
  Run simulated;
};
Pair clipped_lift_pair() {
  Pair p;
  TimeSeries m, s;
  for (int k = 0; k <= 1000; ++k) {
    const double t = 0.01 * k;
    for (std::size_t c = 0; c < kChannelCount; ++c) {
      m.columns[c].push_back(0.0);
      s.columns[c].push_back(0.0);
    }
    m[Channel::t].back() = s[Channel::t].back() = t;
    m[Channel::d_lift].back() = 0.17 * t;
    s[Channel::d_lift].back() = 0.2 * t;
    m[Channel::f_lift].back() = s[Channel::f_lift].back() = 1.5e5;
    m[Channel::f_traction].back() = 2e4;
    s[Channel::f_traction].back() = 1e4;  // the sensor reads 1e4 N high in the data
  }
  p.measured.run.series = m;
  p.measured.meta.lift = {{0.0, 0.25}, {10.0, 0.25}};
  p.measured.meta.drive = p.measured.meta.tilt = {{0.0, 0.0}, {10.0, 0.0}};
  p.simulated.series = s;
  return p;
}

TEST(Discovery, RegressionDataCountsTheResidualOnTheCommandsScale) {
  const Pair p = clipped_lift_pair();
  // clip(u + Δu) = 0.17 m/s asks Δu = 0.17 − 0.25 = −0.08 m/s, not the speeds' difference −0.03
  const RegressionData d =
      regression_data({CorrectionKind::actuator, "lift"}, {&p.measured}, {&p.simulated}, 0.2);
  ASSERT_EQ(d.residual.size(), 1001 - 2 * kRateHalfWindow);
  for (Eigen::Index r = 0; r < d.residual.size(); ++r) EXPECT_NEAR(d.residual[r], -0.08, 1e-9) << r;
  EXPECT_DOUBLE_EQ(d.features(0, feature_index(CorrectionKind::actuator, "command")), 0.25);
  EXPECT_NEAR(d.features(0, feature_index(CorrectionKind::actuator, "force")), 1.5e5, 1e-6);
  // the folds are contiguous fifths of the run
  EXPECT_EQ(d.fold.front(), 0);
  EXPECT_EQ(d.fold.back(), kFolds - 1);
  EXPECT_TRUE(std::is_sorted(d.fold.begin(), d.fold.end()));
  // a sensor: the measured reading minus the simulated one, the simulated reading as the truth
  const RegressionData s =
      regression_data({CorrectionKind::sensor, "f_traction"}, {&p.measured}, {&p.simulated}, 0.0);
  EXPECT_NEAR(s.residual[0], 1e4, 1e-9);
  EXPECT_DOUBLE_EQ(s.features(0, feature_index(CorrectionKind::sensor, "reading")), 1e4);
  // and the fit of that constant offset is one term worth the offset (every feature is constant
  // here, so any one of them can carry it)
  const DiscoveredCorrection c = fit_correction({CorrectionKind::sensor, "f_traction"}, s);
  ASSERT_EQ(c.terms.size(), 1u) << c.expression;
  const double value = s.features(0, feature_index(CorrectionKind::sensor, c.terms[0].feature));
  EXPECT_NEAR(c.terms[0].coefficient * value, 1e4, 1.0) << c.expression;
}

TEST(Discovery, ACylindersFeaturesAreMeansOverItsRatesWindow) {
  // a lift that loses 0.03 m/s · sign(u) while its command ramps up, holds, reverses and stops:
  // the strokes integrated finely (1e-5 s) from the commands, the data's with the loss. A central
  // difference of a stroke is the mean speed over its window, so each row's sign(u) must be that
  // window's mean for the loss to be one term exactly, on the ramps too (at the window's centre,
  // as until 2026-11-28, it is off by up to half the loss just after the lift starts)
  const Series2 lift = {{0.0, 0.0},  {1.0, 0.0},  {1.2, 0.1}, {3.0, 0.1},
                        {3.2, -0.1}, {5.0, -0.1}, {5.2, 0.0}, {10.0, 0.0}};
  const vehicle::PiecewiseLinear command(lift);
  const auto& sign =
      vehicle::correction_features(CorrectionKind::actuator)[static_cast<std::size_t>(
          feature_index(CorrectionKind::actuator, "sign_command"))];
  constexpr double kLoss = 0.03;  // m/s
  Pair p;
  TimeSeries m, s;
  double d_data = 0.0, d_sim = 0.0;
  constexpr int kSub = 1000;
  for (int k = 0; k <= 1000; ++k) {
    if (k > 0)
      for (int q = 0; q < kSub; ++q) {
        vehicle::CorrectionInputs in;
        in.a = command(0.01 * (k - 1) + 0.01 * (q + 0.5) / kSub);
        d_sim += 0.01 / kSub * in.a;
        d_data += 0.01 / kSub * (in.a - kLoss * sign.value(in));
      }
    for (std::size_t c = 0; c < kChannelCount; ++c) {
      m.columns[c].push_back(0.0);
      s.columns[c].push_back(0.0);
    }
    m[Channel::t].back() = s[Channel::t].back() = 0.01 * k;
    m[Channel::d_lift].back() = d_data;
    s[Channel::d_lift].back() = d_sim;
  }
  p.measured.run.series = m;
  p.measured.meta.lift = lift;
  p.measured.meta.drive = p.measured.meta.tilt = {{0.0, 0.0}, {10.0, 0.0}};
  p.simulated.series = s;
  const RegressionData d =
      regression_data({CorrectionKind::actuator, "lift"}, {&p.measured}, {&p.simulated}, 1.0);
  const Eigen::Index k = feature_index(CorrectionKind::actuator, "sign_command");
  // the trapezoid over 10 ms samples places the 2 ms onset of sign(u) within one sample
  double worst = 0.0;
  int onset = 0;  // rows whose window holds part of a start or stop of the loss
  for (Eigen::Index r = 0; r < d.residual.size(); ++r) {
    worst = std::max(worst, std::abs(d.residual[r] + kLoss * d.features(r, k)));
    const double share = std::abs(d.residual[r]) / kLoss;
    onset += share > 0.1 && share < 0.9;
  }
  EXPECT_LT(worst, 0.05 * kLoss);
  EXPECT_GE(onset, 10) << "too few rows inside an onset for the check above to see a window";
}

TEST(Discovery, AStrokeDependentLossAndALossOfTheDiggingPhaseAreFoundAsTheirTerms) {
  // a lift that loses 0.3 d_lift u (a loss growing along the stroke) everywhere and a further
  // 0.2 u inside the digging phase [3, 6) s (flow the dig takes elsewhere), its strokes integrated
  // finely (1e-5 s) from commands at several levels; the phase comes from the simulated run's
  // marks, the phase its effects saw. The fit must keep exactly the two terms, within 2 %
  const Series2 lift = {{0.0, 0.0},   {0.5, 0.0},   {0.7, 0.15}, {2.0, 0.15}, {2.2, 0.08},
                        {4.0, 0.08},  {4.2, -0.1},  {5.0, -0.1}, {5.2, 0.12}, {7.0, 0.12},
                        {7.2, -0.05}, {9.5, -0.05}, {9.6, 0.0}};
  const vehicle::PiecewiseLinear command(lift);
  constexpr double kStrokeLoss = 0.3, kDigLoss = 0.2;  // 1/m, 1
  constexpr double kDigStart = 3.0, kDigEnd = 6.0;     // s
  Pair p;
  TimeSeries m, sim;
  double d_data = 0.2, d_sim = 0.2;  // m: the strokes start mid-way
  constexpr int kSub = 1000;
  for (int k = 0; k <= 1000; ++k) {
    if (k > 0)
      for (int q = 0; q < kSub; ++q) {
        const double t = 0.01 * (k - 1) + 0.01 * (q + 0.5) / kSub;
        const double u = command(t), dig = t >= kDigStart && t < kDigEnd ? 1.0 : 0.0;
        d_sim += 0.01 / kSub * u;
        d_data += 0.01 / kSub * (u - kStrokeLoss * d_data * u - kDigLoss * dig * u);
      }
    for (std::size_t c = 0; c < kChannelCount; ++c) {
      m.columns[c].push_back(0.0);
      sim.columns[c].push_back(0.0);
    }
    m[Channel::t].back() = sim[Channel::t].back() = 0.01 * k;
    m[Channel::d_lift].back() = d_data;
    sim[Channel::d_lift].back() = d_sim;
    m[Channel::f_lift].back() = sim[Channel::f_lift].back() = 1.5e5;
  }
  p.measured.run.series = m;
  p.measured.meta.lift = lift;
  p.measured.meta.drive = p.measured.meta.tilt = {{0.0, 0.0}, {10.0, 0.0}};
  p.simulated.series = sim;
  p.simulated.summary.dig_start_s = kDigStart;
  p.simulated.summary.dig_end_s = kDigEnd;
  const DiscoveryTarget lift_target{CorrectionKind::actuator, "lift"};
  const RegressionData d = regression_data(lift_target, {&p.measured}, {&p.simulated}, 1.0);
  const DiscoveredCorrection c = fit_correction(lift_target, d);
  ASSERT_EQ(c.terms.size(), 2u) << c.expression;
  for (const auto& term : c.terms) {
    if (term.feature == "stroke_times") {
      EXPECT_NEAR(term.coefficient, -kStrokeLoss, 0.02 * kStrokeLoss) << c.expression;
    } else {
      EXPECT_EQ(term.feature, "digging_times") << c.expression;
      EXPECT_NEAR(term.coefficient, -kDigLoss, 0.02 * kDigLoss) << c.expression;
    }
  }
  EXPECT_NE(c.expression.find("d_lift·u_lift"), std::string::npos) << c.expression;
  EXPECT_NE(c.expression.find("[dig]·u_lift"), std::string::npos) << c.expression;
  // without marks the run has no digging phase: its features are zero and stay out of the fit
  p.simulated.summary.dig_start_s.reset();
  p.simulated.summary.dig_end_s.reset();
  const RegressionData none = regression_data(lift_target, {&p.measured}, {&p.simulated}, 1.0);
  EXPECT_EQ(
      none.features.col(feature_index(CorrectionKind::actuator, "digging")).cwiseAbs().maxCoeff(),
      0.0);
}

TEST(Discovery, AResistanceGrowingWithTheLoadIsFoundAsATractionTerm) {
  // the data's tractive force reads 0.02 |f_lift| sign(v) more than the simulation's (a rolling
  // resistance that grows with the load carried), while the machine drives forward and back with
  // and without a load; the regression must keep that one term, within 1 %, and its spec must run
  const Series2 drive = {{0.0, 0.0}, {1.0, 2.0}, {4.0, 2.0}, {5.0, -1.5}, {8.0, -1.5}, {9.0, 0.0}};
  const vehicle::PiecewiseLinear speed(drive);
  Pair p;
  TimeSeries m, sim;
  for (int k = 0; k <= 1000; ++k) {
    const double t = 0.01 * k, v = speed(t);
    const double load = t < 2.5 || t > 6.5 ? 1.6e5 : 2e4;  // N: the bucket loaded, then empty
    const double sign = std::clamp(v / vehicle::kTractionSignRampSpeed, -1.0, 1.0);
    for (std::size_t c = 0; c < kChannelCount; ++c) {
      m.columns[c].push_back(0.0);
      sim.columns[c].push_back(0.0);
    }
    m[Channel::t].back() = sim[Channel::t].back() = t;
    m[Channel::v_drive].back() = sim[Channel::v_drive].back() = v;
    m[Channel::f_lift].back() = sim[Channel::f_lift].back() = load;
    sim[Channel::f_traction].back() = 4e3 * v;
    m[Channel::f_traction].back() = 4e3 * v + 0.02 * load * sign;
  }
  p.measured.run.series = m;
  p.measured.meta.drive = drive;
  p.measured.meta.lift = p.measured.meta.tilt = {{0.0, 0.0}, {10.0, 0.0}};
  p.simulated.series = sim;
  const DiscoveryTarget traction{CorrectionKind::traction, "traction"};
  EXPECT_EQ(traction.label(), "tractive force");
  const RegressionData d = regression_data(traction, {&p.measured}, {&p.simulated}, 0.0);
  const DiscoveredCorrection c = fit_correction(traction, d);
  // the load reaches the feature through the pressure lag, so the fit is near, not exact
  ASSERT_EQ(c.terms.size(), 1u) << c.expression;
  EXPECT_EQ(c.terms[0].feature, "abs_force_sign_speed") << c.expression;
  EXPECT_NEAR(c.terms[0].coefficient, 0.02, 0.01 * 0.02) << c.expression;
  EXPECT_EQ(c.expression.rfind("Δf_traction [N] =", 0), 0u) << c.expression;
  EXPECT_EQ(c.spec.rfind("learned_traction_correction:abs_force_sign_speed=", 0), 0u) << c.spec;
  EXPECT_NO_THROW(vehicle::make_effect(c.spec));
}

TEST(Discovery, JsonCarriesTheEquationCoefficientsAndIntervals) {
  std::mt19937_64 rng = fresh_rng();
  const RegressionData d = synthetic(rng, {{"force", -1e-7}}, 0.002);
  DiscoveredCorrection c = fit_correction({CorrectionKind::actuator, "tilt"}, d);
  ASSERT_EQ(c.terms.size(), 1u) << c.expression;
  const auto j = correction_json(c);
  EXPECT_EQ(j["target"], "tilt speed");
  EXPECT_EQ(j["coefficients"][0]["feature"], "force");
  EXPECT_EQ(j["coefficients"][0]["unit"], "(m/s)/(N)");
  const double lo = j["coefficients"][0]["ci95"][0], hi = j["coefficients"][0]["ci95"][1];
  EXPECT_LT(lo, hi);
  EXPECT_EQ(j["features"].size(), vehicle::correction_features(CorrectionKind::actuator).size());
  EXPECT_FALSE(j.contains("held_out_error_cut"));  // not simulated yet
  EXPECT_EQ(j["effect"], c.spec);
}

}  // namespace
}  // namespace talus::sim2real
