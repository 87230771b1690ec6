// Replaying a measured run's inputs in simulation (issue 6, SPEC §6 "simulate the same inputs"):
// the scenario its metadata names gives the machine, payload, timestep, duration, pile profile and
// phase marks; the measured run gives the operator's target-speed series and where the pile's toe
// lay. A pile scenario builds and settles its pile once, at the fidelity level, and every
// simulation after that starts from the same settled particles, so two simulations differ only
// by their effects. The pile is the scenario's profile, not one rebuilt from the measured laser
// scan: the scan is compared with the simulated pile's scan instead (scan_rms_m), and a large
// difference is reported, not hidden.
#pragma once
#include <chrono>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "host/progress.hpp"
#include "sim2real/measured.hpp"
#include "sim2real/timeseries.hpp"
#include "vehicle/effect.hpp"
#include "vehicle/scenario.hpp"
#include "vehicle/sensors.hpp"

namespace talus {
class Device;
class DiggingSimulation;
struct PileBuild;
}  // namespace talus

namespace talus::sim2real {

// a scenario without particles on flat ground with the effects (may be empty): the 100 Hz log
// of what the sensors report
vehicle::SensorLog simulate_on_flat_ground(const vehicle::Scenario& scenario, vehicle::EffectSet& effects,
                                           Progress* progress = nullptr);

// a finished run in memory, as the contract reads it: the sensors' series and the summary's
// fields. The machine alone: the payload is the load, the work that of the whole run (fidelity
// "vehicle"). A dig: the loaded mass now, the work of the scenario's digging phase and its marks
Run vehicle_run(const vehicle::Scenario& scenario, const vehicle::SensorLog& log);
Run dig_run(const vehicle::Scenario& scenario, const std::string& fidelity, const DiggingSimulation& sim);

// the scenario that metadata.json describes: the named scenario (data/scenarios, any case) with
// the run's operator inputs and pile toe; InputError naming the metadata's field 'scenario'
vehicle::Scenario measured_scenario(const MeasuredRun& measured);

// the half-width of the window over which the members' variance is pooled: see
// ensemble_variance (measured on HD27-D400, docs/sim2real.md "The simulation's own spread")
inline constexpr double kSpreadHalfWindow = 0.2;  // s

// the members' spread, per channel at their shared sample times (t is theirs): the unbiased
// sample variance v(t) = Σ_k (x_k(t) − x̄(t))² / (N − 1), then pooled, each sample the mean of
// those within ±half_window_s. Why pooled: the sample variance of N = 3 members has 2 degrees of
// freedom, so at single instants it falls near zero by chance, and a residual divided by
// σ² + v there reads as far beyond its spread (for a spread 100 times the sensor's variance the
// mean of r²/(σ² + v) is about ln 100 − 0.58 ≈ 4 times what it should be). Pooling m samples
// that scatter independently gives about (N − 1) m degrees of freedom. Error for fewer than 2
// runs, runs that do not share their time base (as ensemble_mean), or a negative window
TimeSeries ensemble_variance(const std::vector<Run>& runs,
                             double half_window_s = kSpreadHalfWindow);

// the simulation's sensitivity around a fitted run (issue 17, sim2real/diagnose.hpp): per channel
// at the fitted run's sample times, the perturbed runs' mean square departure from it,
// s(t) = (1/M) Σ_m (x_m(t) − x̂(t))², pooled over ±half_window_s as ensemble_variance's (a
// departure of M = 2 simulations has as few degrees of freedom as an ensemble of three). The
// perturbed runs are the same simulation at parameters within the fit's uncertainty (an
// orthogonal two-level design: their mean square departure is the delta method's variance of the
// fitted run where it is smooth in the parameters, and twice a realisation's variance where it is
// chaotic in them). Error for no perturbed runs, runs that do not share the fitted run's time base
// (as ensemble_mean), or a negative window
TimeSeries sensitivity_variance(const Run& fitted, const std::vector<Run>& perturbed,
                                double half_window_s = kSpreadHalfWindow);

// the degrees of freedom of ensemble_variance's estimate per channel (index as kChannelNames; t's
// entry 0): ν = (N − 1) max(1, m / τ), m the samples one window pools (their mean count over the
// run) and τ the integrated autocorrelation time of the members' departures from their mean (each
// member its own segment: integrated_autocorrelation_time in sim2real/residuals.hpp). The pooled
// samples scatter independently only as far as the departures decorrelate within the window: on
// HD27 they stay correlated for 0.2-2 s, so at ±0.2 s three members give ν ≈ 2 in most channels,
// not the (N − 1) m ≈ 80 of independent samples. Error as ensemble_variance's
std::vector<double> ensemble_dof(const std::vector<Run>& runs,
                                 double half_window_s = kSpreadHalfWindow);

// the same for sensitivity_variance's estimate: ν = M′ max(1, m / τ), the M perturbed runs'
// departures from the fitted run behind τ. The departures share the fitted run: where the run is
// chaotic in its parameters each is a difference of two independent realisations, and any two are
// correlated by ½, so M of them are worth M′ = M / (1 + (M − 1)/4) independent ones (1.6 for 2,
// 2.3 for 4; where the run is smooth the design makes the estimate nearly exact, and M′ is
// conservative). Error as sensitivity_variance's
std::vector<double> sensitivity_dof(const Run& fitted, const std::vector<Run>& perturbed,
                                    double half_window_s = kSpreadHalfWindow);

// how long the departures behind those estimates stay correlated, per channel (index as
// kChannelNames; t's entry 0) in samples: the integrated autocorrelation time τ of the members'
// departures from their mean, or of the perturbed runs' from the fitted run, each its own segment
// (what ensemble_dof and sensitivity_dof divide the window by). compute_residuals counts a cell's
// samples under the null by it. Errors as ensemble_variance's and sensitivity_variance's
std::vector<double> ensemble_departure_time(const std::vector<Run>& runs);
std::vector<double> sensitivity_departure_time(const Run& fitted,
                                               const std::vector<Run>& perturbed);

// the ensemble's mean run: every channel averaged sample by sample, loaded mass and work
// averaged; the runs must share their time base (the same scenario at the same level) and their
// labels and phase marks, which the mean keeps. Error naming the first run that differs. Two or
// more runs: the mean carries their spread (Run::spread: N, ensemble_variance, ensemble_dof,
// ensemble_departure_time), which the residuals add to the sensor noise; one run is returned as it
// is, without a spread
Run ensemble_mean(const std::vector<Run>& runs);

// piles in one simulation's ensemble at most: a bound far above what smooths a D400 dig (3 to 5)
// that still catches a typo before hours of digging start
inline constexpr int kMaxPileEnsemble = 16;

struct ReplayOptions {
  std::string fidelity = "D400";  // particle level for pile scenarios
  unsigned pile_seed = 1;         // the pile's particle sizes and jitter (the first pile's)
  // piles per simulation of a pile scenario, seeds pile_seed, pile_seed + 1, ...: the simulation
  // is their ensemble_mean (1: one pile, the run as it is). Ignored without a pile
  int pile_ensemble = 1;
  bool progress = false;  // progress of the pile build on stderr
};

class Replay {
 public:
  // a pile scenario needs the device (not owned; outlives the replay); the pile is built lazily
  Replay(const MeasuredRun& measured, const ReplayOptions& options, Device* device);
  ~Replay();
  Replay(const Replay&) = delete;
  Replay& operator=(const Replay&) = delete;

