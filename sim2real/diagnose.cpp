#include "sim2real/diagnose.hpp"

#include <nlopt.h>

#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <bitset>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>

#include "host/error.hpp"
#include "host/interrupt.hpp"
#include "host/parallel.hpp"
#include "sim2real/response_surface.hpp"

namespace talus::sim2real {

std::string listed(const std::vector<std::string>& items, const std::string& between,
                   const std::string& last) {
  std::string out;
  for (std::size_t k = 0; k < items.size(); ++k)
    out += (k == 0 ? "" : k + 1 == items.size() ? last : between) + items[k];
  return out;
}

namespace {

// the power channel follows a changed force or speed reading (vehicle/effect.hpp), so a sensor
// effect's signature always includes it
constexpr std::size_t kPowerChannel = static_cast<std::size_t>(Channel::power);
// a parameter whose range spans this ratio or more (and excludes zero) is searched in log scale
constexpr double kLogScaleRatio = 10.0;
// the scan's extra points towards zero on a range that starts at zero (scan_axis)
constexpr int kNearZeroPoints = 3;
// a fit of two or more parameters runs until it converges (minimise), within this many
// simulations per parameter (a guard, not the stop: BOBYQA converges in tens)
constexpr int kFitEvaluationsPerParameter = 100;
// BOBYQA stops when a step in the normalised box is below this (0.1 % of the range)
constexpr double kFitTolerance = 1e-3;
// a fit of two or more parameters has converged when a restart of BOBYQA from its end point
// lowers the likelihood's objective (a mean of ln(MSE / sigma^2) over the cells) by less than
// this: a thousandth of a log, a 0.1 % change of the mean square error
constexpr double kFitImprovement = 1e-3;
// the discovery tries the sensor readings with the largest excess of their own, at most this many
constexpr std::size_t kDiscoverySensorTargets = 3;
// a channel counts as touched by a correction when its excess falls by this much per run
constexpr double kDiscoveryChannelCut = 0.2;
// the refinement's first step, in its box normalised to [0, 1]: a tenth of the box
constexpr double kDiscoveryRefineStep = 0.1;

std::size_t channel_index(const std::string& name) {
  for (std::size_t c = 1; c < kChannelCount; ++c)
    if (name == kChannelNames[c]) return c;
  throw Error("diagnose: no channel '" + name + "'");
}

// an instance of the candidate with its channel set and parameter i at normalised x[i] in [0, 1]
std::unique_ptr<vehicle::Effect> make_candidate(const Candidate& c, const std::vector<double>& x,
                                                const vehicle::EffectPlugins& plugins) {
  auto effect = vehicle::make_effect(c.effect, plugins);
  if (!c.channel.empty()) effect->set_text("channel", c.channel);
  const auto params = effect->parameters();
  for (std::size_t i = 0; i < params.size() && i < x.size(); ++i) {
    const auto& p = params[i];
    const double u = std::clamp(x[i], 0.0, 1.0);
    const bool log_scale = p.min > 0.0 && p.max >= kLogScaleRatio * p.min;
    const double value = log_scale ? p.min * std::pow(p.max / p.min, u) : p.min + u * (p.max - p.min);
    effect->set(p.name, std::clamp(value, p.min, p.max));
  }
  return effect;
}

// NAME:option=...,param=value,... that make_effect reads back (values to 17 digits)
std::string effect_spec(const vehicle::Effect& e) {
  std::string spec = e.name();
  std::string list;
  for (const auto& o : e.options()) list += (list.empty() ? "" : ",") + o.name + "=" + o.value;
  for (const auto& p : e.parameters()) {
    char v[40];
    std::snprintf(v, sizeof v, "%.17g", p.value);
    list += (list.empty() ? "" : ",") + p.name + "=" + v;
  }
  return list.empty() ? spec : spec + ":" + list;
}

int parameter_count(const Candidate& c, const vehicle::EffectPlugins& plugins) {
  auto e = vehicle::make_effect(c.effect, plugins);
  if (!c.channel.empty()) e->set_text("channel", c.channel);
  return static_cast<int>(e->parameters().size());
}

// the scan's values of one normalised parameter: cell centres of n equal cells and, for a range
// that starts at zero, kNearZeroPoints more towards zero, each a quarter of the one before (down to
// 1/64 of the first cell's centre: 1e-3 of the range for 9 cells), so a true value near zero is
// scanned near itself rather than at the first centre, which may already fit worse than nothing
std::vector<double> scan_axis(int n, bool from_zero) {
  std::vector<double> u;
  if (from_zero) {
    for (int j = kNearZeroPoints; j >= 1; --j) u.push_back((0.5 / n) / std::pow(4.0, j));
  }
  for (int i = 0; i < n; ++i) u.push_back((i + 0.5) / n);
  return u;
}

// the i-th point (from 1) of the Halton sequence in base b: a space-filling design in [0, 1]
double halton(int i, int base) {
  double f = 1.0, r = 0.0;
  for (; i > 0; i /= base) {
    f /= base;
    r += f * (i % base);
  }
  return r;
}

// does parameter i of the candidate's effect range from zero (linearly: not log-scaled)?
std::vector<bool> zero_based(const Candidate& c, const vehicle::EffectPlugins& plugins) {
  auto e = vehicle::make_effect(c.effect, plugins);
  if (!c.channel.empty()) e->set_text("channel", c.channel);
  std::vector<bool> out;
  for (const auto& p : e->parameters()) out.push_back(p.min == 0.0 && p.max > 0.0);
  return out;
}

// the coarse scan's points of a candidate with k parameters: a line of kScanPoints for one, a grid
// of kScanPointsPerAxis2 per axis for two (both with the near-zero points of zero-based ranges),
// and for three or more kScanPoints per parameter of the Halton sequence (bases 2, 3, 5, ...),
// which fills the box evenly without a grid's k-th power
std::vector<std::vector<double>> scan_points(const std::vector<bool>& from_zero) {
  const std::size_t k = from_zero.size();
  std::vector<std::vector<double>> points;
  if (k == 1) {
    for (double u : scan_axis(kScanPoints, from_zero[0])) points.push_back({u});
  } else if (k == 2) {
    for (double u : scan_axis(kScanPointsPerAxis2, from_zero[0]))
      for (double v : scan_axis(kScanPointsPerAxis2, from_zero[1])) points.push_back({u, v});
  } else {
    constexpr int kPrimes[] = {2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37};
    const std::size_t dims = std::min(k, std::size(kPrimes));
    for (int i = 1; i <= kScanPoints * static_cast<int>(k); ++i) {
      std::vector<double> x(k, 0.5);
      for (std::size_t d = 0; d < dims; ++d) x[d] = halton(i, kPrimes[d]);
      points.push_back(x);
    }
  }
  return points;
}

// NLopt's C callback around a std::function; an exception stops the optimiser and is rethrown
struct Objective {
  std::function<double(const std::vector<double>&)> f;
  std::exception_ptr error;
  nlopt_opt opt = nullptr;
};

double nlopt_objective(unsigned n, const double* x, double* gradient, void* data) {
  (void)gradient;  // derivative free
  auto* o = static_cast<Objective*>(data);
  try {
    return o->f(std::vector<double>(x, x + n));
  } catch (...) {
    o->error = std::current_exception();
    nlopt_force_stop(o->opt);
    return HUGE_VAL;
  }
}

// each parameter alone moved by ±1, 2, 3 and 4 quarters of `step` (BOBYQA's first step: half the
// scan's spacing in a candidate's fit) from x, within [0, 1] and the evaluations left (counted
// down), then, where none of those gains kFitImprovement, by quarters of a quarter, and so on
// down to the fit's tolerance; the first scale's best point that lowers f(x) = best by
// kFitImprovement or more replaces x and best (true), else nothing changes (false). Four probes a
// side at each scale cover the whole interval to the next coarser scale's first probe. Why both
// ends: the objective can be discontinuous in a parameter (something in the run switches with
// it), and a restart from the lower side of such a step never crosses it: lift and tilt losses of
// 0.083 and 0.133 on load-carry fitted at 0.068 (objective 5.79) where the truth's basin, from
// 0.075 up, scores 0.13; and BOBYQA, restarted with the same first step, retraces its path to the
// same end on a smooth slope a few thousandths long (a tilt loss of 0.0553 fitted at 0.0515,
// objective 0.247 against the truth's 0.119; docs/sim2real.md section 3)
bool probe_axes(const std::function<double(const std::vector<double>&)>& f, std::vector<double>& x,
                double& best, double step, int& left) {
  constexpr int kProbesPerSide = 4;
  constexpr double kProbeScaleRatio = 1.0 / kProbesPerSide;  // each scale a quarter of the last
  for (double quarter = kProbeScaleRatio * step; quarter >= kFitTolerance && left > 0;
       quarter *= kProbeScaleRatio) {
    std::vector<double> found = x;
    double lowest = best;
    for (std::size_t i = 0; i < x.size(); ++i) {
      for (int k = -kProbesPerSide; k <= kProbesPerSide; ++k) {
        const double v = x[i] + k * quarter;
        if (k == 0 || v < 0.0 || v > 1.0 || left <= 0) continue;
        std::vector<double> y = x;
        y[i] = v;
        --left;
        const double fy = f(y);
        if (fy < lowest) {
          lowest = fy;
          found = y;
        }
      }
    }
    if (best - lowest >= kFitImprovement) {
      x = found;
      best = lowest;
      return true;
    }
  }
  return false;
}

// bounded derivative-free minimisation in [0, 1]^n from x (changed in place); returns f(x).
// NLopt's BOBYQA ends at its first step shorter than the tolerance. In one dimension that is
// convergence; in two or more it came long before the optimum: a three-parameter fit of command
// losses ended after 33 evaluations with the objective at 7.50 and the tilt's loss at 0.250 (true
// 0.113), where three restarts reached -0.58 and 0.114 (docs/sim2real.md section 3, 2026-12-01).
// So a fit of several parameters is restarted from where it ended, with a fresh trust region,
// until a restart gains less than kFitImprovement. Where it then ends, each parameter alone is
// probed on both sides (probe_axes); a better point starts the restarts again. Until the
// evaluations run out
double minimise(const std::function<double(const std::vector<double>&)>& f, std::vector<double>& x, double step,
                int max_evaluations) {
  const unsigned n = static_cast<unsigned>(x.size());
  Objective o{f, nullptr, nlopt_create(NLOPT_LN_BOBYQA, n)};
  if (!o.opt) throw Error("diagnose: NLopt could not create a BOBYQA optimiser");
  std::unique_ptr<std::remove_pointer_t<nlopt_opt>, decltype(&nlopt_destroy)> guard(o.opt, &nlopt_destroy);
  nlopt_set_lower_bounds1(o.opt, 0.0);
  nlopt_set_upper_bounds1(o.opt, 1.0);
  nlopt_set_min_objective(o.opt, &nlopt_objective, &o);
  nlopt_set_xtol_abs1(o.opt, kFitTolerance);
  nlopt_set_initial_step1(o.opt, step);
  double best = HUGE_VAL;
  int left = max_evaluations;
  for (;;) {
    // one BOBYQA run from x, within the evaluations left
    nlopt_set_maxeval(o.opt, left);
    double reached = HUGE_VAL;
    const nlopt_result r = nlopt_optimize(o.opt, x.data(), &reached);
    if (o.error) std::rethrow_exception(o.error);
    // running out of evaluations or meeting a tolerance both leave the best point found
    if (r < 0 && r != NLOPT_ROUNDOFF_LIMITED)
      throw Error("diagnose: NLopt BOBYQA failed (code " + std::to_string(r) + ")");
    left -= nlopt_get_numevals(o.opt);
    const double gain = best - reached;
    best = std::min(best, reached);
    if (n == 1 || left <= 0) break;
    // a restart that gained (almost) nothing: the axes probed; nothing better there, converged.
    // A probe that used the last evaluations ends it too (NLopt takes a budget of 0 as none)
    if (!(gain >= kFitImprovement) && (!probe_axes(f, x, best, step, left) || left <= 0)) break;
  }
  return best;
}

// the effects as a set, a learned actuator correction first: it was fitted to the operator's own
// commands (sim2real/discovery), so it must see them before a found lag or flow limit changes them
vehicle::EffectSet in_hook_order(std::vector<std::unique_ptr<vehicle::Effect>> effects) {
  std::stable_partition(effects.begin(), effects.end(),
                        [](const auto& e) { return e->name() == "learned_actuator_correction"; });
  vehicle::EffectSet set;
  for (auto& e : effects) set.add(std::move(e));
  return set;
}

double mean_of(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x;
  return v.empty() ? 0.0 : s / v.size();
}

}  // namespace

std::vector<std::vector<double>> candidate_scan_points(const Candidate& c,
                                                       const vehicle::EffectPlugins& plugins) {
  return scan_points(zero_based(c, plugins));
}

std::string Candidate::label() const { return channel.empty() ? effect : effect + "[" + channel + "]"; }

std::vector<Candidate> candidate_set(const vehicle::EffectPlugins& plugins) {
  std::vector<Candidate> out;
  for (const auto& name : vehicle::builtin_effect_names()) {
    const auto effect = vehicle::make_builtin_effect(name);
    // an effect with a channel option: one candidate per channel, which is all it can change
    const auto& options = effect->options();
    const auto channel = std::find_if(options.begin(), options.end(), [](const auto& o) { return o.name == "channel"; });
    if (channel != options.end()) {
      for (const auto& ch : channel->choices) {
        std::vector<std::size_t> signature = {channel_index(ch)};
        if (signature[0] != kPowerChannel) signature.push_back(kPowerChannel);
        out.push_back({name, ch, signature});
      }
    } else if (!effect->sensor_channels().empty()) {
      // a sensor effect on fixed channels: those (and the power that follows them)
      std::vector<std::size_t> signature;
      for (const Channel c : effect->sensor_channels()) signature.push_back(static_cast<std::size_t>(c));
      if (std::find(signature.begin(), signature.end(), kPowerChannel) == signature.end())
        signature.push_back(kPowerChannel);
      out.push_back({name, "", signature});
    } else {
      out.push_back({name, "", {}, effect->soil_only()});
    }
  }
  for (const auto& plugin : plugins)
    for (const auto& name : plugin->effect_names())
      out.push_back({name, "", {}, plugin->make(name)->soil_only()});
  return out;
}

std::vector<Candidate> chosen_candidates(const std::vector<Candidate>& all,
                                         const std::vector<std::string>& labels) {
  if (labels.empty()) return all;
  for (const auto& label : labels) {
    if (std::none_of(all.begin(), all.end(),
                     [&](const Candidate& c) { return c.label() == label; })) {
      std::string known;
      for (const auto& c : all) known += (known.empty() ? "" : ", ") + c.label();
      throw InputError("--candidates: no candidate effect is labelled '" + label +
                       "'; fix: name one of " + known);
    }
  }
  std::vector<Candidate> out;
  for (const auto& c : all)
    if (std::find(labels.begin(), labels.end(), c.label()) != labels.end()) out.push_back(c);
  return out;
}

int SensitivityJudgement::simulations() const {
  int sum = curvature_simulations;
  for (const auto& r : runs) sum += r.simulations;
  return sum;
}

TableRow mean_row(const std::vector<TableRow>& rows, const std::string& name) {
  TableRow m;
  m.name = name;
  // each column's mean over the runs where it is defined (an empty measured bucket leaves E_M
  // undefined: sim2real/metrics.hpp loaded_mass_error)
  std::array<double, 7> sum{};
  std::array<int, 7> defined{};
  for (const auto& r : rows) {
    const auto a = r.e.as_array();
    for (std::size_t i = 0; i < 7; ++i) {
      if (std::isnan(a[i])) continue;
      sum[i] += std::abs(a[i]);
      ++defined[i];
    }
  }
  std::array<double, 7> mean{};
  for (std::size_t i = 0; i < 7; ++i)
    mean[i] = defined[i] > 0 ? sum[i] / defined[i] : std::numeric_limits<double>::quiet_NaN();
  m.e = {mean[0], mean[1], mean[2], mean[3], mean[4], mean[5], mean[6]};
  double means = 0.0;
  int runs = 0;
  for (const auto& r : rows) {
    if (std::isnan(r.mean)) continue;
    means += r.mean;
    ++runs;
  }
  m.mean = runs > 0 ? means / runs : std::numeric_limits<double>::quiet_NaN();
  return m;
}

namespace {

// a model's mean excess and log-ratio per run over some runs; ordered by excess, then log-ratio
struct Score {
  double excess = HUGE_VAL, log_ratio = HUGE_VAL;
  bool operator<(const Score& o) const { return excess < o.excess || (excess == o.excess && log_ratio < o.log_ratio); }
};

// a candidate's best point of the coarse scan on the calibration runs
struct Scanned {
  const Candidate* c = nullptr;
  std::vector<double> x;
  Score score;
  int parameters = 0;
  // one parameter: every scan point's value and score, in scan order (the fit's window reuses
  // those inside it)
  std::vector<std::pair<double, Score>> scan_line;
};

// a task of a parallel loop that failed with an exception other than an interrupt: what it said
struct Failure {
  bool failed = false;
  std::string what;
};

// the negative log-likelihood of a run's residuals, Σ over its cells (n_eff / 2) log_ratio, each
// cell counted with the effective samples it has in `at_fit` (the same run at the fitted
// parameters; cells matched by channel and phase, a cell the fit lacks counted as none)
double effective_nll(const Residuals& r, const Residuals& at_fit) {
  double sum = 0.0;
  for (const ResidualCell& cell : r.cells) {
    const auto fit = std::find_if(
        at_fit.cells.begin(), at_fit.cells.end(),
        [&](const ResidualCell& f) { return f.channel == cell.channel && f.phase == cell.phase; });
    if (fit != at_fit.cells.end()) sum += 0.5 * fit->effective_samples * cell.log_ratio;
  }
  return sum;
}

// task(0) .. task(n - 1) on the threads (host/parallel); a task that throws is recorded by index
// and the others run on (a candidate whose simulation fails is reported and skipped, not the whole
// diagnosis). An interrupt stops the loop and is rethrown
std::vector<Failure> run_tasks(std::size_t n, int threads,
                               const std::function<void(std::size_t)>& task) {
  std::vector<Failure> failures(n);
  parallel_for(n, threads, [&](std::size_t i) {
    try {
      task(i);
    } catch (const Interrupted&) {
      throw;
    } catch (const std::exception& e) {
      failures[i] = {true, e.what()};
    }
  });
  return failures;
}

// The search of diagnose(), stage by stage: the replays and their noise, the baseline, then per
// round the signature screen, the coarse scan, the fits with validation, and the decision. It
// holds the model under test (the effects found so far) and every run's current simulation.
class Search {
 public:
  Search(const std::vector<MeasuredRun>& runs, const DiagnoseOptions& options, Device* device,
         const std::function<void(const std::string&)>& note)
      : runs_(runs), options_(options), note_(note) {
    // the replays, their noise, and the calibration / validation split
    for (const auto& run : runs) {
      replays_.push_back(std::make_unique<Replay>(run, options.replay, device));
      sigma_.push_back(noise_sigmas(run.run.series));
      d_.runs.push_back(run.run.dir.string());
    }
    const std::size_t n = runs.size();
    const std::size_t held = options.validation_runs >= 0 ? static_cast<std::size_t>(options.validation_runs)
                                                          : (n >= 2 ? std::max<std::size_t>(1, n / 3) : 0);
    if (held >= n)
      throw InputError("diagnose: --validation " + std::to_string(held) + " leaves no calibration run among " +
                       std::to_string(n) + "; hold out fewer");
    for (std::size_t i = 0; i < n; ++i) (i < n - held ? d_.calibration : d_.validation).push_back(i);
    if (d_.validation.empty()) d_.validation = d_.calibration;
    all_.resize(n);
    for (std::size_t i = 0; i < n; ++i) all_[i] = i;
    // soil effects show only where there are particles
    any_pile_ = std::any_of(replays_.begin(), replays_.end(), [](const auto& r) { return r->scenario().pile; });
    // the machine alone runs on every thread; a pile on the one device, one simulation at a time
    threads_ = any_pile_ ? 1 : (options.threads > 0 ? options.threads : hardware_threads());
  }

