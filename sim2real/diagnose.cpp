#include "sim2real/diagnose.hpp"

#include <nlopt.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <memory>
#include <sstream>

#include "host/error.hpp"

namespace talus::sim2real {

namespace {

// the power channel follows a changed force or speed reading (vehicle/effect.hpp), so a sensor
// effect's signature always includes it
constexpr std::size_t kPowerChannel = static_cast<std::size_t>(Channel::power);
// a parameter whose range spans this ratio or more (and excludes zero) is searched in log scale
constexpr double kLogScaleRatio = 10.0;
// the fit stops when a step in the normalised box is below this (0.1 % of the range)
constexpr double kFitTolerance = 1e-3;
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

std::string format_number(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", v);
  return text;
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

// the scan's values of one normalised parameter: cell centres of n equal cells
std::vector<double> scan_axis(int n) {
  std::vector<double> u(n);
  for (int i = 0; i < n; ++i) u[i] = (i + 0.5) / n;
  return u;
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

// bounded derivative-free minimisation in [0, 1]^n from x (changed in place); returns f(x)
double minimise(const std::function<double(const std::vector<double>&)>& f, std::vector<double>& x, double step,
                int max_evaluations) {
  const unsigned n = static_cast<unsigned>(x.size());
  Objective o{f, nullptr, nlopt_create(NLOPT_LN_BOBYQA, n)};
  if (!o.opt) throw Error("diagnose: NLopt could not create a BOBYQA optimiser");
  std::unique_ptr<std::remove_pointer_t<nlopt_opt>, decltype(&nlopt_destroy)> guard(o.opt, &nlopt_destroy);
  nlopt_set_lower_bounds1(o.opt, 0.0);
  nlopt_set_upper_bounds1(o.opt, 1.0);
  nlopt_set_min_objective(o.opt, &nlopt_objective, &o);
  nlopt_set_maxeval(o.opt, max_evaluations);
  nlopt_set_xtol_abs1(o.opt, kFitTolerance);
  nlopt_set_initial_step1(o.opt, step);
  double best = HUGE_VAL;
  const nlopt_result r = nlopt_optimize(o.opt, x.data(), &best);
  if (o.error) std::rethrow_exception(o.error);
  // running out of evaluations or meeting a tolerance both leave the best point found
  if (r < 0 && r != NLOPT_ROUNDOFF_LIMITED) throw Error("diagnose: NLopt BOBYQA failed (code " + std::to_string(r) + ")");
  return best;
}

double mean_of(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x;
  return v.empty() ? 0.0 : s / v.size();
}

}  // namespace

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
    for (const auto& name : plugin->effect_names()) out.push_back({name, "", {}, false});
  return out;
}

TableRow mean_row(const std::vector<TableRow>& rows, const std::string& name) {
  TableRow m;
  m.name = name;
  std::array<double, 7> sum{};
  for (const auto& r : rows) {
    const auto a = r.e.as_array();
    for (std::size_t i = 0; i < 7; ++i) sum[i] += std::abs(a[i]);
  }
  const double n = rows.empty() ? 1.0 : double(rows.size());
  m.e = {sum[0] / n, sum[1] / n, sum[2] / n, sum[3] / n, sum[4] / n, sum[5] / n, sum[6] / n};
  double means = 0.0;
  for (const auto& r : rows) means += r.mean;
  m.mean = means / n;
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
};

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
  }

  // the baseline: residuals and the paper's error rows; the current model is the baseline
  void baseline() {
    for (std::size_t i = 0; i < runs_.size(); ++i) {
      Run r = simulate(i, nullptr);
      r.summary.fidelity = "baseline";
      d_.simulated_before.push_back(r);
      d_.residuals_before.push_back(compute_residuals(r, runs_[i].run, sigma_[i]));
      const Comparison c = compare_runs(r, runs_[i].run, CompareOptions{});
      d_.error_before.push_back({runs_[i].run.label(), c.e, c.mean});
      d_.scan_rms_m.push_back(replays_[i]->scan_rms_m());
    }
    d_.excess_before = mean_excess(d_.residuals_before, all_);
    say("baseline: excess " + format_number(d_.excess_before) + " per run (noise alone leaves less than " +
        format_number(kSignificantExcess) + "), mean error " + format_number(mean_row(d_.error_before, "").mean));
    current_cal_ = mean_excess(d_.residuals_before, d_.calibration);
    current_val_ = mean_excess(d_.residuals_before, d_.validation);
    current_runs_ = d_.simulated_before;
    current_residuals_ = d_.residuals_before;
  }

