// The cost of one coupled step, stage by stage (issue 13: "measure first"; type G, issue 14). A
// scenario's pile is built and the dig replayed from t = 0; from the scenario's dig_start on,
// `seconds` of digging are timed. Steps alternate: the even ones run unprofiled and give the wall
// time per step and the real-time factor, the odd ones run with the device's stage clock on
// (host/stage_times.hpp) and give the breakdown. Neighbouring steps dig the same soil, so the
// two halves describe the same work, and profiling's queue drains never slow the headline number.
#pragma once
#include <string>
#include <utility>
#include <vector>

#include "digging/digging.hpp"

namespace talus {

struct DigCost {
  std::string scenario, level;
  // type D: the pile's; type G: the terrain's (the zone's, the bucket's and those not yet merged
  // back), a mean over the measured steps
  double particles = 0.0;
  double dt = 0.0;                    // [s]
  int iterations = 0;                 // sweeps per step (the cap, with a sweep tolerance)
  double sweep_tolerance = 0.0;       // [m/s] DiggingOptions::sweep_tolerance (0: none)
  double seconds = 0.0;               // simulated time measured [s]
  int steps = 0;                      // steps measured (both halves)
  double ms_per_step = 0.0;           // mean wall time of an unprofiled step [ms]
  double profiled_ms_per_step = 0.0;  // the same for a profiled step (queue drained per stage)
  double realtime_factor = 0.0;       // dt over the unprofiled step's mean wall time
  // mean wall time per profiled step of each stage, in the order they first ran [ms]; they add
  // up to profiled_ms_per_step
  std::vector<std::pair<std::string, double>> stages;
  // the work measured: means over the measured steps
  double contacts = 0.0;         // particle-particle and particle-geometry contacts
  // of them, rows in the boundary of the runs (StepStats::boundary_rows; 0 unless a CPU device
  // walks the system in parts), walked after the parts by one work-item
  double boundary_rows = 0.0;
  // the parts a step's runs were made of (the device's count for sweep_parts 0), the most over
  // the measured steps; 0 when no step was laid out in runs
  int sweep_parts_used = 0;
  double bucket_contacts = 0.0;  // particle-bucket rows (type D; type G's bucket is kinematic)
  double passes = 0.0;           // outer coupling passes
  double sweeps = 0.0;           // particle sweeps, all passes (fewer with a sweep tolerance)
  double loaded_mass_kg = 0.0;   // in the bucket at the end (to tell an empty dig from a full one)
};

// InputError unless `seconds` fits in the scenario's dig phase (duration after dig_start)
void check_dig_seconds(const vehicle::Scenario& scenario, double seconds);

// digs the scenario on `pile` (build_scenario_pile) to dig_start unmeasured, then measures
// `seconds` (at most the scenario's duration after dig_start; InputError otherwise). Progress
// counts simulated seconds of the scenario
DigCost measure_dig_cost(Device& dev, const vehicle::Scenario& scenario,
                         const FidelityPreset& preset, const PileBuild& pile,
                         const DiggingOptions& options, double seconds, Progress* progress);

}  // namespace talus