  // the baseline: residuals and the paper's error rows; the current model is the baseline
  void baseline() {
    const std::vector<Run> simulated = simulate_all(nullptr);
    for (std::size_t i = 0; i < runs_.size(); ++i) {
      Run r = simulated[i];
      r.summary.fidelity = "baseline";
      d_.simulated_before.push_back(r);
      d_.residuals_before.push_back(compute_residuals(r, runs_[i].run, sigma_[i]));
      const Comparison c = compare_runs(r, runs_[i].run, CompareOptions{});
      d_.error_before.push_back({runs_[i].run.label(), c.e, c.mean});
      d_.scan_rms_m.push_back(replays_[i]->scan_rms_m());
      d_.piles.push_back(replays_[i]->scenario().pile ? options_.replay.pile_ensemble : 1);
    }
    d_.excess_before = mean_excess(d_.residuals_before, all_);
    say("baseline: excess " + message_number(d_.excess_before) +
        " per run (noise alone leaves less than " + message_number(kSignificantExcess) +
        "), mean error " + message_number(mean_row(d_.error_before, "").mean));
    current_cal_ = mean_excess(d_.residuals_before, d_.calibration);
    current_val_ = mean_excess(d_.residuals_before, d_.validation);
    current_runs_ = d_.simulated_before;
    current_residuals_ = d_.residuals_before;
  }

  // the largest excess of any run under the current model: one run beyond noise is enough to
  // search (a mean would hide it among runs the effect does not touch)
  double worst_run() const {
    double worst = 0.0;
    for (const auto& r : judged_valid_ ? judged_ : current_residuals_)
      worst = std::max(worst, r.excess);
    return worst;
  }

