// Letting a granular system come to rest, and measures of its state.
#pragma once
#include "host/progress.hpp"
#include "solvers/dem_world.hpp"

namespace talus {

struct SettleOptions {
  double min_time = 0.5;        // always simulate at least this long [s]
  double max_time = 5.0;        // give up settling after this long [s]
  double rest_speed = 0.01;     // at rest when the RMS particle speed is below this [m/s]
  double check_interval = 0.1;  // how often the speed is measured [s]
};

struct SettleResult {
  double sim_time = 0.0;   // simulated [s]
  double rms_speed = 0.0;  // at the end [m/s]
  bool at_rest = false;
  int steps = 0;
};

// steps `world` until it is at rest or max_time passes; reports progress when given
SettleResult settle(DemWorld& world, const SettleOptions& options, Progress* progress = nullptr);

double rms_speed(const Particles& particles);
// the largest overlap between two particles or a particle and static geometry [m]
double max_overlap(const Particles& particles, const std::vector<StaticGeom>& geoms);

}  // namespace talus