  // the largest excess of any run under the current model: one run beyond noise is enough to
  // search (a mean would hide it among runs the effect does not touch)
  double worst_run() const {
    double worst = 0.0;
    for (const auto& r : current_residuals_) worst = std::max(worst, r.excess);
    return worst;
  }

  // one round: one effect more when a candidate explains enough of what is left; false when none
  bool round(int number, const std::vector<Candidate>& candidates) {
    DiagnosisRound dr;
    dr.excess_before = current_val_;
    const std::vector<const Candidate*> screened = screen(candidates, dr);
    say("round " + std::to_string(number) + ": " + std::to_string(screened.size()) + " candidates to scan, " +
        std::to_string(dr.screened_out.size()) + " screened out by their signature");
    std::vector<Scanned> scanned = scan(screened);
    // 3. fit the best few; 4. validate them with the parameter penalty
    for (std::size_t j = 0; j < scanned.size() && j < static_cast<std::size_t>(kFitted); ++j) {
      if (!(scanned[j].score.excess < current_cal_)) break;  // no better than the model without it
      dr.fitted.push_back(fit(scanned[j]));
    }
    std::sort(dr.fitted.begin(), dr.fitted.end(), [](const auto& a, const auto& b) { return a.score < b.score; });
    // 5. add the winner only when it explains enough of what is left
    if (!dr.fitted.empty() && dr.fitted[0].explained >= kMinExplained) {
      dr.added = true;
      add(dr.fitted[0]);
      say("round " + std::to_string(number) + ": added " + dr.fitted[0].spec);
    } else {
      say("round " + std::to_string(number) + ": no candidate explains " + format_number(100.0 * kMinExplained) +
          " % of the excess left; nothing added");
    }
    d_.rounds.push_back(dr);
    return dr.added;
  }