  // the sensitivity judgement of the current model (the header's "Sensitivity"): every run beyond
  // noise judged again against the spread the simulation shows for parameter changes within the
  // fit's uncertainty; the judged residuals decide from now on, until the model changes
  void judge(const std::string& after) {
    SensitivityJudgement j;
    j.after = after;
    j.runs.resize(runs_.size());
    judged_ = current_residuals_;
    judged_valid_ = true;
    std::vector<std::size_t> beyond;
    for (std::size_t i = 0; i < runs_.size(); ++i) {
      j.runs[i].excess_without = j.runs[i].excess_with = current_residuals_[i].excess;
      if (current_residuals_[i].excess >= kSignificantExcess)
        beyond.push_back(i);
      else
        j.runs[i].reason = "within noise without it";
    }
    const auto skip = [&](const std::string& reason) {
      j.reason = reason;
      for (std::size_t i : beyond) j.runs[i].reason = reason;
      say("sensitivity (" + after + "): not used, " + reason);
      d_.sensitivity.push_back(j);
    };
    if (beyond.empty()) return skip("every run is within noise without it");
    // the fitted parameters: the found candidates' (a learned correction keeps its coefficients,
    // fitted by regression, not by the likelihood whose curvature is measured here)
    std::vector<double> x0;
    std::vector<std::pair<std::size_t, std::size_t>> slots;  // (found effect, its parameter)
    for (std::size_t f = 0; f < d_.found.size(); ++f)
      for (std::size_t k = 0; k < d_.found[f].x.size(); ++k) {
        x0.push_back(d_.found[f].x[k]);
        slots.emplace_back(f, k);
      }
    if (x0.empty())
      return skip(d_.found.empty() ? "no effect was added, so no parameter was fitted"
                                   : "no fitted parameter: the effects found carry none the "
                                     "likelihood fitted");
    const std::size_t p = x0.size();
    const double h = kSensitivityStep;
    // 1. the curvature of the calibration runs' negative log-likelihood, Σ over their cells of
    // (n_eff / 2) log_ratio (sim2real/residuals.hpp), by central differences around the fit (the
    // stencil moved inside the box when the fit lies within a step of a bound)
    std::vector<double> c = x0;
    for (double& v : c) v = std::clamp(v, h, 1.0 - h);
    std::vector<std::vector<double>> points;
    const auto point = [&](std::vector<double> y) {
      points.push_back(std::move(y));
      return points.size() - 1;
    };
    const bool moved = c != x0;
    const std::size_t centre = moved ? point(c) : 0;
    std::vector<std::size_t> plus(p), minus(p);
    std::vector<std::vector<std::size_t>> both_plus(p, std::vector<std::size_t>(p)),
        both_minus(p, std::vector<std::size_t>(p));
    for (std::size_t k = 0; k < p; ++k) {
      std::vector<double> y = c;
      y[k] = c[k] + h;
      plus[k] = point(y);
      y[k] = c[k] - h;
      minus[k] = point(y);
      for (std::size_t l = 0; l < k; ++l) {
        y = c;
        y[k] += h;
        y[l] += h;
        both_plus[k][l] = point(y);
        y = c;
        y[k] -= h;
        y[l] -= h;
        both_minus[k][l] = point(y);
      }
    }
    // each cell counted with the effective samples its residual has at the fit (a correlated
    // residual carries the information of fewer samples than it has: sim2real/residuals.hpp)
    const std::size_t ncal = d_.calibration.size();
    std::vector<double> run_nll(points.size() * ncal, 0.0);
    const std::vector<Failure> curvature_failures =
        run_tasks(points.size() * ncal, threads_, [&](std::size_t t) {
          const std::size_t i = d_.calibration[t % ncal];
          const Run r = simulate_found_at(i, points[t / ncal]);
          run_nll[t] =
              effective_nll(compute_residuals(r, runs_[i].run, sigma_[i]), current_residuals_[i]);
        });
    j.curvature_simulations = static_cast<int>(points.size() * ncal);
    for (const Failure& f : curvature_failures)
      if (f.failed) return skip("a simulation for the curvature failed (" + f.what + ")");
    double effective = 0.0, samples = 0.0;
    for (const std::size_t i : d_.calibration)
      for (const ResidualCell& cell : current_residuals_[i].cells) {
        effective += cell.effective_samples;
        samples += cell.samples;
      }
    j.effective_sample_share = samples > 0.0 ? effective / samples : 1.0;
    const auto nll = [&](std::size_t pt) {
      double sum = 0.0;
      for (std::size_t q = 0; q < ncal; ++q) {
        const std::size_t i = d_.calibration[q];
        sum += pt == points.size() ? effective_nll(current_residuals_[i], current_residuals_[i])
                                   : run_nll[pt * ncal + q];
      }
      return sum;
    };
    const double f0 = nll(moved ? centre : points.size());
    Eigen::MatrixXd hessian(p, p);
    for (std::size_t k = 0; k < p; ++k)
      hessian(k, k) = (nll(plus[k]) - 2.0 * f0 + nll(minus[k])) / (h * h);
    for (std::size_t k = 0; k < p; ++k)
      for (std::size_t l = 0; l < k; ++l) {
        // f(c + h e_k + h e_l) + f(c − h e_k − h e_l) − 2 f(c) = h² (H_kk + H_ll + 2 H_kl)
        const double mixed =
            (nll(both_plus[k][l]) + nll(both_minus[k][l]) - 2.0 * f0) / (2.0 * h * h) -
            0.5 * (hessian(k, k) + hessian(l, l));
        hessian(k, l) = hessian(l, k) = mixed;
      }
    // 2. the covariance, its inverse, with the eigenvalues held to [1/step², 1/tolerance²]: an
    // uncertainty no larger than the probe (where the likelihood does not curve up within it)
    // and no smaller than the fit's own resolution
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(hessian);
    const double lowest = 1.0 / (h * h), highest = 1.0 / (kFitTolerance * kFitTolerance);
    Eigen::VectorXd lambda = eigen.eigenvalues();
    j.curvature_in_range = true;
    for (Eigen::Index k = 0; k < lambda.size(); ++k) {
      if (!(lambda(k) >= lowest && lambda(k) <= highest)) j.curvature_in_range = false;
      lambda(k) = std::isfinite(lambda(k)) ? std::clamp(lambda(k), lowest, highest) : lowest;
    }
    // a square root of the covariance: L Lᵀ = V Λ⁻¹ Vᵀ
    const Eigen::MatrixXd root =
        eigen.eigenvectors() * lambda.cwiseInverse().cwiseSqrt().asDiagonal();
    const Eigen::MatrixXd covariance = root * root.transpose();
    for (std::size_t k = 0; k < p; ++k) {
      const std::size_t f = slots[k].first, q = slots[k].second;
      const FittedEffect& fe = d_.found[f];
      const double se = std::sqrt(covariance(k, k));
      auto at = [&](double u) {
        std::vector<double> y = fe.x;
        y[q] = std::clamp(u, 0.0, 1.0);
        return make_candidate(fe.candidate, y, options_.plugins)->parameters()[q];
      };
      const auto fitted = at(fe.x[q]);
      j.parameters.push_back({fe.candidate.label(), fitted.name, fitted.unit, fitted.value, se,
                              at(fe.x[q] - se).value, at(fe.x[q] + se).value});
    }
    // 3. the design: the columns 1..p of the Sylvester-Hadamard matrix of order M = 2^⌈log2(p +
    // 1)⌉ (balanced and orthogonal), so the points' departures L s_m have the covariance itself
    std::size_t m = 1;
    while (m < p + 1) m *= 2;
    j.design_points = static_cast<int>(m);
    std::vector<std::vector<double>> design(m, x0);
    for (std::size_t r = 0; r < m; ++r) {
      Eigen::VectorXd sign(p);
      for (std::size_t k = 0; k < p; ++k)
        sign(k) = std::bitset<64>(r & (k + 1)).count() % 2 == 0 ? 1.0 : -1.0;
      const Eigen::VectorXd step = root * sign;
      for (std::size_t k = 0; k < p; ++k) design[r][k] = std::clamp(x0[k] + step(k), 0.0, 1.0);
    }
    // 4. every run beyond noise at the design's points, judged against σ² + (1 + 1/N) v + s
    std::vector<Run> perturbed(beyond.size() * m);
    const std::vector<Failure> design_failures = run_tasks(
        perturbed.size(), threads_,
        [&](std::size_t t) { perturbed[t] = simulate_found_at(beyond[t / m], design[t % m]); });
    for (std::size_t b = 0; b < beyond.size(); ++b) {
      const std::size_t i = beyond[b];
      SensitivityRun& jr = j.runs[i];
      jr.simulations = static_cast<int>(m);
      const auto failure =
          std::find_if(design_failures.begin() + static_cast<std::ptrdiff_t>(b * m),
                       design_failures.begin() + static_cast<std::ptrdiff_t>((b + 1) * m),
                       [](const Failure& f) { return f.failed; });
      if (failure != design_failures.begin() + static_cast<std::ptrdiff_t>((b + 1) * m)) {
        jr.reason = "a simulation of the design failed (" + failure->what + ")";
        continue;
      }
      std::vector<Run> runs(perturbed.begin() + static_cast<std::ptrdiff_t>(b * m),
                            perturbed.begin() + static_cast<std::ptrdiff_t>((b + 1) * m));
      for (Run& r : runs) r.summary.fidelity = current_runs_[i].summary.fidelity;
      Run with = current_runs_[i];
      if (!with.spread) with.spread = RunSpread{};
      with.spread->sensitivity_runs = static_cast<int>(m);
      with.spread->sensitivity = sensitivity_variance(current_runs_[i], runs);
      with.spread->sensitivity_dof = sensitivity_dof(current_runs_[i], runs);
      with.spread->sensitivity_tau = sensitivity_departure_time(current_runs_[i], runs);
      judged_[i] = compute_residuals(with, runs_[i].run, sigma_[i]);
      jr.used = true;
      jr.excess_with = judged_[i].excess;
    }
    j.used = std::any_of(j.runs.begin(), j.runs.end(), [](const auto& r) { return r.used; });
    if (!j.used) j.reason = "every run's design failed";
    std::string line = "sensitivity (" + after + "): " + std::to_string(p) + " parameter" +
                       (p > 1 ? "s" : "") + " (";
    for (std::size_t k = 0; k < j.parameters.size(); ++k)
      line += (k ? ", " : "") + j.parameters[k].parameter + " " +
              message_number(j.parameters[k].value) + " [" + message_number(j.parameters[k].low) +
              ", " + message_number(j.parameters[k].high) + "]";
    line += "), " + std::to_string(j.simulations()) + " simulations;";
    for (std::size_t i : beyond)
      line += " run " + std::to_string(i) + " excess " + message_number(j.runs[i].excess_without) +
              " -> " + message_number(j.runs[i].excess_with);
    say(line);
    d_.sensitivity.push_back(j);
  }

