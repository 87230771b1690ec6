// The sim-to-real loop (issue 6, SPEC §6; docs/sim2real.md): given measured runs, simulate their
// inputs with the baseline model, measure the residual per channel and phase against the data's
// own noise (sim2real/residuals.hpp; with a pile ensemble, also against the simulation's own
// spread between piles, which the replay's run carries, so every excess and likelihood below
// uses it without a second code path), and look for the effect the model lacks among candidates
// (the built-in effects, vehicle/effect.hpp, and any a plug-in brings).
//
// One round of the search:
//  1. signature screen: a candidate that can change only some channels (a sensor's bias or delay,
//     the wheel-slip speed reading) can at most remove the excess of those channels; when that
//     bound is below the share a winner must explain, or the channel it acts on shows no excess
//     of its own, it is not simulated at all (for the members of a set searched where too few
//     singles pass, and for a set of three's third, step 5, the bound is the share one member of
//     a set must explain, kMemberShare)
//  2. coarse scan: each remaining candidate at kScanPoints values across its range (and towards
//     zero on a range that starts there), a 2-D grid for two parameters, a Halton design for three
//     or more, on the calibration runs; a candidate whose simulation throws is reported and skipped
//  3. fit: the best kFitted candidates' parameters from their best scan point with NLopt's BOBYQA
//     (derivative free, bounded; Powell 2009) in a box normalised to [0, 1] (logarithmic for
//     ranges spanning a decade or more), at most kFitEvaluations simulations for one parameter and
//     until convergence for more (a guard of 100 per parameter); the fit
//     maximises the likelihood (Residuals::log_ratio), the scan and the decisions use the excess.
//     One parameter: the window between the best scan point's neighbours is sampled first
//     (kWindowPointsPerSide more on each side) and a parabola fitted to the likelihood there
//     (sim2real/response_surface.hpp); where the samples have more than one local minimum (a
//     chaotic dig) its vertex is the estimate, else BOBYQA starts from it
//  4. validation: each fitted candidate on the held-out runs; its score is the validation excess
//     plus kParameterPenalty per fitted parameter, so a richer effect must earn its parameters
//     (the calibration excess when the held-out runs show nothing to explain, see 5)
//  5. decision: the best-scoring candidate is added when it removes at least kMinExplained of the
//     validation excess that is left. Else pairs: each of the kSetBases best singles is taken
//     provisionally, a second candidate searched on top of it (screen, scan, fit), and the two
//     refitted jointly from there and validated as one model (both effects' parameters
//     penalised); the best pair is added when it removes kMinExplained together. Else, when the
//     best pair removes at least two thirds of kMinExplained, sets of three, the same way on top
//     of each of the kSetBases best pairs (five or more effects of comparable size share the
//     residual: of five, a pair removes two fifths), the third screened by kMemberShare. With
//     fewer than kSetBases singles to build on, the candidates the screen left out whose channels
//     hold kMemberShare are scanned and fitted as singles first. Else the round adds nothing.
//     Held-out runs that show no
//     excess (an effect that needs a manoeuvre they lack) cannot confirm a candidate, only refute
//     it: then the share explained is the calibration runs', if the candidate keeps the held-out
//     runs within noise
// Rounds repeat (each fits one more effect, or a set, on top of those added, which keep their
// values) until every run's excess is within noise, nothing qualifies, or max_effects rounds have
// added. "Unexplained"
// means some run keeps an excess beyond noise at the end.
// Sensitivity (issue 17): "unexplained" must mean a missing effect, not the simulation's
// sensitivity to the fitted parameters. After a round adds an effect (and after the discovery
// adds one), every run still beyond noise is judged again against the spread the simulation
// shows for parameter changes within the fit's uncertainty: the covariance of the found effects'
// fitted parameters from the curvature of the calibration runs' log-likelihood (central
// differences at kSensitivityStep in the normalised box; eigenvalues held to [1/step²,
// 1/kFitTolerance²]), each such run simulated at the points of a two-level orthogonal design
// around the fit scaled by that covariance (2^⌈log2(p + 1)⌉ points for p parameters), and their
// mean square departure from the fitted run added to the residual's variance
// (RunSpread::sensitivity, one law: compute_residuals). The rounds go on, the discovery runs and
// the verdict is given on that judgement. Its cost: p(p + 1) simulations per calibration run for
// the curvature, and the design's points per run judged.
// Discovery (issue 17, sim2real/discovery.hpp): when an excess beyond noise remains after the
// rounds (or when asked), a sparse learned correction is fitted per target on the calibration
// runs, each simulated on all runs, and the best is added when it removes at least kMinExplained
// of the excess left (on the held-out runs, as a candidate's share); else the diagnosis stays
// "unexplained" with the residual's signature.
#pragma once
#include <cstddef>
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "sim2real/discovery.hpp"
#include "sim2real/measured.hpp"
#include "sim2real/replay.hpp"
#include "sim2real/residuals.hpp"
#include "sim2real/table.hpp"
#include "vehicle/effect_plugin.hpp"

