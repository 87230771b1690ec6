// The force-feedback sweep of SPEC §5 / paper §7: one full loading cycle per point s of the
// controller's search line, each an independent digging simulation, and the paper's measures of
// how a controller tuned in one simulator transfers to another (domain gap, domain shift,
// performance drop). Scale-out across processes and machines is the caller's (apps/cmd_sweep.cpp:
// MPI ranks, or shards for a Slurm job array): a cycle needs nothing but its own inputs.
#pragma once
#include <string>
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

// one loading cycle with the controller at search parameter s, on a pile built for `scenario`
// (feedback_scenario) and scanned (`surface`, the laser scan's (x, z) points); with `trace`, the
// cycle's 100 Hz sensor log is copied there (to see why a fill ended where it did)
CycleResult run_feedback_cycle(Device& dev, const vehicle::Scenario& scenario, const FidelityPreset& preset,
                               const PileBuild& pile, const std::vector<std::pair<double, double>>& surface,
                               const DiggingOptions& options, double s, vehicle::SensorLog* trace = nullptr);

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