  // one round: one effect more when a candidate explains enough of what is left; false when none
  bool round(int number, const std::vector<Candidate>& candidates) {
    DiagnosisRound dr;
    dr.excess_before = current_val_;
    const std::vector<const Candidate*> screened = screen(candidates, dr);
    say("round " + std::to_string(number) + ": " + std::to_string(screened.size()) + " candidates to scan, " +
        std::to_string(dr.screened_out.size()) + " screened out by their signature");
    fit_best(scan(screened, dr), dr);
    // 5. add the winner only when it explains enough of what is left; else the best pair, or set
    // of three, that does; 6. then, if an earlier round's effect carries fitted parameters, all of
    // them refitted together
    const bool earlier_fitted = std::any_of(d_.found.begin(), d_.found.end(),
                                            [](const FittedEffect& f) { return !f.x.empty(); });
    if (!dr.fitted.empty() && dr.fitted[0].explained >= kMinExplained &&
        holds_on_reference(dr, {dr.fitted[0].spec}, dr.fitted[0].explained_on)) {
      dr.added = true;
      add(dr.fitted[0]);
      say("round " + std::to_string(number) + ": added " + dr.fitted[0].spec);
    } else if (const FittedSet* set = joint_set(candidates, dr)) {
      dr.added = true;
      for (const auto& m : set->members) add(m);
      current_cal_ = set->excess_calibration;
      current_val_ = set->excess_validation;
      say("round " + std::to_string(number) + ": added the " +
          (set->members.size() == 2 ? "pair " : "set ") + listed(set->specs(), ", ", " and "));
    } else {
      say("round " + std::to_string(number) + ": no candidate, pair or set of three explains " +
          message_number(100.0 * kMinExplained) + " % of the excess left; nothing added");
    }
    if (dr.added && earlier_fitted) dr.refit = refit_found(number);
    d_.rounds.push_back(dr);
    return dr.added;
  }

  // 6. every found effect's fitted parameters refitted together on the calibration runs (the
  // likelihood, as a pair's fit, from the values the rounds left), a learned correction at its
  // coefficients; the refit replaces them only if the calibration runs' log-ratio falls and the
  // held-out runs' excess does not rise (a joint fit that buys the calibration runs at the held-out
  // runs' cost is an overfit, not an explanation)
  JointRefit refit_found(int number) {
    JointRefit r;
    std::vector<double> x;
    for (const FittedEffect& f : d_.found) {
      r.before.push_back(f.spec);
      x.insert(x.end(), f.x.begin(), f.x.end());
    }
    const auto score_found = [&](const std::vector<std::size_t>& which,
                                 const std::vector<double>& y) {
      r.simulations += static_cast<int>(which.size());
      return score_model(which, [&](std::size_t i) { return simulate_found_at(i, y); });
    };
    std::vector<double> ratio;
    for (std::size_t i : d_.calibration) ratio.push_back(current_residuals_[i].log_ratio);
    r.log_ratio_before = mean_of(ratio);
    r.excess_calibration_before = current_cal_;
    r.excess_validation_before = current_val_;
    minimise([&](const std::vector<double>& y) { return score_found(d_.calibration, y).log_ratio; },
             x, 0.5 / kScanPointsPerAxis2,
             kFitEvaluationsPerParameter * static_cast<int>(x.size()));
    const Score cal = score_found(d_.calibration, x);
    const bool disjoint = d_.validation != d_.calibration;
    const Score val = disjoint ? score_found(d_.validation, x) : cal;
    r.log_ratio_after = cal.log_ratio;
    r.excess_calibration_after = cal.excess;
    r.excess_validation_after = val.excess;
    r.kept = r.log_ratio_after < r.log_ratio_before &&
             r.excess_validation_after <= r.excess_validation_before;
    // the effects at their refitted values (found order, each effect's parameters in its order)
    std::size_t at = 0;
    for (FittedEffect& f : d_.found) {
      const std::vector<double> xf(x.begin() + static_cast<std::ptrdiff_t>(at),
                                   x.begin() + static_cast<std::ptrdiff_t>(at + f.x.size()));
      at += f.x.size();
      if (f.x.empty()) {
        r.after.push_back(f.spec);
        continue;
      }
      const FittedEffect refitted = as_fitted(f.candidate, xf);
      r.after.push_back(refitted.spec);
      if (!r.kept) continue;
      f.x = refitted.x;
      f.spec = refitted.spec;
      f.effect = refitted.effect;
    }
    say("round " + std::to_string(number) + ": refitted together (" +
        (r.kept ? "kept" : "not kept") + "): calibration log-ratio " +
        message_number(r.log_ratio_before) + " -> " + message_number(r.log_ratio_after) +
        ", held-out excess " + message_number(r.excess_validation_before) + " -> " +
        message_number(r.excess_validation_after));
    if (r.kept) {
      for (std::size_t k = 0; k < d_.found.size(); ++k) found_specs_[k] = d_.found[k].spec;
      resimulate(r.excess_calibration_after, r.excess_validation_after);
    }
    return r;
  }

  // discovery: a learned correction per target, fitted on the calibration runs against the current
  // model, simulated on every run; the best added when it explains enough of what is left
  // true when it added one
  bool discover() {
    d_.discovery_ran = true;
    // the sensor channels whose own excess is beyond noise on the calibration runs, largest first
    std::vector<std::pair<double, std::string>> own;
    for (std::size_t c = 1; c < kChannelCount; ++c) {
      if (c == kPowerChannel) continue;  // power follows the other readings
      std::vector<double> e;
      for (std::size_t i : d_.calibration) e.push_back(current_residuals_[i].excess_of({c}));
      if (mean_of(e) >= kSignificantExcess) own.emplace_back(mean_of(e), kChannelNames[c]);
    }
    std::sort(own.begin(), own.end(), std::greater<>());
    std::vector<std::string> channels;
    for (std::size_t k = 0; k < own.size() && k < kDiscoverySensorTargets; ++k)
      channels.push_back(own[k].second);
    std::vector<const MeasuredRun*> measured;
    std::vector<const Run*> simulated;
    for (std::size_t i : d_.calibration) {
      measured.push_back(&runs_[i]);
      simulated.push_back(&current_runs_[i]);
    }
    const std::vector<DiscoveryTarget> targets = discovery_targets(channels);
    say("discovery: " + std::to_string(targets.size()) +
        " targets (the drive, lift and tilt speeds, the tractive force" +
        (channels.empty() ? std::string() : ", the readings with an excess of their own") + ")");
    // the machine of the first calibration run (every run of one diagnosis replays one machine)
    const vehicle::MachineDescription machine =
        vehicle::parse_machine(vehicle::machine_file(replays_[d_.calibration.front()]->scenario()));
    for (const DiscoveryTarget& target : targets) {
      DiscoveredCorrection c = fit_correction(
          target, regression_data(target, measured, simulated, command_limit(target, machine)));
      if (c.terms.empty()) {
        say("  " + target.label() + ": no sparse model cuts the held-out residual (mean square " +
            message_number(c.cv_mse_none) + ")");
        d_.discovery_tried.push_back(c);
        continue;
      }
      say("  " + target.label() + ": " + c.expression);
      // a correction whose simulation fails is reported and skipped, as a candidate is
      try {
        evaluate(c);
      } catch (const Interrupted&) {
        throw;
      } catch (const std::exception& e) {
        say("    its simulation failed (" + std::string(e.what()) + "); skipped");
        d_.discovery_tried.push_back(c);
        continue;
      }
      say("    explains " + message_number(100.0 * c.explained) + " % of the excess on the " +
          c.explained_on + " runs");
      d_.discovery_tried.push_back(c);
    }
    // the best refined on the simulations: the regression fits the measured state, which the
    // simulation reaches only approximately, so its coefficients are a start, not the optimum
    auto best_of = [&]() {
      const DiscoveredCorrection* best = nullptr;
      for (const auto& c : d_.discovery_tried)
        if (c.simulated && (!best || c.explained > best->explained)) best = &c;
      return best;
    };
    if (const DiscoveredCorrection* best = best_of(); best && best->explained > 0.0) {
      try {
        DiscoveredCorrection refined = refine(*best);
        if (refined.explained > best->explained) {
          say("  refined: " + refined.expression + ", explains " +
              message_number(100.0 * refined.explained) + " %");
          d_.discovery_tried.push_back(refined);
        }
      } catch (const Interrupted&) {
        throw;
      } catch (const std::exception& e) {
        say("  the refinement's simulation failed (" + std::string(e.what()) +
            "); the regression's values kept");
      }
    }
    // the best simulated correction, if it explains enough
    const DiscoveredCorrection* best = best_of();
    if (!best || best->explained < kMinExplained) {
      say("discovery: no correction explains " + message_number(100.0 * kMinExplained) +
          " % of the excess left");
      return false;
    }
    if (!holds_on_reference(d_.discovery_chaos_checks, {best->spec}, best->explained_on)) {
      say("discovery: " + best->expression + " does not hold on the reference piles; not added");
      return false;
    }
    d_.discovered = *best;
    FittedEffect f;
    f.candidate = {best->target.effect_name(), "", {}};
    const auto effect = vehicle::make_effect(best->spec, options_.plugins);
    f.effect = effect->to_json();
    f.spec = best->spec;
    f.parameters = static_cast<int>(best->terms.size());
    f.excess_calibration = best->excess_calibration;
    f.excess_validation = best->excess_validation;
    f.explained = best->explained;
    f.explained_on = best->explained_on;
    f.score = best->score;
    say("discovery: added " + best->expression);
    add(f);
    return true;
  }

  // the correction simulated on every run: its excess, the share it explains (counted as a
  // candidate's) and the channels whose excess it lowers
  void evaluate(DiscoveredCorrection& c) {
    const std::vector<Run> simulated = simulate_all(&c.spec);
    std::vector<Residuals> after(runs_.size());
    for (std::size_t i = 0; i < runs_.size(); ++i)
      after[i] = compute_residuals(simulated[i], runs_[i].run, sigma_[i]);
    c.simulated = true;
    c.excess_calibration = mean_excess(after, d_.calibration);
    c.excess_validation = mean_excess(after, d_.validation);
    const Share share = share_explained(c.excess_calibration, c.excess_validation);
    c.explained = share.explained;
    c.explained_on = share.on;
    c.score = c.explained_on == "validation" ? c.excess_validation : c.excess_calibration;
    c.channels.clear();
    for (std::size_t ch = 1; ch < kChannelCount; ++ch) {
      double before = 0.0, with = 0.0;
      for (std::size_t i = 0; i < runs_.size(); ++i) {
        before += current_residuals_[i].excess_of({ch});
        with += after[i].excess_of({ch});
      }
      if (before - with >= kDiscoveryChannelCut * static_cast<double>(runs_.size()))
        c.channels.emplace_back(kChannelNames[ch]);
    }
  }

  // the coefficients refitted by the likelihood of the calibration runs' simulations (BOBYQA, as a
  // candidate's fit), each in a box of ±max(3 intervals, its own size) around the regression's
  // value
  DiscoveredCorrection refine(const DiscoveredCorrection& start) {
    DiscoveredCorrection c = start;
    std::vector<double> span(c.terms.size());
    for (std::size_t k = 0; k < span.size(); ++k)
      span[k] = std::max(3.0 * c.terms[k].half_width, std::abs(c.terms[k].coefficient));
    auto at = [&](const std::vector<double>& x) {
      DiscoveredCorrection trial = start;
      for (std::size_t k = 0; k < span.size(); ++k)
        trial.terms[k].coefficient = start.terms[k].coefficient + (2.0 * x[k] - 1.0) * span[k];
      describe_correction(trial);
      return trial;
    };
    auto log_ratio = [&](const std::vector<double>& x) {
      const DiscoveredCorrection trial = at(x);
      std::vector<double> l;
      for (std::size_t i : d_.calibration) {
        const Run r = simulate(i, vehicle::make_effect(trial.spec, options_.plugins));
        l.push_back(compute_residuals(r, runs_[i].run, sigma_[i]).log_ratio);
      }
      return mean_of(l);
    };
    std::vector<double> x(span.size(), 0.5);
    minimise(log_ratio, x, kDiscoveryRefineStep, kFitEvaluations);
    c = at(x);
    // a term the refinement took to exactly zero (its box's edge: span = |coefficient|) does
    // nothing in the simulation: it leaves the expression, as a term the regression never chose
    // (the sixth documentation run printed two such terms, docs/discovery.md)
    const auto zero = [](const DiscoveredTerm& term) { return term.coefficient == 0.0; };
    if (!std::all_of(c.terms.begin(), c.terms.end(), zero)) {
      c.terms.erase(std::remove_if(c.terms.begin(), c.terms.end(), zero), c.terms.end());
      describe_correction(c);
    }
    c.refined = true;
    evaluate(c);
    return c;
  }