namespace talus::sim2real {

// values along one parameter in the coarse scan (2 parameters: 5 x 5)
inline constexpr int kScanPoints = 9;
inline constexpr int kScanPointsPerAxis2 = 5;
// candidates fitted per round, and the simulations each fit may use
inline constexpr int kFitted = 3;
// the sets each taken as the base of a larger one when none explains enough: singles as the first
// of a pair, pairs as the first two of a set of three
inline constexpr int kSetBases = 2;
// the largest set of candidates fitted jointly (a pair, then three)
inline constexpr int kLargestSet = 3;
inline constexpr int kFitEvaluations = 24;
// a one-parameter fit samples the window between the best scan point's neighbours at this many
// more points on each side of it (sim2real/response_surface.hpp): with the three scan points
// there, nine samples at a quarter of the scan's spacing
inline constexpr int kWindowPointsPerSide = 3;
// a winner must remove this share of the excess left (on the validation runs)
inline constexpr double kMinExplained = 0.5;
// the share of the excess a candidate's channels must hold to be searched as a member of a set:
// of a set that removes kMinExplained, some member removes at least kMinExplained / kLargestSet
inline constexpr double kMemberShare = kMinExplained / kLargestSet;
// the excess one fitted parameter must pay for, per run (in the units of Residuals::excess: one
// channel-phase cell whose mean-square residual is e^0.2 = 1.22 times the noise allowance)
inline constexpr double kParameterPenalty = 0.2;
// the step of the likelihood's central differences for the sensitivity's curvature, in the box
// normalised to [0, 1]: ten times the fit's stopping tolerance (1e-3), so the differences measure
// the likelihood rather than the optimiser's last step, and a hundredth of the box, so they stay
// near the fit. A direction the likelihood does not curve up in within it is taken as uncertain by
// this step (the smallest honest statement: the data do not pin it down within the probe)
inline constexpr double kSensitivityStep = 0.01;
// a run's excess below this counts as within noise (one cell whose mean-square residual is
// e^0.5 = 1.65 times the allowance, or a few cells barely above it)
inline constexpr double kSignificantExcess = 0.5;

// one candidate: an effect, with its channel option fixed for channel-bound effects
struct Candidate {
  std::string effect;                 // built-in or plug-in effect name
  std::string channel;                // the value of its option "channel", or empty
  // channels it can change, the one it acts on first (power follows it); empty: all (it acts on
  // the machine)
  std::vector<std::size_t> signature;
  bool needs_particles = false;       // acts on the soil only (soil_cohesion)
  std::string label() const;          // "hydraulic_lag", "sensor_bias[f_lift]"
};

// the built-in effects, channel-bound ones once per channel, then every effect of the plug-ins
std::vector<Candidate> candidate_set(const vehicle::EffectPlugins& plugins);
// those of `all` whose labels `labels` names, in `all`'s order (all of them for no labels);
// InputError naming --candidates and the labels there are for one that names none
std::vector<Candidate> chosen_candidates(const std::vector<Candidate>& all,
                                         const std::vector<std::string>& labels);

// the coarse scan's points of a candidate in its box normalised to [0, 1] per parameter (step 2
// above): what a parameter's normalised value means is make_candidate's mapping, linear, or
// logarithmic for ranges that exclude zero and span a decade
std::vector<std::vector<double>> candidate_scan_points(const Candidate& c,
                                                       const vehicle::EffectPlugins& plugins);

struct DiagnoseOptions {
  ReplayOptions replay;
  int max_effects = 2;
  // how many of the runs (the last ones) are held out for validation; -1: a third, at least one
  // when there are two or more runs; with one run the fit is validated on the run it was fitted to
  int validation_runs = -1;
  vehicle::EffectPlugins plugins;  // their effects join the candidates
  // the candidates to search, by label ("engine_power_sharing", "sensor_bias[f_lift]"); empty:
  // every built-in and plug-in effect. For a recovery where the effect's form is known or
  // suspected, and for a loop that would otherwise cost hours of pile digs
  std::vector<std::string> candidates;
  // run the discovery even when the candidates leave nothing beyond noise
  bool discover = false;
  // simulations of the machine alone run at once (0: the host's hardware threads); runs on a pile
  // share the one OpenCL device and run one at a time. Any count gives the same diagnosis, bit
  // for bit: the parallel loops keep their results by index (host/parallel.hpp)
  int threads = 0;
};

struct FittedEffect {
  Candidate candidate;
  nlohmann::json effect;       // {"name": ..., "params": {...}} as the effect reports itself
  std::string spec;            // NAME:key=value,... (talus run --effect)
  int parameters = 0;          // fitted parameters
  double excess_calibration = 0.0;  // mean per calibration run, with this effect added
  double excess_validation = 0.0;   // mean per validation run
  double explained = 0.0;      // share of the excess left that it removes, on the runs below
  // "validation"; or "calibration" when the held-out runs had nothing beyond noise to explain (the
  // effect does not show in them) and it kept them within noise
  std::string explained_on;
  double score = 0.0;          // excess_validation + penalty
  int simulations = 0;
  // the other members' candidate labels when it was fitted and added as one of a set (a pair or
  // three): the shares above are then the set's, together
  std::vector<std::string> fitted_with;
  std::vector<double> x;  // its parameters in the box normalised to [0, 1] (the fit's variables)
  // one parameter: the window's samples' local minima (0: no window) and their scatter about
  // their parabola against its rise (LocalParabola::roughness; NaN without a window, infinite
  // where the parabola has no minimum; JSON null for both), and whether the estimate is the
  // parabola's vertex (WindowTrend::rough) or the optimiser's
  int local_minima = 0;
  double roughness = std::numeric_limits<double>::quiet_NaN();
  bool trend_estimate = false;
};

// the items joined by `between`, the last two by `last` ("a, b and c": ", ", " and "), for the
// notes and the report
std::string listed(const std::vector<std::string>& items, const std::string& between,
                   const std::string& last);

// two or three candidates fitted jointly (when no smaller set explains enough): a smaller set
// taken provisionally, one more candidate searched on top of it, all refitted together and
// validated as one model
struct FittedSet {
  // in the order they were taken, each with the joint fit's values
  std::vector<FittedEffect> members;
  double excess_calibration = 0.0, excess_validation = 0.0;
  double explained = 0.0;  // share of the excess left before the set that the set removes
  std::string explained_on;
  double score = 0.0;  // as a single's, with every member's parameters penalised