  // the measured inputs simulated with the effects (empty set: the baseline); the run carries the
  // summary fields the metrics read (loaded mass, work of the digging phase, phase marks). A
  // scenario without a pile may be simulated from several threads at once (each call builds its
  // own machine; the diagnosis runs its scans so); a pile scenario from one thread at a time
  Run simulate(vehicle::EffectSet& effects);
  // the same simulation on the chaos reference: a second ensemble of as many piles, disjoint
  // from the first (seeds pile_seed + pile_ensemble, ...), built at first use. On pile data a
  // model can fit one ensemble's chaotic realisation by chance; the reference is where such a fit
  // must hold again (the diagnosis's chaos check). members() is left as simulate() set it. A
  // scenario without a pile has no chaos: InputError
  Run simulate_reference(vehicle::EffectSet& effects);

  const vehicle::Scenario& scenario() const { return scenario_; }
  const MeasuredRun& measured() const { return measured_; }
  // the root-mean-square height difference [m] between the measured scan and the simulated pile's
  // scan over their common x range (the mean over an ensemble's piles); nullopt before the first
  // pile simulation or without a pile
  std::optional<double> scan_rms_m() const { return scan_rms_; }
  // a pile scenario's last simulation, pile by pile in seed order: the ensemble's members, whose
  // mean simulate() returned with their spread (Run::spread, for 2 or more piles; empty without a
  // pile: those simulations may run on several threads)
  const std::vector<Run>& members() const { return members_; }
  int simulations() const;
  double wall_s() const;  // time spent in simulate(), pile build included (summed over threads)

 private:
  MeasuredRun measured_;
  vehicle::Scenario scenario_;
  ReplayOptions options_;
  Device* device_ = nullptr;
  // the piles of the first `piles` members from `first_seed`, each built at first use into
  // `built`, dug with the effects; their ensemble mean
  Run simulate_piles(vehicle::EffectSet& effects, unsigned first_seed,
                     std::vector<std::unique_ptr<PileBuild>>& built, std::vector<Run>* members);
  // one simulation more, and its wall time since `start`
  void count(std::chrono::steady_clock::time_point start);
  std::vector<std::unique_ptr<PileBuild>> piles_;  // one per ensemble member, built at first use
  std::vector<std::unique_ptr<PileBuild>> reference_piles_;  // the chaos reference's, likewise
  std::optional<double> scan_rms_;
  std::vector<Run> members_;
  mutable std::mutex count_mutex_;  // guards the two counts below
  int simulations_ = 0;
  double wall_s_ = 0.0;
};

}  // namespace talus::sim2real