  // after: the runs with the effects found (the last round's simulations)
  Diagnosis finish() {
    // the verdict is the judged residuals' (a judgement that skips says why)
    if (!judged_valid_) judge("end");
    d_.simulations = simulations_;
    d_.simulated_after = current_runs_;
    d_.residuals_after = judged_;
    if (d_.found.empty()) {
      d_.error_after = d_.error_before;
    } else {
      for (std::size_t i = 0; i < runs_.size(); ++i) {
        const Comparison c = compare_runs(current_runs_[i], runs_[i].run, CompareOptions{});
        d_.error_after.push_back({runs_[i].run.label(), c.e, c.mean});
      }
    }
    d_.excess_after = mean_excess(d_.residuals_after, all_);
    d_.unexplained = worst_run() >= kSignificantExcess;
    return d_;
  }

 private:
  void say(const std::string& line) const {
    if (note_) note_(line);
  }

  // the share of the excess left that a model with these excesses removes: on the held-out runs;
  // when they leave nothing beyond noise (the effect does not show in them), on the calibration
  // runs, provided it keeps the held-out runs within noise. One rule for candidates, sets and
  // learned corrections
  struct Share {
    double explained = 0.0;
    std::string on;
  };
  Share share_explained(double excess_calibration, double excess_validation) const {
    const bool disjoint = d_.validation != d_.calibration;
    if (current_val_ >= kSignificantExcess || !disjoint)
      return {current_val_ > 0.0 ? (current_val_ - excess_validation) / current_val_ : 0.0,
              "validation"};
    return {excess_validation < kSignificantExcess && current_cal_ > 0.0
                ? (current_cal_ - excess_calibration) / current_cal_
                : 0.0,
            "calibration"};
  }

  // whether an addition (its specs) whose share was counted `on` those runs holds on the chaos
  // reference (ChaosCheck): always on held-out runs or flat-ground data; on pile data with the
  // share counted on the calibration runs, only if it explains enough there too
  bool holds_on_reference(DiagnosisRound& dr, const std::vector<std::string>& specs,
                          const std::string& on) {
    return holds_on_reference(dr.chaos_checks, specs, on);
  }
  bool holds_on_reference(std::vector<ChaosCheck>& checks, const std::vector<std::string>& specs,
                          const std::string& on) {
    if (on != "calibration" || !any_pile_) return true;
    ChaosCheck check;
    check.effects = specs;
    // the model as it is, then with the addition, each calibration run on the reference piles
    const std::vector<std::string> none;
    for (const std::vector<std::string>* extra : {&none, &specs}) {
      std::vector<double> excess;
      for (std::size_t i : d_.calibration) {
        std::vector<std::unique_ptr<vehicle::Effect>> extras;
        for (const auto& spec : *extra)
          extras.push_back(vehicle::make_effect(spec, options_.plugins));
        vehicle::EffectSet set = model_effects(std::move(extras));
        // a flat-ground run among pile runs has no chaos: its own simulation
        const Run r = replays_[i]->scenario().pile ? replays_[i]->simulate_reference(set)
                                                   : replays_[i]->simulate(set);
        ++simulations_;
        ++check.simulations;
        excess.push_back(compute_residuals(r, runs_[i].run, sigma_[i]).excess);
      }
      (extra == &none ? check.excess_before : check.excess_with) = mean_of(excess);
    }
    check.explained = check.excess_before >= kSignificantExcess
                          ? (check.excess_before - check.excess_with) / check.excess_before
                          : 0.0;
    check.passed = check.explained >= kMinExplained;
    std::string names;
    for (const auto& spec : specs) names += (names.empty() ? "" : " and ") + spec;
    say("  chaos check of " + names + " on the reference piles: calibration excess " +
        message_number(check.excess_before) + " -> " + message_number(check.excess_with) +
        " (explains " + message_number(100.0 * check.explained) + " %; " +
        (check.passed ? "holds" : "refused: a chance fit of the model's own piles") + ")");
    checks.push_back(check);
    return check.passed;
  }

  // a candidate whose simulation threw: reported in the round and the notes, then skipped
  void failed(DiagnosisRound& dr, const std::string& label, const std::string& what) const {
    dr.failed.push_back({label, what});
    say("  " + label + ": its simulation failed (" + what + "); skipped");
  }

  // the effects found so far, then `extra`, in hook order
  vehicle::EffectSet model_effects(std::vector<std::unique_ptr<vehicle::Effect>> extra) const {
    std::vector<std::unique_ptr<vehicle::Effect>> effects;
    for (const auto& spec : found_specs_)
      effects.push_back(vehicle::make_effect(spec, options_.plugins));
    for (auto& e : extra) effects.push_back(std::move(e));
    return in_hook_order(std::move(effects));
  }

  // run i simulated with the effects found so far plus, optionally, a candidate
  Run simulate(std::size_t i, std::unique_ptr<vehicle::Effect> extra) {
    std::vector<std::unique_ptr<vehicle::Effect>> extras;
    if (extra) extras.push_back(std::move(extra));
    vehicle::EffectSet set = model_effects(std::move(extras));
    Run r = replays_[i]->simulate(set);
    ++simulations_;
    return r;
  }

  // every run simulated with the effects found so far plus, optionally, the effect `extra` (a
  // spec), the runs at once
  std::vector<Run> simulate_all(const std::string* extra) {
    std::vector<Run> simulated(runs_.size());
    parallel_for(runs_.size(), threads_, [&](std::size_t i) {
      simulated[i] = simulate(i, extra ? vehicle::make_effect(*extra, options_.plugins) : nullptr);
    });
    return simulated;
  }

  // the mean excess and log-ratio per run of the runs `which` with the candidate at x
  Score score_runs(const std::vector<std::size_t>& which, const Candidate* c, const std::vector<double>& x) {
    return score_model(which, [&](std::size_t i) {
      return simulate(i, c ? make_candidate(*c, x, options_.plugins) : nullptr);
    });
  }

  // the mean excess and log-ratio over some runs of a model, each run simulated by `simulated`
  Score score_model(const std::vector<std::size_t>& which,
                    const std::function<Run(std::size_t)>& simulated) {
    std::vector<double> e, l;
    for (std::size_t i : which) {
      const Residuals res = compute_residuals(simulated(i), runs_[i].run, sigma_[i]);
      e.push_back(res.excess);
      l.push_back(res.log_ratio);
    }
    return Score{mean_of(e), mean_of(l)};
  }

  // the mean excess of some runs' residuals
  static double mean_excess(const std::vector<Residuals>& res, const std::vector<std::size_t>& which) {
    std::vector<double> v;
    for (std::size_t i : which) v.push_back(res[i].excess);
    return mean_of(v);
  }

  // 1. the signature screen: candidates not yet found whose channels hold `share` of the excess
  // (a single must remove kMinExplained; a set's member kMemberShare)
  std::vector<const Candidate*> screen(const std::vector<Candidate>& candidates, DiagnosisRound& dr,
                                       double share = kMinExplained) const {
    std::vector<const Candidate*> screened;
    for (const auto& c : candidates) {
      const bool taken =
          std::any_of(d_.found.begin(), d_.found.end(), [&](const auto& f) { return f.candidate.label() == c.label(); });
      if (taken) continue;
      if (c.needs_particles && !any_pile_) {
        dr.screened_out.push_back(c.label());
        continue;
      }
      if (!c.signature.empty()) {
        // it can remove no more than its channels' excess, and nothing unless the channel it acts
        // on (the first) departs from the data: power follows a reading, it does not lead it
        std::vector<double> bound, own;
        for (std::size_t i : d_.calibration) {
          bound.push_back(current_residuals_[i].excess_of(c.signature));
          own.push_back(current_residuals_[i].excess_of({c.signature.front()}));
        }
        if (mean_of(bound) < share * current_cal_ || mean_of(own) < kSignificantExcess) {
          dr.screened_out.push_back(c.label());
          continue;
        }
      }
      screened.push_back(&c);
    }
    return screened;
  }

  // 2. the coarse scan on the calibration runs: each candidate's best grid point, best first. All
  // candidates' points are one list of independent simulations, run on the threads at once; each
  // candidate's best is then read in point order, as a serial scan would
  std::vector<Scanned> scan(const std::vector<const Candidate*>& screened, DiagnosisRound& dr) {
    struct Point {
      std::size_t candidate;
      std::vector<double> x;
    };
    std::vector<int> parameters(screened.size());
    std::vector<Failure> setup(screened.size());
    std::vector<Point> points;
    std::vector<std::size_t> first_point(screened.size() + 1, 0);
    for (std::size_t k = 0; k < screened.size(); ++k) {
      first_point[k] = points.size();
      parameters[k] = parameter_count(*screened[k], options_.plugins);
      if (parameters[k] == 0) continue;
      try {
        for (auto& x : scan_points(zero_based(*screened[k], options_.plugins)))
          points.push_back({k, std::move(x)});
      } catch (const std::exception& e) {
        setup[k] = {true, e.what()};
      }
    }
    first_point[screened.size()] = points.size();
    std::vector<Score> scores(points.size());
    const std::vector<Failure> failures = run_tasks(points.size(), threads_, [&](std::size_t p) {
      scores[p] = score_runs(d_.calibration, screened[points[p].candidate], points[p].x);
    });
    std::vector<Scanned> scanned;
    for (std::size_t k = 0; k < screened.size(); ++k) {
      const Candidate* c = screened[k];
      if (parameters[k] == 0) {
        say("  " + c->label() + ": no parameters to fit, skipped");
        continue;
      }
      if (setup[k].failed) {
        failed(dr, c->label(), setup[k].what);
        continue;
      }
      // its first failure in point order, or its best point
      const std::size_t begin = first_point[k], end = first_point[k + 1];
      const auto failure = std::find_if(failures.begin() + static_cast<std::ptrdiff_t>(begin),
                                        failures.begin() + static_cast<std::ptrdiff_t>(end),
                                        [](const Failure& f) { return f.failed; });
      if (failure != failures.begin() + static_cast<std::ptrdiff_t>(end)) {
        failed(dr, c->label(), failure->what);
        continue;
      }
      Scanned best{c, points[begin].x, Score{}, parameters[k], {}};
      for (std::size_t p = begin; p < end; ++p)
        if (scores[p] < best.score) best = {c, points[p].x, scores[p], parameters[k], {}};
      if (parameters[k] == 1)
        for (std::size_t p = begin; p < end; ++p)
          best.scan_line.emplace_back(points[p].x[0], scores[p]);
      say("  scan " + c->label() + ": best excess " + message_number(best.score.excess) + " (now " +
          message_number(current_cal_) + ", " + std::to_string(end - begin) + " points)");
      scanned.push_back(best);
    }
    std::sort(scanned.begin(), scanned.end(), [](const auto& a, const auto& b) { return a.score < b.score; });
    return scanned;
  }

