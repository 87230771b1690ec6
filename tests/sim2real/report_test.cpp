// sim2real/report: the diagnosis in markdown, from a diagnosis put together by hand around the
// synthetic run pair whose residuals are known (tests/sim2real/synthetic_runs.hpp)
#include "sim2real/report.hpp"

#include <gtest/gtest.h>

#include "sim2real/residuals.hpp"
#include "tests/sim2real/synthetic_runs.hpp"

namespace talus::sim2real {
namespace {

// the synthetic pair: the measured reference and the simulated run
MeasuredRun reference_run() {
  MeasuredRun measured;
  measured.run.series = test::reference_series();
  measured.run.summary = test::reference_summary();
  return measured;
}
sim2real::Run simulated_run() {
  sim2real::Run simulated;
  simulated.series = test::simulated_series();
  simulated.summary = test::simulated_summary();
  return simulated;
}

// a one-run diagnosis: the measured reference, the simulated run's residual, nothing found
Diagnosis one_run_diagnosis(const MeasuredRun& measured, const Run& simulated) {
  Diagnosis d;
  d.runs = {"runs/fb35"};
  d.calibration = d.validation = {0};
  d.residuals_before = {compute_residuals(simulated, measured.run, noise_sigmas(measured.run.series))};
  d.simulated_before = {simulated};
  d.error_before = {{"FB35", {0.05, 0.05, 0.0, 0.1, 0.2, -0.1, 0.1}, 0.6 / 7.0}};
  d.error_after = d.error_before;
  d.scan_rms_m = {0.3};
  d.unexplained = true;
  return d;
}

// the run's section names its roles, the largest residual cells (on noise-free data the bucket
// tip's 3 cm in every phase leads, then the traction that is wildly off outside the dig), a scan
// far from the simulated pile's; the effects say UNEXPLAINED; both tables end with the mean over
// runs
TEST(Report, NamesTheResidualTheScanWarningAndTheVerdict) {
  const MeasuredRun measured = reference_run();
  const sim2real::Run simulated = simulated_run();
  const Diagnosis d = one_run_diagnosis(measured, simulated);
  const std::string report = diagnosis_report(d, {measured});
  for (const char* part : {"# talus diagnose", "(runs/fb35; calibration and validation)", "| bucket_tip_z | dig |",
                           "| f_traction | approach |", "Warning: the measured pile scan lies 0.3 m", "UNEXPLAINED.",
                           "## Error before", "## Error after", "mean over runs"})
    EXPECT_NE(report.find(part), std::string::npos) << part << "\n" << report;
  // at most kSignatureCells rows of residual cells
  const std::string signature = residual_signature(d.residuals_before[0], measured.run, simulated);
  std::size_t rows = 0;
  for (std::size_t at = signature.find("\n|"); at != std::string::npos; at = signature.find("\n|", at + 1)) ++rows;
  EXPECT_EQ(rows, 1 + kSignatureCells);  // the separator line and the cells
}

// an effect whose value is the trend's minimum over a rough window says so beside it; one the
// optimiser found says nothing more
TEST(Report, SaysWhenAnEffectsValueIsTheTrendOfARoughWindow) {
  const MeasuredRun measured = reference_run();
  Diagnosis d = one_run_diagnosis(measured, simulated_run());
  FittedEffect f;
  f.spec = "cylinder_friction:force=12100";
  f.explained = 0.6;
  f.explained_on = "validation";
  f.local_minima = 1;
  d.found = {f};
  EXPECT_EQ(diagnosis_report(d, {measured}).find("local minima"), std::string::npos);
  d.found[0].local_minima = 3;
  d.found[0].trend_estimate = true;
  const std::string report = diagnosis_report(d, {measured});
  EXPECT_NE(report.find("- cylinder_friction:force=12100 (explains 60 % of the excess of the "
                        "validation runs); its value is the minimum of the likelihood's trend over "
                        "the fit's window, whose samples had 3 local minima"),
            std::string::npos)
      << report;
}

// an effect added as one of a set says which others it was fitted with, and that the share is
// theirs together
TEST(Report, SaysWhichEffectsASetsMemberWasFittedWith) {
  const MeasuredRun measured = reference_run();
  Diagnosis d = one_run_diagnosis(measured, simulated_run());
  FittedEffect f;
  f.spec = "sensor_bias:channel=f_lift,bias=20000";
  f.explained = 0.6;
  f.explained_on = "validation";
  f.fitted_with = {"sensor_bias[f_tilt]", "sensor_bias[v_drive]"};
  d.found = {f};
  const std::string report = diagnosis_report(d, {measured});
  EXPECT_NE(report.find("- sensor_bias:channel=f_lift,bias=20000 (fitted with sensor_bias[f_tilt] "
                        "and sensor_bias[v_drive], which together explain 60 % of the excess of "
                        "the validation runs)"),
            std::string::npos)
      << report;
}

// a residual judged against a simulation's spread says so under its table, with the spread's
// share per channel (and its degrees of freedom, where estimated); one judged against the sensor
// noise alone says nothing more
TEST(Report, SaysWhenTheSimulationsSpreadJudgedTheResidual) {
  const MeasuredRun measured = reference_run();
  sim2real::Run simulated = simulated_run();
  const std::vector<double> sigma(kChannelCount, 1e3);
  EXPECT_EQ(spread_note(compute_residuals(simulated, measured.run, sigma)), "");
  simulated.spread = RunSpread{3, {}, 0, {}, {}, {}, {}, {}};
  simulated.spread->variance[Channel::t] = simulated.series[Channel::t];
  for (std::size_t c = 1; c < kChannelCount; ++c)
    simulated.spread->variance.columns[c].assign(simulated.series.size(), c == 1 ? 4e6 : 0.0);
  const std::string note = spread_note(compute_residuals(simulated, measured.run, sigma));
  // f_lift's share: (4/3) 4e6 / (1e6 + (4/3) 4e6) = 16/19 = 0.84
  for (const char* part : {"own spread over 3 piles", "f_lift 0.84", "f_tilt 0.00"})
    EXPECT_NE(note.find(part), std::string::npos) << part << "\n" << note;
  EXPECT_EQ(note.find("Student"), std::string::npos) << note;
  // an estimated variance: its degrees of freedom per channel
  simulated.spread->variance_dof.assign(kChannelCount, 2.0);
  const std::string t_note = spread_note(compute_residuals(simulated, measured.run, sigma));
  for (const char* part : {"Student's t", "f_lift 2.0", "power 2.0"})
    EXPECT_NE(t_note.find(part), std::string::npos) << part << "\n" << t_note;
}

// a joint refit in a line: kept or not, the objective and the held-out excess, each effect's spec
// before and after; nothing without one
TEST(Report, SaysInALineWhatTheJointRefitChanged) {
  Diagnosis d;
  d.rounds.resize(2);
  EXPECT_EQ(refit_note(d), "");
  JointRefit r;
  r.before = {"cylinder_friction:force=25000", "sensor_bias:channel=f_lift,bias=21884"};
  r.after = {"cylinder_friction:force=19973", "sensor_bias:channel=f_lift,bias=24835"};
  r.log_ratio_before = 2.31;
  r.log_ratio_after = -0.346;
  r.excess_validation_before = 1.43;
  r.excess_validation_after = 0.0;
  r.kept = true;
  r.simulations = 19;
  d.rounds[1].refit = r;
  const std::string note = refit_note(d);
  for (const char* part : {"Refitted together after round 2 (kept", "log-ratio 2.31 -> -0.346",
                           "held-out excess 1.43 -> 0", "19 simulations",
                           "cylinder_friction:force=25000 -> cylinder_friction:force=19973",
                           "bias=21884 -> sensor_bias:channel=f_lift,bias=24835"})
    EXPECT_NE(note.find(part), std::string::npos) << part << "\n" << note;
}

// a chaos check in a line: where, the addition, the reference's calibration excess without and
// with it, its share, held or refused; nothing without one
TEST(Report, SaysInALineWhatTheChaosCheckFound) {
  Diagnosis d;
  d.rounds.resize(1);
  EXPECT_EQ(chaos_check_note(d), "");
  ChaosCheck c;
  c.effects = {"hydraulic_lag:time_constant=0.002"};
  c.excess_before = 0.31;
  c.excess_with = 0.29;
  c.explained = 0.0;
  c.passed = false;
  d.rounds[0].chaos_checks.push_back(c);
  ChaosCheck discovery = c;
  discovery.effects = {"learned_correction:target=lift"};
  discovery.excess_before = 2.0;
  discovery.excess_with = 0.5;
  discovery.explained = 0.75;
  discovery.passed = true;
  d.discovery_chaos_checks.push_back(discovery);
  const std::string note = chaos_check_note(d);
  for (const char* part :
       {"Chaos check in round 1", "hydraulic_lag:time_constant=0.002",
        "calibration excess 0.31 -> 0.29", "refused", "Chaos check of the discovery",
        "learned_correction:target=lift", "2 -> 0.5", "explains 75 %", "holds"})
    EXPECT_NE(note.find(part), std::string::npos) << part << "\n" << note;
}

// the verdict's sensitivity judgement in one line: the parameters within one standard error, the
// simulations, the judged runs' excess without and with it; or why it was not used
TEST(Report, SaysInALineWhetherTheSensitivitySpreadJudgedTheVerdict) {
  Diagnosis d;
  EXPECT_EQ(sensitivity_note(d), "");
  SensitivityJudgement j;
  j.after = "round 1";
  j.used = true;
  j.parameters = {{"soil_cohesion", "cohesion", "Pa", 5012.0, 0.004, 4950.0, 5070.0}};
  j.curvature_simulations = 4;
  j.effective_sample_share = 0.031;
  j.design_points = 2;
  j.runs = {{true, "", 2, 2.5, 0.12}, {false, "within noise without it", 0, 0.3, 0.3}};
  d.sensitivity = {j};
  const std::string used = sensitivity_note(d);
  for (const char* part :
       {"Sensitivity spread (round 1)", "soil_cohesion cohesion 5012 [4950, 5070] Pa",
        "2 simulations per run judged, 4 for the curvature",
        "counted the calibration runs' samples as 0.031 of their number", "run 0 2.5 -> 0.12"})
    EXPECT_NE(used.find(part), std::string::npos) << part << "\n" << used;
  EXPECT_EQ(used.find("run 1"), std::string::npos) << used;  // not judged: within noise
  j.used = false;
  j.reason = "no effect was added, so no parameter was fitted";
  d.sensitivity = {j};
  EXPECT_NE(sensitivity_note(d).find("not used (round 1): no effect was added"), std::string::npos)
      << sensitivity_note(d);
}

// the error table's last row is the mean of the absolute values over the runs
TEST(Report, ErrorTableEndsWithTheMeanRow) {
  const std::vector<TableRow> rows = {{"a", {0.1, 0.2, 0.3, 0.4, 0.5, -0.2, 0.1}, 0.3},
                                      {"b", {0.3, 0.2, 0.1, 0.0, 0.1, 0.2, -0.3}, 0.1}};
  const std::vector<TableRow> table = error_table(rows);
  ASSERT_EQ(table.size(), 3u);
  EXPECT_EQ(table.back().name, "mean over runs");
  EXPECT_DOUBLE_EQ(table.back().e.e_m, 0.2);
}

}  // namespace
}  // namespace talus::sim2real
