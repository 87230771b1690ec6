// The force-feedback sweep of SPEC §5 / paper §7: one full loading cycle per point s of the
// controller's search line, each an independent digging simulation, and the paper's measures of
// how a controller tuned in one simulator transfers to another (domain gap, domain shift,
// performance drop). Scale-out across processes and machines is the caller's (apps/cmd_sweep.cpp:
// MPI ranks, or shards for a Slurm job array): a cycle needs nothing but its own inputs.
#pragma once
#include <string>
#include <utility>
#include <vector>

#include "digging/digging.hpp"
#include "vehicle/force_feedback.hpp"

namespace talus {

struct CycleResult {
  double s = 0.0;                 // search parameter
  double loaded_mass_kg = 0.0;    // M: soil in the bucket at the end of the cycle
  double cycle_time_s = 0.0;      // T: from the start to the return to the starting point
  double work_J = 0.0;            // W: the work of the whole cycle
  bool completed = false;         // false when the cycle hit the time limit before returning
  double fill_start_s = -1.0, breakout_s = -1.0;
  double productivity() const { return cycle_time_s > 0.0 ? loaded_mass_kg / cycle_time_s : 0.0; }  // M/T [kg/s]
  double efficiency() const { return work_J > 0.0 ? loaded_mass_kg / work_J : 0.0; }                  // M/W [kg/J]
};

// the scenario's pile placed `approach` metres in front of the bucket's tip (the paper starts
// 5 m from the pile) and given `max_time` seconds for the cycle
vehicle::Scenario feedback_scenario(const vehicle::Scenario& scenario, double approach, double max_time);

// the pile of a loading cycle: the cycle's scenario, its pile built (or read from the pile cache)
// and its laser scan before loading, as (x, z) points with x increasing (the controller's surface)
struct CyclePile {
  vehicle::Scenario scenario;
  PileBuild pile;
  std::vector<std::pair<double, double>> surface;
};
// `base`'s pile at the preset, placed by feedback_scenario(base, approach, max_time); talus::Error
// when the scan finds no surface
CyclePile build_cycle_pile(Device& dev, const vehicle::Scenario& base, double approach,
                           double max_time, const FidelityPreset& preset,
                           const DiggingOptions& options, Progress* progress);

// one loading cycle stepped by the caller: the dig on the cycle's pile and the cycle's phases
// (vehicle/force_feedback.hpp). The approach, hold and retreat drive themselves; the fill is the
// force-feedback controller's at `gains`, or the caller's targets (a learning agent, a controller
// of one's own). The phase is the one the sensors after the last step call for, as a controller
// reads it before choosing its next targets.
class LoadingCycle {
 public:
  // `cycle` from build_cycle_pile; the pile is copied into the dig, so `cycle` need not outlive it.
  // With `effects` (model extensions, vehicle/effect.hpp; not owned, must outlive the cycle) the
  // machine runs through them as a dig does, and the controller reads the sensors as the effects
  // report them (a delayed or biased sensor misleads it as it would the real machine's)
  LoadingCycle(Device& dev, const CyclePile& cycle, const FidelityPreset& preset,
               const DiggingOptions& options, const vehicle::FeedbackGains& gains,
               vehicle::EffectSet* effects = nullptr);
  // it holds a DiggingSimulation, which stays where it was built
  LoadingCycle(const LoadingCycle&) = delete;
  LoadingCycle& operator=(const LoadingCycle&) = delete;

  vehicle::CyclePhase phase() const { return cycle_.phase(); }
  // back at the start, or the cycle's time limit reached (completed() tells which)
  bool done() const { return cycle_.done() || sim_.done(); }
  bool completed() const { return cycle_.done(); }
  const vehicle::FeedbackCycle& cycle() const { return cycle_; }
  // one step with the phase's own targets (the controller's in the fill)
  void step();
  // one step of the fill with the caller's targets [m/s]; talus::Error outside the fill
  void step_fill(const vehicle::CycleTargets& fill);
  // the paper's measures so far: M now, T (the return to the start, or the time so far), W, when
  // the fill began and ended (-1 before), at search parameter `s` (only recorded)
  CycleResult result(double s) const;
  const DiggingSimulation& simulation() const { return sim_; }
  // the state between two steps: the dig's (DiggingSimulation::save_state) and the cycle's phase
  // (vehicle::FeedbackCycle::save_state); restored into a cycle made with the same pile and gains
  void save_state(ByteWriter& w) const;
  void restore_state(ByteReader& r);

 private:
  // the sensors the cycle reads after each step: what the machine's sensors report through the
  // effects (the truth without effects), as the controller sees them
  const vehicle::SensorSample& reading() const { return sim_.sensors(); }
  void step_with(const vehicle::CycleTargets& c);

  DiggingSimulation sim_;
  vehicle::FeedbackCycle cycle_;
};

// one loading cycle with the controller at search parameter s on the cycle's pile; with `trace`,
// the cycle's 100 Hz sensor log is copied there (to see why a fill ended where it did)
CycleResult run_feedback_cycle(Device& dev, const CyclePile& cycle, const FidelityPreset& preset,
                               const DiggingOptions& options, double s,
                               vehicle::SensorLog* trace = nullptr);

// the sweep's best productivity M/T and where it is
struct SweepOptimum {
  double s = 0.0;
  double productivity = 0.0;  // [kg/s]
};
SweepOptimum best_productivity(const std::vector<CycleResult>& results);

// a controller tuned in domain `from` (its optimum) used in domain `to` (paper §7.2):
//   gap   = |P*_from - P*_to| (and relative to P*_to), shift = |s*_from - s*_to|,
//   drop  = (P*_to - P_to(s*_from)) / P*_to, with P_to between samples linear in s
struct DomainTransfer {
  double gap_kg_s = 0.0, gap_rel = 0.0, shift = 0.0, drop_rel = 0.0;
};
DomainTransfer domain_transfer(const std::vector<CycleResult>& from, const std::vector<CycleResult>& to);

}  // namespace talus