  // a one-parameter candidate's window around its best scan point: the new points sampled on the
  // calibration runs (the best sample taken as the scan's best if it scores better) and the trend
  // of the likelihood (log-ratio) over every sample in the window; none where a sample's
  // likelihood is not finite. `s.x` must be a scan point: fit() calls this once per Scanned
  template <class ScoreFn>
  std::optional<WindowTrend> sample_window(Scanned& s, const FitWindow& w, ScoreFn& score) {
    std::vector<double> u, y;
    for (const auto& [v, sc] : s.scan_line)
      if (v >= w.lo && v <= w.hi) {
        u.push_back(v);
        y.push_back(sc.log_ratio);
      }
    for (double v : w.new_points) {
      const Score sc = score(d_.calibration, std::vector<double>{v});
      u.push_back(v);
      y.push_back(sc.log_ratio);
      if (sc < s.score) {
        s.x = {v};
        s.score = sc;
      }
    }
    if (!std::all_of(y.begin(), y.end(), [](double v) { return std::isfinite(v); }))
      return std::nullopt;
    return window_trend(u, y, w);
  }

  // 3. and 4.: the likelihood's optimum from the best scan point, then its excess on the held-out
  // runs, the share it explains and its penalised score. One parameter: the window's trend first;
  // a rough one's vertex is the estimate (sample_window). The optimum is the estimate even where
  // a window sample's floored excess is lower: near the floor that difference is noise, and
  // falling back to a sample a quarter of the scan's spacing away put G400 friction 20-35 % off
  // where the optimum was 1-15 % off (docs/sim2real.md "The likelihood's optimum, not the best
  // sample", 2026-12-01)
  FittedEffect fit(Scanned& s) {
    int simulations = 0;  // counted here: other fits run beside this one
    const auto score = [&](const std::vector<std::size_t>& which, const std::vector<double>& x) {
      simulations += static_cast<int>(which.size());
      return score_runs(which, s.c, x);
    };
    const bool disjoint = d_.validation != d_.calibration;
    double step = 0.5 / (s.parameters == 1 ? kScanPoints : kScanPointsPerAxis2);
    std::vector<double> x = s.x;
    FittedEffect f;
    Score fitted;
    // one parameter: the likelihood's trend in the window around the best scan point; the
    // optimiser's first step half the window's spacing between samples
    if (s.parameters == 1) {
      std::vector<double> axis;
      for (const auto& [u, sc] : s.scan_line) axis.push_back(u);
      std::sort(axis.begin(), axis.end());
      const FitWindow w = fit_window(axis, s.x[0], kWindowPointsPerSide);
      const std::optional<WindowTrend> trend = sample_window(s, w, score);
      x = s.x;
      if (trend) {
        f.local_minima = trend->local_minima;
        f.roughness = trend->parabola.roughness();
        f.trend_estimate = trend->rough();
        if (trend->parabola.convex) x = {trend->parabola.vertex};
      }
      step = 0.5 * w.spacing;
    }
    if (f.trend_estimate) {
      // rough: the trend's minimum is the estimate, whatever single samples happen to score
      fitted = score(d_.calibration, x);
      s.x = x;
      s.score = fitted;
    } else {
      const int evaluations =
          s.parameters == 1 ? kFitEvaluations : kFitEvaluationsPerParameter * s.parameters;
      minimise([&](const std::vector<double>& y) { return score(d_.calibration, y).log_ratio; }, x,
               step, evaluations);
      fitted = score(d_.calibration, x);
      s.x = x;
      s.score = fitted;
    }
    f.candidate = *s.c;
    const auto effect = make_candidate(*s.c, s.x, options_.plugins);
    f.effect = effect->to_json();
    f.spec = effect_spec(*effect);
    f.parameters = s.parameters;
    f.x = s.x;
    f.excess_calibration = fitted.excess;
    f.excess_validation = disjoint ? score(d_.validation, s.x).excess : f.excess_calibration;
    // the share it explains of what is left
    const Share share = share_explained(f.excess_calibration, f.excess_validation);
    f.explained = share.explained;
    f.explained_on = share.on;
    // the score ranks on the runs the share is counted on; a candidate that pushes held-out runs
    // beyond noise ranks last
    const bool harmless = f.explained_on == "validation" || f.excess_validation < kSignificantExcess;
    f.score = harmless ? (f.explained_on == "validation" ? f.excess_validation : f.excess_calibration) +
                             kParameterPenalty * f.parameters
                       : HUGE_VAL;
    f.simulations = simulations;
    return f;
  }

  // a fit's line in the notes (said by the caller, in rank order, once the fits beside it are done)
  void say_fit(const FittedEffect& f) const {
    say("  fit " + f.spec + ": excess calibration " + message_number(f.excess_calibration) +
        ", validation " + message_number(f.excess_validation) + " (explains " +
        message_number(100.0 * f.explained) + " % on the " + f.explained_on + " runs" +
        (f.parameters != 1 || f.local_minima == 0
             ? std::string()
             : "; window: " + std::to_string(f.local_minima) + " local minima, " +
                   (f.trend_estimate ? "the trend's minimum taken" : "refined")) +
        ")");
  }

  // run i simulated with the effects found so far plus the candidates at their normalised values
  Run simulate_with(std::size_t i,
                    const std::vector<std::pair<const Candidate*, std::vector<double>>>& extras) {
    std::vector<std::unique_ptr<vehicle::Effect>> candidates;
    candidates.reserve(extras.size());
    for (const auto& [c, x] : extras) candidates.push_back(make_candidate(*c, x, options_.plugins));
    vehicle::EffectSet set = model_effects(std::move(candidates));
    Run r = replays_[i]->simulate(set);
    ++simulations_;
    return r;
  }

  // run i simulated with the effects found, their fitted parameters (in found order, each
  // effect's in its own order) at the normalised values x; a learned correction at its own
  // coefficients. At the fit's x, the same simulation as the current model's
  Run simulate_found_at(std::size_t i, const std::vector<double>& x) {
    std::vector<std::unique_ptr<vehicle::Effect>> effects;
    std::size_t at = 0;
    for (const auto& f : d_.found) {
      if (f.x.empty()) {
        effects.push_back(vehicle::make_effect(f.spec, options_.plugins));
        continue;
      }
      const std::vector<double> xf(x.begin() + static_cast<std::ptrdiff_t>(at),
                                   x.begin() + static_cast<std::ptrdiff_t>(at + f.x.size()));
      at += f.x.size();
      effects.push_back(make_candidate(f.candidate, xf, options_.plugins));
    }
    vehicle::EffectSet set = in_hook_order(std::move(effects));
    Run r = replays_[i]->simulate(set);
    ++simulations_;
    return r;
  }

  // the model's state (the effects found and every run's simulation), to try a candidate on it
  struct Model {
    std::vector<std::string> specs;
    double cal = 0.0, val = 0.0;
    std::vector<Run> runs;
    std::vector<Residuals> residuals;
  };
  Model model() const {
    return {found_specs_, current_cal_, current_val_, current_runs_, current_residuals_};
  }
  void restore(Model m) {
    found_specs_ = std::move(m.specs);
    current_cal_ = m.cal;
    current_val_ = m.val;
    current_runs_ = std::move(m.runs);
    current_residuals_ = std::move(m.residuals);
  }

  // 3. fit the best few of a scan (those better than the model without them), each fit on its
  // own thread; 4. validate them with the parameter penalty. Reported in rank order, as a serial
  // loop would; dr.fitted gains them, best score first
  void fit_best(std::vector<Scanned> scanned, DiagnosisRound& dr) {
    std::size_t fitted = 0;
    while (fitted < scanned.size() && fitted < static_cast<std::size_t>(kFitted) &&
           scanned[fitted].score.excess < current_cal_)
      ++fitted;
    std::vector<FittedEffect> fits(fitted);
    const std::vector<Failure> fit_failures =
        run_tasks(fitted, threads_, [&](std::size_t j) { fits[j] = fit(scanned[j]); });
    for (std::size_t j = 0; j < fitted; ++j) {
      if (fit_failures[j].failed) {
        failed(dr, scanned[j].c->label(), fit_failures[j].what);
        continue;
      }
      say_fit(fits[j]);
      dr.fitted.push_back(fits[j]);
    }
    std::sort(dr.fitted.begin(), dr.fitted.end(),
              [](const auto& a, const auto& b) { return a.score < b.score; });
  }

  // joint sets (step 5), when no single candidate explains enough: pairs on the best singles,
  // then sets of three on the best pairs; the first set that explains enough and holds on the
  // chaos reference (dr.pairs[0] or dr.triples[0]), else nullptr
  const FittedSet* joint_set(const std::vector<Candidate>& candidates, DiagnosisRound& dr) {
    static_assert(kLargestSet == 3, "DiagnosisRound holds pairs and sets of three");
    // the best few of some sets (singles or pairs) that explain something: the bases of the next
    // size
    const auto bases_of = [](const auto& sets, const auto& members) {
      std::vector<std::vector<FittedEffect>> bases;
      for (const auto& set : sets)
        if (std::isfinite(set.score) && set.explained > 0.0 &&
            static_cast<int>(bases.size()) < kSetBases)
          bases.push_back(members(set));
      return bases;
    };
    const auto single = [](const FittedEffect& f) { return std::vector<FittedEffect>{f}; };
    const auto members = [](const FittedSet& s) { return s.members; };
    // too few singles to be bases (five comparable effects can leave every channel below the
    // singles' screen, docs/sim2real.md step 5): the candidates that screen left out whose channels
    // still hold a member's share (kMemberShare) are scanned and fitted now, as singles, to fill
    // the bases' free places (bases only: the round's single was decided on the singles' screen;
    // they join `fitted`, and `screened_out` keeps that screen's list)
    std::vector<std::vector<FittedEffect>> bases = bases_of(dr.fitted, single);
    if (bases.size() < static_cast<std::size_t>(kSetBases)) {
      DiagnosisRound members_screen;
      std::vector<const Candidate*> more;
      for (const Candidate* c : screen(candidates, members_screen, kMemberShare))
        if (std::find(dr.screened_out.begin(), dr.screened_out.end(), c->label()) !=
            dr.screened_out.end())
          more.push_back(c);
      if (!more.empty()) {
        say("sets: " + std::to_string(more.size()) +
            " candidates screened out as singles scanned as members of a set");
        DiagnosisRound extra;
        fit_best(scan(more, extra), extra);
        for (auto& f : extra.failed) dr.failed.push_back(f);
        for (const auto& b : bases_of(extra.fitted, single))
          if (bases.size() < static_cast<std::size_t>(kSetBases)) bases.push_back(b);
        dr.fitted.insert(dr.fitted.end(), extra.fitted.begin(), extra.fitted.end());
      }
    }
    // pairs on the best singles, the second candidate screened as a single would be
    dr.pairs = search_sets(candidates, dr, bases, kMinExplained);
    if (const FittedSet* set = accepted(dr, dr.pairs)) return set;
    // sets of three on the best pairs, where no pair removed enough (a pair that did but was
    // refused by the chaos check ends the search) and one could: were the shares additive, a set
    // that removes kMinExplained holds a pair that removes two thirds of it, so below that no
    // third member is searched (a diagnosis the candidates cannot explain stops here); the third
    // screened by a member's share of what the pair leaves
    if (dr.pairs.empty() || dr.pairs[0].explained >= kMinExplained ||
        dr.pairs[0].explained < kMinExplained * (kLargestSet - 1) / kLargestSet)
      return nullptr;
    dr.triples = search_sets(candidates, dr, bases_of(dr.pairs, members), kMemberShare);
    return accepted(dr, dr.triples);
  }

