// Discovery of a term outside the candidate list (issue 17, docs/discovery.md): when the candidate
// effects leave a residual beyond noise, fit a sparse model of it in the dynamics of the quantity
// it disturbs, as a learned correction (vehicle/learned_correction.hpp) the simulator then runs.
//
// For each target (the drive, lift and tilt speeds; the sensor channels that show an excess of
// their own) and the runs it is fitted on:
//  1. regression data: per measured sample, what the correction must add (an actuator: the
//     measured achieved speed minus the simulated one, both central differences over
//     ±kRateHalfWindow samples of the stroke, or the drive's speed reading; a sensor: the
//     measured reading minus the simulated one) and the dictionary's features, evaluated from the
//     measured state for an actuator (its command from the operator's inputs) and from the
//     simulated readings for a sensor (the simulation stands for the truth the sensor distorts);
//     a cylinder's features are their means over the central difference's window, as its
//     residual is the mean of a speed over that window
//  2. sparse regression by sequential thresholding one term at a time (backward elimination):
//     least squares on all features (scaled to unit RMS), then repeatedly the term whose removal
//     raises the residual least is dropped, giving one model per number of terms. Removing one
//     term at a time, by the loss of fit rather than by the size of its coefficient as SINDy's
//     STLSQ does (Brunton, Proctor & Kutz 2016), keeps one of a group of nearly collinear
//     features (a command that takes two values is collinear with its sign and its square)
//     instead of keeping them all with large cancelling coefficients
//  3. the sparsity by blocked cross-validation: each run cut into kFolds contiguous blocks, each
//     block predicted by the path fitted on the others; the fewest terms whose held-out error is
//     within kOneSeRule of the least, at most kMaxTerms; that many terms from the path, then
//     improved by exchanging one term for one outside while that lowers the residual
//  4. the coefficients' 95 % intervals from ordinary least squares on the support, the variance
//     inflated for the residual's autocorrelation (by its integrated autocorrelation time τ,
//     n_eff = n / τ: integrated_autocorrelation_time in sim2real/residuals.hpp)
// diagnose() then simulates the calibration and held-out runs with each target's correction and
// keeps the best only if it removes at least half of the excess left on the held-out runs.
#pragma once
#include <Eigen/Dense>
#include <cstddef>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "sim2real/measured.hpp"
#include "sim2real/timeseries.hpp"
#include "vehicle/learned_correction.hpp"
#include "vehicle/machine.hpp"

namespace talus::sim2real {

// samples either side of a central difference (±0.05 s at 100 Hz): the stroke sensor's noise
// (1 mm) becomes 0.014 m/s of speed, a tenth of the commanded lift speeds
inline constexpr int kRateHalfWindow = 5;
// blocks per run in the cross-validation
inline constexpr int kFolds = 5;
// a model with more terms is not an explanation a person can check
inline constexpr int kMaxTerms = 3;
// the model with the fewest terms whose held-out error is within this factor of the least is chosen
inline constexpr double kOneSeRule = 1.05;
// two features whose values over the regression's rows correlate this closely are the same
// function of these data: on load-carry the lift's sign(u) and f_lift·sign(u) correlate at 0.993-
// 0.996 (one speed up, one down, a near-constant load), which no fit can separate
inline constexpr double kAliasCorrelation = 0.99;
// a correction must cut the held-out mean-square residual by this share to be simulated at all
inline constexpr double kMinRegressionGain = 0.05;

// a quantity a learned correction may act on
struct DiscoveryTarget {
  vehicle::CorrectionKind kind = vehicle::CorrectionKind::actuator;
  std::string target;         // "drive", "lift", "tilt", "traction", or a sensor channel's name
  std::string label() const;  // "lift speed", "tractive force", "f_traction reading"
  // learned_actuator_correction, learned_traction_correction or learned_sensor_correction
  std::string effect_name() const;
  std::string option() const;  // "actuator=lift", "" (the traction's) or "channel=f_traction"
};

// the actuator targets, the tractive force, then the sensor channels given (those with an excess
// of their own)
std::vector<DiscoveryTarget> discovery_targets(const std::vector<std::string>& sensor_channels);

// the largest target speed the machine's actuator follows [m/s] (a cylinder's max_speed, the
// driveline's top speed): commands beyond it are clipped, so a correction that brings the
// command back within it does less than its size. Infinity for the traction and a sensor target
double command_limit(const DiscoveryTarget& target, const vehicle::MachineDescription& machine);

// the regression problem of one target over some runs (measured[i] against simulated[i]); for an
// actuator, `limit` is its command_limit: the residual is counted on the command's scale,
// (measured − simulated speed) − (u − clip(u)), so that clip(u + Δu) reproduces the measured speed
// where the baseline's command was clipped
struct RegressionData {
  Eigen::MatrixXd features;  // rows: samples; columns: the kind's dictionary, in its order
  Eigen::VectorXd residual;  // what the correction must add, in the target's unit
  std::vector<int> fold;     // each row's block, 0 .. kFolds − 1
  std::vector<int> run;      // each row's run, an index into the runs given
};
RegressionData regression_data(const DiscoveryTarget& target,
                               const std::vector<const MeasuredRun*>& measured,
                               const std::vector<const Run*>& simulated, double limit);

// the backward-elimination path: path[m] holds the m features (column indices) of the m-term
// model, m = 0 .. the number of features that are not zero throughout
std::vector<std::vector<Eigen::Index>> elimination_path(const Eigen::MatrixXd& x,
                                                        const Eigen::VectorXd& y);

// one discovered term with its 95 % interval
struct DiscoveredTerm {
  std::string feature;     // the dictionary's name (the effect's parameter)
  std::string expression;  // the feature in the target's symbols, "|f_lift|·u_lift"
  std::string unit;        // the coefficient's unit
  double coefficient = 0.0;
  double half_width = 0.0;  // the 95 % interval is coefficient ± half_width
  // features the fitted data cannot tell from this one (|correlation| ≥ kAliasCorrelation over the
  // regression's rows): as good a term on these runs, a different physics elsewhere
  std::vector<std::string> aliases, alias_expressions;
};

// a target's sparse model, before and after it is simulated
struct DiscoveredCorrection {
  DiscoveryTarget target;
  std::vector<DiscoveredTerm> terms;       // empty: nothing beats no correction on held-out blocks
  double cv_mse = 0.0, cv_mse_none = 0.0;  // held-out blocks' mean-square residual with and without
  int samples = 0;
  std::string spec;        // the effect, as `--effect` reads it
  std::string expression;  // "Δu_lift = −2.1e−07 (±1.1e−08) (m/s)/(N)·f_lift"
  // filled by diagnose() when simulated
  bool simulated = false;
  bool refined = false;  // coefficients refitted by the simulations' likelihood (their intervals
                         // stay the regression's)
  double excess_calibration = 0.0, excess_validation = 0.0, explained = 0.0;
  std::string explained_on;
  std::vector<std::string> channels;  // those whose excess it lowers
  double score = 0.0;
};

// steps 2–4 on the data: the sparse model and its intervals (terms empty when no model of up to
// kMaxTerms terms cuts the held-out error by kMinRegressionGain)
DiscoveredCorrection fit_correction(const DiscoveryTarget& target, const RegressionData& data);

// the correction's spec and expression from its target and terms (after its coefficients change)
void describe_correction(DiscoveredCorrection& c);

// the correction's JSON for `talus diagnose --json` ("discovered")
nlohmann::json correction_json(const DiscoveredCorrection& c);

}  // namespace talus::sim2real
