#include "sim2real/replay.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "digging/digging.hpp"
#include "host/device.hpp"
#include "host/error.hpp"
#include "host/interrupt.hpp"
#include "sim2real/residuals.hpp"
#include "terrain/pile.hpp"
#include "vehicle/data_file.hpp"
#include "vehicle/wheel_loader.hpp"

namespace talus::sim2real {

vehicle::SensorLog simulate_on_flat_ground(const vehicle::Scenario& sc, vehicle::EffectSet& effects,
                                           Progress* progress) {
  vehicle::WheelLoader loader(vehicle::machine_file(sc), sc.payload);
  vehicle::SensorLog log(100.0);
  const int steps = static_cast<int>(std::llround(sc.duration / sc.timestep));
  // the first sample at rest, through the effects (an empty set is the identity)
  vehicle::start_with_effects(loader, effects, log, sc);
  for (int k = 0; k < steps; ++k) {
    // feedforward targets at the start of the step; the clock counts steps
    const double h = sc.timestep;
    const double t = k * h;
    vehicle::step_with_effects(loader, effects, t, h, (k + 1) * h, {sc.drive(t), sc.lift(t), sc.tilt(t)},
                               [&] { loader.step(h); }, &log);
    if (progress) progress->update((k + 1) * sc.timestep);
    // asked to stop (host/interrupt.hpp): between steps, with or without a progress line
    if (interrupt_requested())
      throw_if_interrupted(sc.name + " on flat ground at t = " + std::to_string((k + 1) * h) +
                           " s");
  }
  return log;
}

Run vehicle_run(const vehicle::Scenario& scenario, const vehicle::SensorLog& log) {
  Run run;
  run.series = to_timeseries(log.samples());
  run.summary.scenario = scenario.name;
  run.summary.fidelity = "vehicle";
  run.summary.loaded_mass_kg = scenario.payload;
  run.summary.work_J = log.work();
  // the digging phase its effects saw (vehicle::start_with_effects), where the scenario has one
  if (scenario.dig_end > scenario.dig_start) {
    run.summary.dig_start_s = scenario.dig_start;
    run.summary.dig_end_s = scenario.dig_end;
  }
  return run;
}

Run dig_run(const vehicle::Scenario& scenario, const std::string& fidelity, const DiggingSimulation& sim) {
  Run run;
  run.series = to_timeseries(sim.log().samples());
  run.summary.scenario = scenario.name;
  run.summary.fidelity = fidelity;
  run.summary.loaded_mass_kg = sim.loaded_mass();
  run.summary.work_J = vehicle::work_between(sim.log().samples(), scenario.dig_start, scenario.dig_end);
  run.summary.dig_start_s = scenario.dig_start;
  run.summary.dig_end_s = scenario.dig_end;
  return run;
}

namespace {

// every member on the first's time base, labels and marks (Error naming the first that differs)
void check_members(const std::vector<Run>& runs, const std::string& who) {
  if (runs.empty()) throw Error(who + ": no runs");
  const Run& first = runs.front();
  for (std::size_t m = 1; m < runs.size(); ++m) {
    const Run& r = runs[m];
    const std::string which = who + ": run " + std::to_string(m) + " (" + r.label() + ")";
    if (r.series.size() != first.series.size() || r.series[Channel::t] != first.series[Channel::t])
      throw Error(which +
                  " has other sample times than run 0; an ensemble shares its scenario and level");
    if (r.summary.scenario != first.summary.scenario ||
        r.summary.fidelity != first.summary.fidelity ||
        r.summary.dig_start_s != first.summary.dig_start_s ||
        r.summary.dig_end_s != first.summary.dig_end_s)
      throw Error(which + " has another scenario, level or phase marks than run 0");
  }
}

// a per-sample variance pooled: each sample the mean of those within ±half_window_s of it (the
// window shrinks at the run's ends)
std::vector<double> pooled(const std::vector<double>& t, const std::vector<double>& raw,
                           double half_window_s) {
  const std::size_t samples = t.size();
  std::vector<double> out(samples, 0.0);
  std::size_t lo = 0, hi = 0;  // the window [lo, hi) of sample i
  for (std::size_t i = 0; i < samples; ++i) {
    while (t[lo] < t[i] - half_window_s) ++lo;
    while (hi < samples && t[hi] <= t[i] + half_window_s) ++hi;
    double sum = 0.0;
    for (std::size_t j = lo; j < hi; ++j) sum += raw[j];
    out[i] = sum / static_cast<double>(hi - lo);
  }
  return out;
}

// the mean number of samples a window of ±half_window_s pools over the run (pooled's windows)
double mean_window_samples(const std::vector<double>& t, double half_window_s) {
  if (t.empty()) return 1.0;
  double sum = 0.0;
  std::size_t lo = 0, hi = 0;
  for (std::size_t i = 0; i < t.size(); ++i) {
    while (t[lo] < t[i] - half_window_s) ++lo;
    while (hi < t.size() && t[hi] <= t[i] + half_window_s) ++hi;
    sum += static_cast<double>(hi - lo);
  }
  return sum / static_cast<double>(t.size());
}

// per run, per channel: a series whose squares a variance pools
using Departures = std::vector<std::vector<std::vector<double>>>;

// τ per channel (index as kChannelNames, t's 0): the integrated autocorrelation time of the
// departures, each run its own segment
std::vector<double> departure_times(const Departures& departures) {
  std::vector<double> tau(kChannelCount, 0.0);
  for (std::size_t c = 0; c < kChannelCount; ++c) {
    if (static_cast<Channel>(c) == Channel::t) continue;
    std::vector<double> z;
    std::vector<int> segment;
    for (std::size_t k = 0; k < departures.size(); ++k) {
      z.insert(z.end(), departures[k][c].begin(), departures[k][c].end());
      segment.insert(segment.end(), departures[k][c].size(), static_cast<int>(k));
    }
    tau[c] = integrated_autocorrelation_time(z, segment);
  }
  return tau;
}

// ν = per_sample · max(1, m / τ) per channel
std::vector<double> pooled_dof(const std::vector<double>& t, const std::vector<double>& tau,
                               double per_sample, double half_window_s) {
  const double window = mean_window_samples(t, half_window_s);
  std::vector<double> dof(kChannelCount, 0.0);
  for (std::size_t c = 0; c < kChannelCount; ++c)
    if (static_cast<Channel>(c) != Channel::t) dof[c] = per_sample * std::max(1.0, window / tau[c]);
  return dof;
}

// each member's departure from the members' mean (checked as ensemble_variance's, naming `who`)
Departures ensemble_departures(const std::vector<Run>& runs, const std::string& who) {
  check_members(runs, who);
  if (runs.size() < 2)
    throw Error(who + ": " + std::to_string(runs.size()) +
                " run; a sample variance needs 2 or more members");
  const std::size_t samples = runs.front().series.size();
  const double n = static_cast<double>(runs.size());
  Departures departures(runs.size(), std::vector<std::vector<double>>(kChannelCount));
  for (std::size_t c = 0; c < kChannelCount; ++c) {
    if (static_cast<Channel>(c) == Channel::t) continue;
    for (auto& d : departures) d[c].resize(samples);
    for (std::size_t i = 0; i < samples; ++i) {
      double mean = 0.0;
      for (const Run& r : runs) mean += r.series.columns[c][i];
      mean /= n;
      for (std::size_t k = 0; k < runs.size(); ++k)
        departures[k][c][i] = runs[k].series.columns[c][i] - mean;
    }
  }
  return departures;
}

// each perturbed run's departure from the fitted one (checked as sensitivity_variance's)
Departures sensitivity_departures(const Run& fitted, const std::vector<Run>& perturbed,
                                  const std::string& who) {
  if (perturbed.empty())
    throw Error(who +
                ": no perturbed runs; give the simulations at parameters within the fit's "
                "uncertainty");
  std::vector<Run> all = {fitted};
  all.insert(all.end(), perturbed.begin(), perturbed.end());
  check_members(all, who);
  Departures departures(perturbed.size(), std::vector<std::vector<double>>(kChannelCount));
  for (std::size_t k = 0; k < perturbed.size(); ++k)
    for (std::size_t c = 0; c < kChannelCount; ++c) {
      if (static_cast<Channel>(c) == Channel::t) continue;
      const auto& x = perturbed[k].series.columns[c];
      const auto& centre = fitted.series.columns[c];
      departures[k][c].resize(x.size());
      for (std::size_t i = 0; i < x.size(); ++i) departures[k][c][i] = x[i] - centre[i];
    }
  return departures;
}

void check_window(double half_window_s, const std::string& who) {
  if (!(half_window_s >= 0.0) || !std::isfinite(half_window_s))
    throw Error(who + ": half_window_s = " + message_number(half_window_s) +
                "; give a finite window of 0 s (no pooling) or more");
}

}  // namespace

TimeSeries ensemble_variance(const std::vector<Run>& runs, double half_window_s) {
  check_members(runs, "ensemble_variance");
  if (runs.size() < 2)
    throw Error("ensemble_variance: " + std::to_string(runs.size()) +
                " run; a sample variance needs 2 or more members");
  check_window(half_window_s, "ensemble_variance");
  const auto& t = runs.front().series[Channel::t];
  const std::size_t samples = t.size();
  const double n = static_cast<double>(runs.size());
  TimeSeries variance;
  variance[Channel::t] = t;
  for (std::size_t c = 0; c < kChannelCount; ++c) {
    if (static_cast<Channel>(c) == Channel::t) continue;
    // the unbiased sample variance at each sample: the members' mean first, then their squared
    // departures from it (two passes: members that agree give exactly 0)
    std::vector<double> raw(samples, 0.0);
    for (std::size_t i = 0; i < samples; ++i) {
      double mean = 0.0;
      for (const Run& r : runs) mean += r.series.columns[c][i];
      mean /= n;
      double sum2 = 0.0;
      for (const Run& r : runs) {
        const double d = r.series.columns[c][i] - mean;
        sum2 += d * d;
      }
      raw[i] = sum2 / (n - 1.0);
    }
    // pooled: the mean of the samples within ±half_window_s
    variance.columns[c] = pooled(t, raw, half_window_s);
  }
  return variance;
}

std::vector<double> ensemble_departure_time(const std::vector<Run>& runs) {
  return departure_times(ensemble_departures(runs, "ensemble_departure_time"));
}

std::vector<double> ensemble_dof(const std::vector<Run>& runs, double half_window_s) {
  const Departures departures = ensemble_departures(runs, "ensemble_dof");
  check_window(half_window_s, "ensemble_dof");
  return pooled_dof(runs.front().series[Channel::t], departure_times(departures),
                    static_cast<double>(runs.size()) - 1.0, half_window_s);
}

std::vector<double> sensitivity_departure_time(const Run& fitted,
                                               const std::vector<Run>& perturbed) {
  return departure_times(sensitivity_departures(fitted, perturbed, "sensitivity_departure_time"));
}

std::vector<double> sensitivity_dof(const Run& fitted, const std::vector<Run>& perturbed,
                                    double half_window_s) {
  const Departures departures = sensitivity_departures(fitted, perturbed, "sensitivity_dof");
  check_window(half_window_s, "sensitivity_dof");
  // M departures from one shared run, correlated by ½ where it is chaotic (the header comment)
  const double m = static_cast<double>(perturbed.size());
  return pooled_dof(fitted.series[Channel::t], departure_times(departures),
                    m / (1.0 + (m - 1.0) / 4.0), half_window_s);
}

TimeSeries sensitivity_variance(const Run& fitted, const std::vector<Run>& perturbed,
                                double half_window_s) {
  if (perturbed.empty())
    throw Error(
        "sensitivity_variance: no perturbed runs; give the simulations at parameters "
        "within the fit's uncertainty");
  std::vector<Run> all = {fitted};
  all.insert(all.end(), perturbed.begin(), perturbed.end());
  check_members(all, "sensitivity_variance");
  check_window(half_window_s, "sensitivity_variance");
  const auto& t = fitted.series[Channel::t];
  const double m = static_cast<double>(perturbed.size());
  TimeSeries s;
  s[Channel::t] = t;
  for (std::size_t c = 0; c < kChannelCount; ++c) {
    if (static_cast<Channel>(c) == Channel::t) continue;
    // the mean square departure from the fitted run: its own value is the centre (not the
    // perturbed runs' mean), as the measured run is compared with the fitted one
    std::vector<double> raw(t.size(), 0.0);
    for (std::size_t i = 0; i < t.size(); ++i) {
      double sum2 = 0.0;
      for (const Run& r : perturbed) {
        const double d = r.series.columns[c][i] - fitted.series.columns[c][i];
        sum2 += d * d;
      }
      raw[i] = sum2 / m;
    }
    s.columns[c] = pooled(t, raw, half_window_s);
  }
  return s;
}

Run ensemble_mean(const std::vector<Run>& runs) {
  check_members(runs, "ensemble_mean");
  const Run& first = runs.front();
  if (runs.size() == 1) return first;
  // sums in member order, then one division: the same runs give the same mean, bit for bit
  Run mean = first;
  const double n = static_cast<double>(runs.size());
  for (std::size_t c = 0; c < kChannelCount; ++c) {
    if (static_cast<Channel>(c) == Channel::t) continue;
    auto& column = mean.series.columns[c];
    for (std::size_t m = 1; m < runs.size(); ++m)
      for (std::size_t i = 0; i < column.size(); ++i) column[i] += runs[m].series.columns[c][i];
    for (double& v : column) v /= n;
  }
  for (std::size_t m = 1; m < runs.size(); ++m) {
    mean.summary.loaded_mass_kg += runs[m].summary.loaded_mass_kg;
    mean.summary.work_J += runs[m].summary.work_J;
  }
  mean.summary.loaded_mass_kg /= n;
  mean.summary.work_J /= n;
  mean.summary.details["pile_ensemble"] = runs.size();
  // the members' spread, which the residuals add to the sensor noise (sim2real/residuals.hpp):
  // the departures' τ found once, the degrees of freedom from it (ensemble_dof's law)
  const std::vector<double> tau = ensemble_departure_time(runs);
  mean.spread = RunSpread{static_cast<int>(runs.size()),
                          ensemble_variance(runs),
                          0,
                          {},
                          pooled_dof(first.series[Channel::t], tau, n - 1.0, kSpreadHalfWindow),
                          {},
                          tau,
                          {}};
  return mean;
}

vehicle::Scenario measured_scenario(const MeasuredRun& measured) {
  vehicle::Scenario sc;
  try {
    sc = vehicle::load_scenario(measured.meta.scenario);
  } catch (const InputError& e) {
    throw InputError((measured.run.dir / kMetadataFile).string() + ": field 'scenario': " + e.what() +
                     "; the loop simulates the run with that scenario's machine, pile and timing");
  }
  // the run's own inputs and pile position
  sc.drive = vehicle::PiecewiseLinear(measured.meta.drive);
  sc.lift = vehicle::PiecewiseLinear(measured.meta.lift);
  sc.tilt = vehicle::PiecewiseLinear(measured.meta.tilt);
  if (sc.pile) sc.pile_toe_x = measured.meta.pile_toe_x_m;
  // as long as the measurement, rounded up to whole steps of any level (20 ms, D400's, is a multiple
  // of every timestep: 2.5, 5, 10, 20 ms), so every measured sample has a simulated one
  constexpr double kStepGrain = 0.02;  // s
  const auto& t = measured.run.series[Channel::t];
  if (!t.empty()) sc.duration = std::max(sc.duration, std::ceil(t.back() / kStepGrain - 1e-9) * kStepGrain);
  if (measured.run.summary.dig_start_s) sc.dig_start = *measured.run.summary.dig_start_s;
  if (measured.run.summary.dig_end_s) sc.dig_end = *measured.run.summary.dig_end_s;
  return sc;
}

namespace {

// RMS of z_a - z_b over the x range both scans cover (linear between points, 1 cm spacing)
std::optional<double> scan_difference(const Series2& a, const std::vector<Eigen::Vector2d>& b) {
  if (a.size() < 2 || b.size() < 2) return std::nullopt;
  std::vector<double> xa, za, xb, zb;
  for (const auto& [x, z] : a) xa.push_back(x), za.push_back(z);
  for (const auto& p : b) xb.push_back(p.x()), zb.push_back(p.y());
  // b's x must increase strictly for interpolate(); the scanner's points do, except repeats
  std::vector<double> xs, zs;
  for (size_t i = 0; i < xb.size(); ++i)
    if (xs.empty() || xb[i] > xs.back()) xs.push_back(xb[i]), zs.push_back(zb[i]);
  const double lo = std::max(xa.front(), xs.front()), hi = std::min(xa.back(), xs.back());
  if (!(hi > lo) || xs.size() < 2) return std::nullopt;
  constexpr double kSpacing = 0.01;  // m
  std::vector<double> at;
  for (double x = lo; x <= hi; x += kSpacing) at.push_back(x);
  const auto fa = interpolate(xa, za, at), fb = interpolate(xs, zs, at);
  double sum = 0.0;
  for (size_t i = 0; i < at.size(); ++i) sum += (fa[i] - fb[i]) * (fa[i] - fb[i]);
  return std::sqrt(sum / at.size());
}

}  // namespace

Replay::Replay(const MeasuredRun& measured, const ReplayOptions& options, Device* device)
    : measured_(measured), scenario_(measured_scenario(measured)), options_(options), device_(device) {
  if (options_.pile_ensemble < 1 || options_.pile_ensemble > kMaxPileEnsemble)
    throw InputError("replay: a pile ensemble of " + std::to_string(options_.pile_ensemble) +
                     " piles; give 1 to " + std::to_string(kMaxPileEnsemble));
  if (scenario_.pile) {
    level_preset(options_.fidelity);  // an unknown level fails now, listing the known ones
    if (!device_) throw Error("replay of " + measured.run.dir.string() + ": a pile scenario needs an OpenCL device");
  }
}

Replay::~Replay() = default;

Run Replay::simulate(vehicle::EffectSet& effects) {
  const auto start = std::chrono::steady_clock::now();
  Run run;
  if (!scenario_.pile)
    run = vehicle_run(scenario_, simulate_on_flat_ground(scenario_, effects));
  else
    run = simulate_piles(effects, options_.pile_seed, piles_, &members_);
  count(start);
  run.dir = measured_.run.dir;
  return run;
}

void Replay::count(std::chrono::steady_clock::time_point start) {
  const std::lock_guard<std::mutex> lock(count_mutex_);
  ++simulations_;
  wall_s_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

Run Replay::simulate_reference(vehicle::EffectSet& effects) {
  if (!scenario_.pile)
    throw InputError(
        "replay of " + measured_.run.dir.string() +
        ": a chaos reference needs a pile scenario (flat-ground runs are not chaotic)");
  const auto start = std::chrono::steady_clock::now();
  Run run =
      simulate_piles(effects, options_.pile_seed + static_cast<unsigned>(options_.pile_ensemble),
                     reference_piles_, nullptr);
  count(start);
  run.dir = measured_.run.dir;
  return run;
}

Run Replay::simulate_piles(vehicle::EffectSet& effects, unsigned first_seed,
                           std::vector<std::unique_ptr<PileBuild>>& built,
                           std::vector<Run>* members_out) {
  // the ensemble's piles at the level, once; every simulation digs a copy of each
  const FidelityPreset& preset = level_preset(options_.fidelity);
  const int piles = options_.pile_ensemble;
  const bool scan_of_these = &built == &piles_;  // the reported scan difference is the model's
  std::vector<Run> members;
  for (int k = 0; k < piles; ++k) {
    DiggingOptions digging;
    digging.pile.seed = first_seed + static_cast<unsigned>(k);
    if (built.size() <= static_cast<std::size_t>(k)) {
      const PileProfile placed = scenario_pile_profile(scenario_);
      const std::string label =
          "pile " + preset.name +
          (piles > 1 || !scan_of_these ? " seed " + std::to_string(digging.pile.seed) : "");
      Progress progress(label, 1.5 * digging.pile.max_time, options_.progress);
      built.push_back(std::make_unique<PileBuild>(
          build_scenario_pile(*device_, scenario_, placed, preset, digging, &progress)));
      progress.finish(std::to_string(built.back()->particles.size()) + " particles");
      // the scan difference of the ensemble: its piles' mean
      if (scan_of_these) {
        const auto rms = scan_difference(measured_.meta.pile_scan,
                                         scan_scenario_pile(*built.back(), placed, preset).points);
        if (rms) scan_rms_ = (scan_rms_.value_or(0.0) * k + *rms) / (k + 1);
      }
    }
    DiggingSimulation sim(*device_, scenario_, preset, *built[k], digging, &effects);
    sim.run([&](int) {
      if (interrupt_requested())
        throw_if_interrupted("the replay of " + scenario_.name +
                             " at t = " + std::to_string(sim.time()) + " s");
    });
    members.push_back(dig_run(scenario_, preset.name, sim));
  }
  Run run = ensemble_mean(members);
  if (members_out) *members_out = std::move(members);
  return run;
}

int Replay::simulations() const {
  const std::lock_guard<std::mutex> lock(count_mutex_);
  return simulations_;
}

double Replay::wall_s() const {
  const std::lock_guard<std::mutex> lock(count_mutex_);
  return wall_s_;
}

}  // namespace talus::sim2real