  // the best of some sets (best score first) when it removes kMinExplained and holds on the chaos
  // reference, else nullptr
  const FittedSet* accepted(DiagnosisRound& dr, const std::vector<FittedSet>& sets) {
    if (sets.empty() || sets[0].explained < kMinExplained) return nullptr;
    return holds_on_reference(dr, sets[0].specs(), sets[0].explained_on) ? &sets[0] : nullptr;
  }

  // each base (a set of fitted effects) provisionally in the model, one more candidate searched on
  // top of it (screened by `share` of what the base leaves; its scan on the threads), then all
  // refitted jointly (the fits of all the bases on the threads at once) and validated against the
  // excess before any of them; best score first
  std::vector<FittedSet> search_sets(const std::vector<Candidate>& candidates, DiagnosisRound& dr,
                                     const std::vector<std::vector<FittedEffect>>& bases,
                                     double share) {
    if (bases.empty()) return {};
    const Model before = model();
    const bool disjoint = d_.validation != d_.calibration;
    // the candidate of each member and of the one searched on top, and their values in that order
    struct Trial {
      std::vector<const Candidate*> members;
      std::vector<std::size_t> sizes;  // how many of x each member's
      std::vector<double> x;
      std::string base;                 // the base's labels, for the notes
      std::vector<std::string> labels;  // every member's, sorted: which set it is
    };
    const auto candidate_of = [&](const std::string& label) -> const Candidate* {
      for (const auto& c : candidates)
        if (c.label() == label) return &c;
      return nullptr;
    };
    // what the notes and the failures call this search and one of its sets
    const bool pairs = bases.front().size() == 1;
    const std::string kind = pairs ? "pairs" : "sets of three";
    const std::string one = pairs ? "pair" : "set of three";
    std::vector<Trial> trials;
    for (const auto& base : bases) {
      Trial t;
      std::vector<std::string> labels;
      labels.reserve(base.size() + 1);
      for (const auto& m : base) labels.push_back(m.candidate.label());
      t.base = listed(labels, " and ", " and ");
      try {
        // the base provisionally in the model: the screen and the scan see what it leaves
        for (const auto& m : base) found_specs_.push_back(m.spec);
        current_runs_ = simulate_all(nullptr);
        for (std::size_t i = 0; i < runs_.size(); ++i) {
          current_residuals_[i] = compute_residuals(current_runs_[i], runs_[i].run, sigma_[i]);
        }
        current_cal_ = mean_excess(current_residuals_, d_.calibration);
        current_val_ = mean_excess(current_residuals_, d_.validation);
        say(kind + ": " + t.base + " taken provisionally (excess " + message_number(current_cal_) +
            ")");
        DiagnosisRound inner;
        std::vector<const Candidate*> screened;
        for (const Candidate* c : screen(candidates, inner, share)) {
          const bool in_base = std::any_of(base.begin(), base.end(), [&](const FittedEffect& m) {
            return m.candidate.label() == c->label();
          });
          if (!in_base) screened.push_back(c);
        }
        std::vector<Scanned> scanned = scan(screened, inner);
        for (const auto& f : inner.failed) dr.failed.push_back(f);
        restore(before);
        if (scanned.empty()) continue;
        for (const auto& m : base) {
          t.members.push_back(candidate_of(m.candidate.label()));
          t.sizes.push_back(m.x.size());
          t.x.insert(t.x.end(), m.x.begin(), m.x.end());
        }
        t.members.push_back(scanned[0].c);
        t.sizes.push_back(scanned[0].x.size());
        t.x.insert(t.x.end(), scanned[0].x.begin(), scanned[0].x.end());
        t.labels = labels;
        t.labels.push_back(scanned[0].c->label());
        std::sort(t.labels.begin(), t.labels.end());
        // a set of three another base already reached ({A, B} + C and {A, C} + B) is fitted once
        // (pairs keep both orders, as before sets of three: each start its own joint fit)
        const bool again = !pairs && std::any_of(trials.begin(), trials.end(), [&](const Trial& u) {
          return u.labels == t.labels;
        });
        if (!again) trials.push_back(std::move(t));
      } catch (const Interrupted&) {
        throw;
      } catch (const std::exception& e) {
        restore(before);
        failed(dr, one + " with " + t.base, e.what());
      }
    }
    // all refitted together from their own values, on the calibration runs: each base's fit on
    // its own thread (the model is the one before the round again, and stays so)
    std::vector<FittedSet> fitted(trials.size());
    const std::vector<Failure> failures = run_tasks(trials.size(), threads_, [&](std::size_t k) {
      fitted[k] = fit_set(trials[k].members, trials[k].sizes, trials[k].x, disjoint);
    });
    std::vector<FittedSet> sets;
    for (std::size_t k = 0; k < trials.size(); ++k) {
      if (failures[k].failed) {
        failed(dr, one + " with " + trials[k].base, failures[k].what);
        continue;
      }
      say("  " + std::string(pairs ? "pair " : "set ") + listed(fitted[k].specs(), " + ", " + ") +
          ": explains " + message_number(100.0 * fitted[k].explained) + " % on the " +
          fitted[k].explained_on + " runs");
      sets.push_back(fitted[k]);
    }
    std::sort(sets.begin(), sets.end(),
              [](const auto& a, const auto& b) { return a.score < b.score; });
    return sets;
  }

  // the set (candidate k at the next sizes[k] values of x) fitted jointly from x on the
  // calibration runs and validated as one model: its shares against the excess before any of
  // them. The likelihood's joint optimum is the estimate, as a single fit's is (until 2026-12-01
  // a pair's start, each effect fitted on its own, was kept where its floored excess was lower:
  // near the floor that is noise)
  FittedSet fit_set(const std::vector<const Candidate*>& members,
                    const std::vector<std::size_t>& sizes, std::vector<double> x, bool disjoint) {
    auto split = [&](const std::vector<double>& y) {
      std::vector<std::pair<const Candidate*, std::vector<double>>> parts;
      auto at = y.begin();
      for (std::size_t k = 0; k < members.size(); ++k) {
        const auto next = at + static_cast<std::ptrdiff_t>(sizes[k]);
        parts.push_back({members[k], std::vector<double>(at, next)});
        at = next;
      }
      return parts;
    };
    auto score_set = [&](const std::vector<std::size_t>& which, const std::vector<double>& y) {
      return score_model(which, [&](std::size_t i) { return simulate_with(i, split(y)); });
    };
    minimise([&](const std::vector<double>& y) { return score_set(d_.calibration, y).log_ratio; },
             x, 0.5 / kScanPointsPerAxis2,
             kFitEvaluationsPerParameter * static_cast<int>(x.size()));
    FittedSet set;
    for (const auto& [c, xs] : split(x)) set.members.push_back(as_fitted(*c, xs));
    set.excess_calibration = score_set(d_.calibration, x).excess;
    set.excess_validation = disjoint ? score_set(d_.validation, x).excess : set.excess_calibration;
    const Share share = share_explained(set.excess_calibration, set.excess_validation);
    set.explained = share.explained;
    set.explained_on = share.on;
    const bool harmless =
        set.explained_on == "validation" || set.excess_validation < kSignificantExcess;
    set.score = harmless ? (set.explained_on == "validation" ? set.excess_validation
                                                             : set.excess_calibration) +
                               kParameterPenalty * static_cast<double>(x.size())
                         : HUGE_VAL;
    // each effect reports the set's shares (they are added together or not at all) and the others'
    // labels (a later refit changes their values, not their labels)
    for (FittedEffect& f : set.members) {
      for (const FittedEffect& other : set.members)
        if (&other != &f) f.fitted_with.push_back(other.candidate.label());
      f.excess_calibration = set.excess_calibration;
      f.excess_validation = set.excess_validation;
      f.explained = set.explained;
      f.explained_on = set.explained_on;
      f.score = set.score;
    }
    return set;
  }

  // a candidate at normalised values as a FittedEffect (its spec, JSON and parameters)
  FittedEffect as_fitted(const Candidate& c, const std::vector<double>& x) const {
    FittedEffect f;
    f.candidate = c;
    const auto effect = make_candidate(c, x, options_.plugins);
    f.effect = effect->to_json();
    f.spec = effect_spec(*effect);
    f.parameters = static_cast<int>(x.size());
    f.x = x;
    return f;
  }

  // the effect joins the model; every run is simulated again with it
  void add(const FittedEffect& f) {
    d_.found.push_back(f);
    found_specs_.push_back(f.spec);
    resimulate(f.excess_calibration, f.excess_validation);
  }

  // the model changed (found_specs_ as it now is; cal and val its mean excess on the calibration
  // and held-out runs): every run simulated again, the verdict's judgement stale
  void resimulate(double cal, double val) {
    judged_valid_ = false;
    current_cal_ = cal;
    current_val_ = val;
    current_runs_ = simulate_all(nullptr);
    for (std::size_t i = 0; i < runs_.size(); ++i) {
      current_runs_[i].summary.fidelity = "with-effects";
      current_residuals_[i] = compute_residuals(current_runs_[i], runs_[i].run, sigma_[i]);
    }
  }