  // the members' specs, in order
  std::vector<std::string> specs() const {
    std::vector<std::string> out;
    for (const auto& m : members) out.push_back(m.spec);
    return out;
  }
};

// the effects found refitted together after a round added one (greedy forward selection fits each
// with the earlier ones fixed, so an earlier fit may have taken up part of what a later effect
// explains): kept only if it fits the calibration runs better and leaves the held-out runs no worse
struct JointRefit {
  std::vector<std::string> before, after;  // the found effects' specs (after: as refitted)
  double excess_calibration_before = 0.0, excess_calibration_after = 0.0;
  double excess_validation_before = 0.0, excess_validation_after = 0.0;
  double log_ratio_before = 0.0,
         log_ratio_after = 0.0;  // calibration runs' mean, the fit's objective
  bool kept = false;
  int simulations = 0;
};

// The chaos check of an addition whose share was counted on the calibration runs of pile data.
// There the held-out runs were within noise and cannot refuse it, and a pile dig is chaotic: the
// scans and fits try tens of parameter values, each a new realisation of the digs, and the best of
// them can fit the calibration runs by chance (a 2 ms hydraulic lag "explained" effect-free G400
// data, docs/sim2real.md). So the calibration runs are simulated again on a second ensemble of
// piles, disjoint from the model's (Replay::simulate_reference), without and with the addition:
// the addition must explain kMinExplained of the excess there too, and nothing when the reference
// leaves no excess beyond noise (what it explained was the first ensemble's realisation)
struct ChaosCheck {
  std::vector<std::string> effects;  // the addition's specs: one effect, or a set's two or three
  double excess_before = 0.0;        // the calibration runs' mean excess on the reference
  double excess_with = 0.0;          // the same with the addition
  double explained = 0.0;            // (before - with) / before; 0 when before is within noise
  bool passed = false;               // explained >= kMinExplained
  int simulations = 0;
};

struct DiagnosisRound {
  double excess_before = 0.0;            // mean validation excess per run before the round
  std::vector<std::string> screened_out; // labels the signature screen skipped
  // candidates whose simulation threw (label, message): reported and skipped
  std::vector<std::pair<std::string, std::string>> failed;
  std::vector<FittedEffect> fitted;      // best score first
  std::vector<FittedSet> pairs;          // when no single one explains enough; best score first
  std::vector<FittedSet> triples;        // when no pair explains enough either; best score first
  bool added = false;  // fitted[0] was added, or pairs[0]'s two effects, or triples[0]'s three
  // the chaos checks of the additions tried (pile data, share counted on the calibration runs)
  std::vector<ChaosCheck> chaos_checks;
  // after an addition that leaves two or more effects with fitted parameters
  std::optional<JointRefit> refit;
};

// one fitted parameter in a sensitivity judgement: its value and the fit's uncertainty
struct SensitivityParameter {
  std::string effect;     // the candidate's label
  std::string parameter;  // the parameter's name
  std::string unit;
  double value = 0.0;  // fitted
  // one standard error in the normalised box (sqrt of the covariance's diagonal), and the values
  // at the fit ∓ that error (clamped to the range; asymmetric on a logarithmic range)
  double standard_error_box = 0.0;
  double low = 0.0, high = 0.0;
};

// one run's judgement against the sensitivity spread
struct SensitivityRun {
  bool used = false;
  std::string reason;                              // why not, when not used
  int simulations = 0;                             // the design's simulations of this run
  double excess_without = 0.0, excess_with = 0.0;  // the run's excess without and with it
};

// the judgement after a round or the discovery added an effect (see the header comment)
struct SensitivityJudgement {
  std::string after;  // "round 1", "discovery", or "end" (nothing was judged before the verdict)
  bool used = false;
  std::string reason;  // why not, when not used
  std::vector<SensitivityParameter> parameters;
  double step = kSensitivityStep;
  // whether the log-likelihood's Hessian was positive definite with every eigenvalue within
  // [1/step², 1/kFitTolerance²] (else they were held there)
  bool curvature_in_range = false;
  int curvature_simulations = 0;     // of the calibration runs, for the Hessian
  // the calibration runs' effective samples over their samples at the fit (Σ n_eff / Σ n over
  // their cells, ResidualCell::effective_samples): the share of the likelihood's samples the
  // curvature counted, 1 where the residual is white; null in the JSON where no curvature was
  // measured (the judgement skipped)
  double effective_sample_share = 1.0;
  int design_points = 0;             // simulations per run judged
  std::vector<SensitivityRun> runs;  // per run (all of them)
  int simulations() const;           // the curvature's and the design's
};

struct Diagnosis {
  std::vector<std::string> runs;          // directories, in the given order
  std::vector<std::size_t> calibration, validation;  // indices into runs
  // per run; after: as the verdict judged them (with the sensitivity spread where it was used)
  std::vector<Residuals> residuals_before, residuals_after;
  // the simulations behind them, labelled "<scenario>-baseline" and "<scenario>-with-effects"
  std::vector<Run> simulated_before, simulated_after;
  std::vector<TableRow> error_before, error_after;            // per run (paper's seven metrics)
  std::vector<DiagnosisRound> rounds;
  std::vector<std::string> candidates;    // the labels searched (DiagnoseOptions::candidates)
  std::vector<FittedEffect> found;        // the effects added, in order
  double excess_before = 0.0, excess_after = 0.0;  // mean per run, all runs
  bool unexplained = false;               // some run keeps an excess beyond noise
  std::vector<std::optional<double>> scan_rms_m;   // per run (pile scenarios)
  // piles each pile run's simulations dug and averaged (ReplayOptions::pile_ensemble; 1 without
  // a pile), per run
  std::vector<int> piles;
  // discovery: whether it ran, every target's correction (simulated ones with their shares), and
  // the one added (also the last of `found`), if any
  bool discovery_ran = false;
  std::vector<DiscoveredCorrection> discovery_tried;
  std::optional<DiscoveredCorrection> discovered;
  // the chaos check of the correction about to be added (pile data, share on the calibration runs)
  std::vector<ChaosCheck> discovery_chaos_checks;
  // the sensitivity judgements in order; the last judged the verdict (sensitivity.back().runs)
  std::vector<SensitivityJudgement> sensitivity;
  int simulations = 0;
  double wall_s = 0.0;
};

// progress notes (one line each) go to `note` when given
Diagnosis diagnose(const std::vector<MeasuredRun>& runs, const DiagnoseOptions& options, Device* device,
                   const std::function<void(const std::string&)>& note = {});

// the mean row of per-run error rows: each metric's mean absolute value, and the mean of the means
TableRow mean_row(const std::vector<TableRow>& rows, const std::string& name);

// the JSON of `talus diagnose --json`: effects_found [{name, params}], error_before, error_after
// (E_x .. E_W and mean, averaged over runs, with per-run rows), unexplained, discovered (null, or
// the correction added: expression, coefficients with intervals, features, held_out_error_cut,
// and error_before/error_after over the held-out runs), and the details
nlohmann::json diagnosis_json(const Diagnosis& d);

}  // namespace talus::sim2real