  // discovery: a learned correction per target, fitted on the calibration runs against the current
  // model, simulated on every run; the best added when it explains enough of what is left
  void discover() {
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
    say("discovery: " + std::to_string(3 + channels.size()) +
        " targets (the drive, lift and tilt speeds" +
        (channels.empty() ? std::string() : ", the readings with an excess of their own") + ")");
    // the machine of the first calibration run (every run of one diagnosis replays one machine)
    const vehicle::MachineDescription machine =
        vehicle::parse_machine(vehicle::machine_file(replays_[d_.calibration.front()]->scenario()));
    for (const DiscoveryTarget& target : discovery_targets(channels)) {
      DiscoveredCorrection c = fit_correction(
          target, regression_data(target, measured, simulated, command_limit(target, machine)));
      if (c.terms.empty()) {
        say("  " + target.label() + ": no sparse model cuts the held-out residual (mean square " +
            format_number(c.cv_mse_none) + ")");
        d_.discovery_tried.push_back(c);
        continue;
      }
      say("  " + target.label() + ": " + c.expression);
      evaluate(c);
      say("    explains " + format_number(100.0 * c.explained) + " % of the excess on the " +
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
      DiscoveredCorrection refined = refine(*best);
      if (refined.explained > best->explained) {
        say("  refined: " + refined.expression + ", explains " +
            format_number(100.0 * refined.explained) + " %");
        d_.discovery_tried.push_back(refined);
      }
    }
    // the best simulated correction, if it explains enough
    const DiscoveredCorrection* best = best_of();
    if (!best || best->explained < kMinExplained) {
      say("discovery: no correction explains " + format_number(100.0 * kMinExplained) +
          " % of the excess left");
      return;
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
  }

  // the correction simulated on every run: its excess, the share it explains (counted as a
  // candidate's) and the channels whose excess it lowers
  void evaluate(DiscoveredCorrection& c) {
    std::vector<Residuals> after(runs_.size());
    for (std::size_t i = 0; i < runs_.size(); ++i)
      after[i] = compute_residuals(simulate(i, vehicle::make_effect(c.spec, options_.plugins)),
                                   runs_[i].run, sigma_[i]);
    const bool disjoint = d_.validation != d_.calibration;
    c.simulated = true;
    c.excess_calibration = mean_excess(after, d_.calibration);
    c.excess_validation = mean_excess(after, d_.validation);
    if (current_val_ >= kSignificantExcess || !disjoint) {
      c.explained = current_val_ > 0.0 ? (current_val_ - c.excess_validation) / current_val_ : 0.0;
      c.explained_on = "validation";
    } else {
      c.explained = c.excess_validation < kSignificantExcess && current_cal_ > 0.0
                        ? (current_cal_ - c.excess_calibration) / current_cal_
                        : 0.0;
      c.explained_on = "calibration";
    }
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
    c.refined = true;
    evaluate(c);
    return c;
  }

  // after: the runs with the effects found (the last round's simulations)
  Diagnosis finish() {
    d_.simulated_after = current_runs_;
    d_.residuals_after = current_residuals_;
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

  // run i simulated with the effects found so far plus, optionally, a candidate
  Run simulate(std::size_t i, std::unique_ptr<vehicle::Effect> extra) {
    vehicle::EffectSet set;
    for (const auto& spec : found_specs_) set.add(vehicle::make_effect(spec, options_.plugins));
    if (extra) set.add(std::move(extra));
    Run r = replays_[i]->simulate(set);
    ++d_.simulations;
    return r;
  }

  // the mean excess and log-ratio per run of the runs `which` with the candidate at x
  Score score_runs(const std::vector<std::size_t>& which, const Candidate* c, const std::vector<double>& x) {
    std::vector<double> e, l;
    for (std::size_t i : which) {
      const Run r = simulate(i, c ? make_candidate(*c, x, options_.plugins) : nullptr);
      const Residuals res = compute_residuals(r, runs_[i].run, sigma_[i]);
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

  // 1. the signature screen: candidates not yet found whose channels hold enough excess
  std::vector<const Candidate*> screen(const std::vector<Candidate>& candidates, DiagnosisRound& dr) const {
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
        if (mean_of(bound) < kMinExplained * current_cal_ || mean_of(own) < kSignificantExcess) {
          dr.screened_out.push_back(c.label());
          continue;
        }
      }
      screened.push_back(&c);
    }
    return screened;
  }

  // 2. the coarse scan on the calibration runs: each candidate's best grid point, best first
  std::vector<Scanned> scan(const std::vector<const Candidate*>& screened) {
    std::vector<Scanned> scanned;
    for (const Candidate* c : screened) {
      const int k = parameter_count(*c, options_.plugins);
      if (k == 0 || k > 2) {
        say("  " + c->label() + ": " + std::to_string(k) + " parameters; only effects with 1 or 2 are fitted, skipped");
        continue;
      }
      std::vector<std::vector<double>> points;
      if (k == 1) {
        for (double u : scan_axis(kScanPoints)) points.push_back({u});
      } else {
        for (double u : scan_axis(kScanPointsPerAxis2))
          for (double v : scan_axis(kScanPointsPerAxis2)) points.push_back({u, v});
      }
      Scanned best{c, points[0], Score{}, k};
      for (const auto& x : points) {
        const Score e = score_runs(d_.calibration, c, x);
        if (e < best.score) best = {c, x, e, k};
      }
      say("  scan " + c->label() + ": best excess " + format_number(best.score.excess) + " (now " +
          format_number(current_cal_) + ")");
      scanned.push_back(best);
    }
    std::sort(scanned.begin(), scanned.end(), [](const auto& a, const auto& b) { return a.score < b.score; });
    return scanned;
  }

  // 3. and 4.: the likelihood's optimum from the best scan point (kept only if its excess is no
  // worse), then its excess on the held-out runs, the share it explains and its penalised score
  FittedEffect fit(Scanned& s) {
    const int before = d_.simulations;
    const bool disjoint = d_.validation != d_.calibration;
    const double step = 0.5 / (s.parameters == 1 ? kScanPoints : kScanPointsPerAxis2);
    std::vector<double> x = s.x;
    minimise([&](const std::vector<double>& y) { return score_runs(d_.calibration, s.c, y).log_ratio; }, x, step,
             kFitEvaluations);
    const Score fitted = score_runs(d_.calibration, s.c, x);
    if (fitted.excess <= s.score.excess) s.x = x;
    FittedEffect f;
    f.candidate = *s.c;
    const auto effect = make_candidate(*s.c, s.x, options_.plugins);
    f.effect = effect->to_json();
    f.spec = effect_spec(*effect);
    f.parameters = s.parameters;
    f.excess_calibration = std::min(fitted.excess, s.score.excess);
    f.excess_validation = disjoint ? score_runs(d_.validation, s.c, s.x).excess : f.excess_calibration;
    // the share it explains of what the held-out runs leave; when they leave nothing beyond
    // noise (the effect does not show in them), the share of the calibration runs', provided
    // it keeps the held-out runs within noise
    if (current_val_ >= kSignificantExcess || !disjoint) {
      f.explained = current_val_ > 0.0 ? (current_val_ - f.excess_validation) / current_val_ : 0.0;
      f.explained_on = "validation";
    } else {
      f.explained = f.excess_validation < kSignificantExcess && current_cal_ > 0.0
                        ? (current_cal_ - f.excess_calibration) / current_cal_
                        : 0.0;
      f.explained_on = "calibration";
    }
    // the score ranks on the runs the share is counted on; a candidate that pushes held-out runs
    // beyond noise ranks last
    const bool harmless = f.explained_on == "validation" || f.excess_validation < kSignificantExcess;
    f.score = harmless ? (f.explained_on == "validation" ? f.excess_validation : f.excess_calibration) +
                             kParameterPenalty * f.parameters
                       : HUGE_VAL;
    f.simulations = d_.simulations - before;
    say("  fit " + f.spec + ": excess calibration " + format_number(f.excess_calibration) + ", validation " +
        format_number(f.excess_validation) + " (explains " + format_number(100.0 * f.explained) + " % on the " +
        f.explained_on + " runs)");
    return f;
  }

  // the effect joins the model; every run is simulated again with it
  void add(const FittedEffect& f) {
    d_.found.push_back(f);
    found_specs_.push_back(f.spec);
    current_cal_ = f.excess_calibration;
    current_val_ = f.excess_validation;
    for (std::size_t i = 0; i < runs_.size(); ++i) {
      current_runs_[i] = simulate(i, nullptr);
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
  Diagnosis d_;
  // the model under test and every run's simulation and residuals under it
  std::vector<std::string> found_specs_;
  double current_cal_ = 0.0, current_val_ = 0.0;
  std::vector<Run> current_runs_;
  std::vector<Residuals> current_residuals_;
};

}  // namespace

Diagnosis diagnose(const std::vector<MeasuredRun>& runs, const DiagnoseOptions& options, Device* device,
                   const std::function<void(const std::string&)>& note) {
  if (runs.empty()) throw InputError("diagnose: no measured runs; give one or more run folders with --data");
  const auto start = std::chrono::steady_clock::now();
  // the replays and the baseline
  Search search(runs, options, device, note);
  search.baseline();
  // rounds: one effect more each, while some run keeps an excess beyond noise
  const std::vector<Candidate> candidates = candidate_set(options.plugins);
  for (int round = 0; round < options.max_effects && search.worst_run() >= kSignificantExcess; ++round) {
    if (!search.round(round + 1, candidates)) break;
  }
  // discovery: when what is left is beyond noise, or when asked
  if (options.discover || search.worst_run() >= kSignificantExcess) search.discover();
  // the model with what was found, against the data
  Diagnosis d = search.finish();
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
      for (const auto& c : res.cells)
        cells.push_back({{"channel", kChannelNames[c.channel]}, {"phase", res.phases[c.phase].name},
                         {"rms", c.rms}, {"mean", c.mean}, {"sigma", c.sigma}, {"excess", c.excess}});
      a.push_back({{"excess", res.excess}, {"cells", cells}});
    }
    return a;
  };
  auto fitted_json = [](const FittedEffect& f) {
    return json{{"candidate", f.candidate.label()}, {"effect", f.effect}, {"spec", f.spec},
                {"parameters", f.parameters}, {"excess_calibration", f.excess_calibration},
                {"excess_validation", f.excess_validation}, {"explained", f.explained},
                {"explained_on", f.explained_on}, {"score", f.score},
                {"simulations", f.simulations}};
  };
  json found = json::array();
  for (const auto& f : d.found) found.push_back({{"name", f.effect["name"]}, {"params", f.effect["params"]}});
  json rounds = json::array();
  for (const auto& r : d.rounds) {
    json fitted = json::array();
    for (const auto& f : r.fitted) fitted.push_back(fitted_json(f));
    rounds.push_back({{"excess_before", r.excess_before}, {"screened_out", r.screened_out}, {"fitted", fitted}, {"added", r.added}});
  }
  json runs = json::array();
  for (std::size_t i = 0; i < d.runs.size(); ++i) {
    const bool cal = std::find(d.calibration.begin(), d.calibration.end(), i) != d.calibration.end();
    const bool val = std::find(d.validation.begin(), d.validation.end(), i) != d.validation.end();
    json r = {{"dir", d.runs[i]}, {"role", cal && val ? "calibration and validation" : cal ? "calibration" : "validation"}};
    if (d.scan_rms_m[i]) r["scan_rms_m"] = *d.scan_rms_m[i];
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
  return {{"effects_found", found},
          {"discovered", discovered},
          {"discovery", {{"ran", d.discovery_ran}, {"tried", tried}}},
          {"error_before", table_json(d.error_before)},
          {"error_after", table_json(d.error_after)},
          {"unexplained", d.unexplained},
          {"excess_before", d.excess_before},
          {"excess_after", d.excess_after},
          {"significant_excess", kSignificantExcess},
          {"runs", runs},
          {"rounds", rounds},
          {"residuals_before", residuals_json(d.residuals_before)},
          {"residuals_after", residuals_json(d.residuals_after)},
          {"simulations", d.simulations},
          {"wall_s", d.wall_s}};
}

}  // namespace talus::sim2real