  const std::vector<MeasuredRun>& runs_;
  const DiagnoseOptions& options_;
  const std::function<void(const std::string&)>& note_;
  std::vector<std::unique_ptr<Replay>> replays_;
  std::vector<std::vector<double>> sigma_;  // every run's channel noise
  std::vector<std::size_t> all_;            // 0 .. n-1
  bool any_pile_ = false;
  int threads_ = 1;                  // simulations at once
  std::atomic<int> simulations_{0};  // every simulation of the search, on any thread
  Diagnosis d_;
  // the model under test and every run's simulation and residuals under it
  std::vector<std::string> found_specs_;
  double current_cal_ = 0.0, current_val_ = 0.0;
  std::vector<Run> current_runs_;
  std::vector<Residuals> current_residuals_;
  // the current model's residuals as the last sensitivity judgement left them, when it judged
  // this model (judged_valid_); they decide "beyond noise" until the model changes
  std::vector<Residuals> judged_;
  bool judged_valid_ = false;
};

}  // namespace

Diagnosis diagnose(const std::vector<MeasuredRun>& runs, const DiagnoseOptions& options, Device* device,
                   const std::function<void(const std::string&)>& note) {
  if (runs.empty()) throw InputError("diagnose: no measured runs; give one or more run folders with --data");
  // the candidates checked before anything is simulated
  const std::vector<Candidate> candidates =
      chosen_candidates(candidate_set(options.plugins), options.candidates);
  const auto start = std::chrono::steady_clock::now();
  // the replays and the baseline
  Search search(runs, options, device, note);
  search.baseline();
  // rounds: one effect more each, while some run keeps an excess beyond noise
  for (int round = 0; round < options.max_effects && search.worst_run() >= kSignificantExcess; ++round) {
    if (!search.round(round + 1, candidates)) break;
    // what is left judged against the simulation's sensitivity to what was fitted
    search.judge("round " + std::to_string(round + 1));
  }
  // discovery: when what is left is beyond noise (and beyond the sensitivity), or when asked
  if (options.discover || search.worst_run() >= kSignificantExcess) {
    if (search.discover()) search.judge("discovery");
  }
  // the model with what was found, against the data
  Diagnosis d = search.finish();
  for (const auto& c : candidates) d.candidates.push_back(c.label());
  d.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return d;
}

nlohmann::json diagnosis_json(const Diagnosis& d) {
  using nlohmann::json;
  auto row_json = [](const TableRow& r) {
    return json{{"name", r.name}, {"E_x", r.e.e_x}, {"E_v", r.e.e_v}, {"E_tr", r.e.e_tr}, {"E_l", r.e.e_l},
                {"E_t", r.e.e_t}, {"E_M", r.e.e_m}, {"E_W", r.e.e_w}, {"mean", r.mean}};
  };
  auto table_json = [&](const std::vector<TableRow>& rows) {
    json t = row_json(mean_row(rows, "mean over runs"));
    t["runs"] = json::array();
    for (const auto& r : rows) t["runs"].push_back(row_json(r));
    return t;
  };
  auto residuals_json = [](const std::vector<Residuals>& per_run) {
    json a = json::array();
    for (const auto& res : per_run) {
      json cells = json::array();
      for (const auto& c : res.cells) {
        json cell = {{"channel", kChannelNames[c.channel]},
                     {"phase", res.phases[c.phase].name},
                     {"rms", c.rms},
                     {"mean", c.mean},
                     {"sigma", c.sigma},
                     {"excess", c.excess},
                     {"effective_samples", c.effective_samples}};
        // the simulation's own spread the cell was judged with (ensemble and sensitivity), when
        // there was one
        if (res.judged_with_spread()) {
          cell["spread"] = c.spread;
          cell["spread_share"] = c.spread_share;
          cell["null_samples"] = c.null_samples;
          cell["allowance"] = c.allowance;
        }
        cells.push_back(cell);
      }
      a.push_back({{"excess", res.excess}, {"cells", cells}});
    }
    return a;
  };
  // the simulation's own spread in a run's likelihood (sim2real/residuals.hpp): null when the
  // sensor noise alone judged it, else the piles, their variance's degrees of freedom and each
  // channel's mean share of the variance its residual was judged against, for the baseline and for
  // the model with what was found
  auto spread_json = [](const Residuals& before, const Residuals& after) {
    if (before.spread_members == 0) return json(nullptr);
    json share_before = json::object(), share_after = json::object();
    for (std::size_t c = 1; c < kChannelCount; ++c) {
      share_before[kChannelNames[c]] = before.spread_share_of(c);
      share_after[kChannelNames[c]] = after.spread_share_of(c);
    }
    // the members' variance's degrees of freedom per channel (null: taken as known exactly)
    json dof = nullptr;
    if (!before.variance_dof.empty()) {
      dof = json::object();
      for (std::size_t c = 1; c < kChannelCount; ++c)
        dof[kChannelNames[c]] = before.variance_dof[c];
    }
    return json{{"members", before.spread_members},
                {"variance_dof", dof},
                {"variance_share_before", share_before},
                {"variance_share_after", share_after}};
  };
  auto fitted_json = [](const FittedEffect& f) {
    return json{{"candidate", f.candidate.label()},
                {"effect", f.effect},
                {"spec", f.spec},
                {"parameters", f.parameters},
                {"excess_calibration", f.excess_calibration},
                {"excess_validation", f.excess_validation},
                {"explained", f.explained},
                {"explained_on", f.explained_on},
                {"score", f.score},
                {"simulations", f.simulations},
                {"fitted_with", f.fitted_with},
                {"window_local_minima", f.local_minima},
                {"roughness", std::isfinite(f.roughness) ? json(f.roughness) : json(nullptr)},
                {"trend_estimate", f.trend_estimate}};
  };
  json found = json::array();
  for (const auto& f : d.found) found.push_back({{"name", f.effect["name"]}, {"params", f.effect["params"]}});
  auto chaos_checks_json = [](const std::vector<ChaosCheck>& checks) {
    json out = json::array();
    for (const auto& c : checks)
      out.push_back({{"effects", c.effects},
                     {"excess_before", c.excess_before},
                     {"excess_with", c.excess_with},
                     {"explained", c.explained},
                     {"passed", c.passed},
                     {"simulations", c.simulations}});
    return out;
  };
  json rounds = json::array();
  for (const auto& r : d.rounds) {
    json fitted = json::array();
    for (const auto& f : r.fitted) fitted.push_back(fitted_json(f));
    json failed = json::array();
    for (const auto& [label, what] : r.failed)
      failed.push_back({{"candidate", label}, {"error", what}});
    auto sets_json = [](const std::vector<FittedSet>& sets) {
      json out = json::array();
      for (const auto& set : sets) {
        json labels = json::array();
        for (const auto& m : set.members) labels.push_back(m.candidate.label());
        out.push_back({{"candidates", labels},
                       {"specs", set.specs()},
                       {"excess_calibration", set.excess_calibration},
                       {"excess_validation", set.excess_validation},
                       {"explained", set.explained},
                       {"explained_on", set.explained_on},
                       {"score", set.score}});
      }
      return out;
    };
    json refit = nullptr;
    if (r.refit)
      refit = {{"before", r.refit->before},
               {"after", r.refit->after},
               {"excess_calibration_before", r.refit->excess_calibration_before},
               {"excess_calibration_after", r.refit->excess_calibration_after},
               {"excess_validation_before", r.refit->excess_validation_before},
               {"excess_validation_after", r.refit->excess_validation_after},
               {"log_ratio_before", r.refit->log_ratio_before},
               {"log_ratio_after", r.refit->log_ratio_after},
               {"kept", r.refit->kept},
               {"simulations", r.refit->simulations}};
    rounds.push_back({{"excess_before", r.excess_before},
                      {"screened_out", r.screened_out},
                      {"failed", failed},
                      {"fitted", fitted},
                      {"pairs", sets_json(r.pairs)},
                      {"triples", sets_json(r.triples)},
                      {"added", r.added},
                      {"chaos_checks", chaos_checks_json(r.chaos_checks)},
                      {"refit", refit}});
  }
  // the sensitivity judgements (docs/sim2real.md): each with its parameters' uncertainty, its cost
  // and every run's excess without and with the spread
  auto run_judgement_json = [](const SensitivityRun& r) {
    json j = {{"used", r.used},
              {"simulations", r.simulations},
              {"excess_without", r.excess_without},
              {"excess_with", r.excess_with}};
    if (!r.used) j["reason"] = r.reason;
    return j;
  };
  json sensitivity = json::array();
  int sensitivity_simulations = 0;
  for (const auto& j : d.sensitivity) {
    json parameters = json::array();
    for (const auto& p : j.parameters)
      parameters.push_back({{"effect", p.effect},
                            {"parameter", p.parameter},
                            {"unit", p.unit},
                            {"value", p.value},
                            {"standard_error_box", p.standard_error_box},
                            {"low", p.low},
                            {"high", p.high}});
    json per_run = json::array();
    for (const auto& r : j.runs) per_run.push_back(run_judgement_json(r));
    json entry = {{"after", j.after},
                  {"used", j.used},
                  {"parameters", parameters},
                  {"step_box", j.step},
                  {"curvature_in_range", j.curvature_in_range},
                  {"curvature_simulations", j.curvature_simulations},
                  {"effective_sample_share",
                   j.curvature_simulations > 0 ? json(j.effective_sample_share) : json(nullptr)},
                  {"design_points", j.design_points},
                  {"simulations", j.simulations()},
                  {"runs", per_run}};
    if (!j.used) entry["reason"] = j.reason;
    sensitivity.push_back(entry);
    sensitivity_simulations += j.simulations();
  }
  json runs = json::array();
  for (std::size_t i = 0; i < d.runs.size(); ++i) {
    const bool cal = std::find(d.calibration.begin(), d.calibration.end(), i) != d.calibration.end();
    const bool val = std::find(d.validation.begin(), d.validation.end(), i) != d.validation.end();
    json r = {{"dir", d.runs[i]}, {"role", cal && val ? "calibration and validation" : cal ? "calibration" : "validation"}};
    if (d.scan_rms_m[i]) r["scan_rms_m"] = *d.scan_rms_m[i];
    if (i < d.piles.size()) r["piles"] = d.piles[i];
    if (i < d.residuals_before.size() && i < d.residuals_after.size())
      r["model_spread"] = spread_json(d.residuals_before[i], d.residuals_after[i]);
    // the judgement that gave the verdict
    if (!d.sensitivity.empty() && i < d.sensitivity.back().runs.size())
      r["sensitivity_spread"] = run_judgement_json(d.sensitivity.back().runs[i]);
    runs.push_back(r);
  }
  // the correction discovered, with the error over the held-out runs before and after the model
  json discovered = nullptr;
  if (d.discovered) {
    discovered = correction_json(*d.discovered);
    std::vector<TableRow> before, after;
    for (std::size_t i : d.validation) {
      if (i < d.error_before.size()) before.push_back(d.error_before[i]);
      if (i < d.error_after.size()) after.push_back(d.error_after[i]);
    }
    discovered["error_before_held_out"] = row_json(mean_row(before, "mean over held-out runs"));
    discovered["error_after_held_out"] = row_json(mean_row(after, "mean over held-out runs"));
  }
  json tried = json::array();
  for (const auto& c : d.discovery_tried) tried.push_back(correction_json(c));
  return {
      {"effects_found", found},
      {"candidates", d.candidates},
      {"discovered", discovered},
      {"discovery",
       {{"ran", d.discovery_ran},
        {"tried", tried},
        {"chaos_checks", chaos_checks_json(d.discovery_chaos_checks)}}},
      {"error_before", table_json(d.error_before)},
      {"error_after", table_json(d.error_after)},
      {"unexplained", d.unexplained},
      {"excess_before", d.excess_before},
      {"excess_after", d.excess_after},
      {"significant_excess", kSignificantExcess},
      // whether any run's residual was judged against the simulation's own spread too
      {"model_spread_used", std::any_of(d.residuals_before.begin(), d.residuals_before.end(),
                                        [](const Residuals& r) { return r.spread_members > 0; })},
      // whether the verdict judged some run against the simulation's sensitivity to the fit
      {"sensitivity_used", !d.sensitivity.empty() && d.sensitivity.back().used},
      {"sensitivity", sensitivity},
      {"sensitivity_simulations", sensitivity_simulations},
      {"runs", runs},
      {"rounds", rounds},
      {"residuals_before", residuals_json(d.residuals_before)},
      {"residuals_after", residuals_json(d.residuals_after)},
      {"simulations", d.simulations},
      {"wall_s", d.wall_s}};
}

}  // namespace talus::sim2real
