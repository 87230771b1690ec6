#include "digging/dig_cost.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>

#include "host/error.hpp"
#include "host/stage_times.hpp"

namespace talus {

namespace {
// turns the device's stage clock on for one scope, and off again whatever happens
class Profiling {
 public:
  Profiling(Device& dev, StageTimes* times) : dev_(dev) { dev_.set_stage_times(times); }
  ~Profiling() { dev_.set_stage_times(nullptr); }
  Profiling(const Profiling&) = delete;
  Profiling& operator=(const Profiling&) = delete;

 private:
  Device& dev_;
};
}  // namespace

void check_dig_seconds(const vehicle::Scenario& scenario, double seconds) {
  const double available = scenario.duration - scenario.dig_start;
  if (!(seconds > 0.0) || seconds > available + 1e-9) {
    std::ostringstream m;
    m << "--seconds: " << scenario.name << " digs for " << available << " s after its dig_start ("
      << scenario.dig_start << " s); choose a time in (0, " << available << "]";
    throw InputError(m.str());
  }
}

DigCost measure_dig_cost(Device& dev, const vehicle::Scenario& scenario,
                         const FidelityPreset& preset, const PileBuild& pile,
                         const DiggingOptions& options, double seconds, Progress* progress) {
  // what can be measured: the dig phase must hold `seconds`
  check_dig_seconds(scenario, seconds);

  // the machine, run unmeasured to the start of the dig
  DiggingSimulation sim(dev, scenario, preset, pile, options);
  const int start_steps = static_cast<int>(std::lround(scenario.dig_start / preset.dt));
  const int measured_steps =
      std::min(std::max(2, static_cast<int>(std::lround(seconds / preset.dt))),
               sim.steps_total() - start_steps);
  if (measured_steps < 2)
    throw InputError("--seconds: " + scenario.name + " at " + preset.name +
                     " leaves fewer than two steps to measure after dig_start");
  for (int k = 0; k < start_steps; ++k) {
    sim.step();
    if (progress) progress->update(sim.time(), "to the dig");
  }

  // the measured steps: even ones plain, odd ones profiled
  DigCost cost;
  cost.scenario = scenario.name;
  cost.level = preset.name;
  // the particle world: type D's pile, or type G's terrain (its particles come and go: a mean)
  const bool type_g = sim.multiscale();
  const DemWorld& dem = type_g ? sim.terrain().dem() : sim.dem();
  cost.dt = preset.dt;
  cost.iterations = preset.iterations;
  cost.sweep_tolerance = applied_sweep_tolerance(options.sweep_tolerance, preset);
  StageTimes times;
  double plain_wall = 0.0, profiled_wall = 0.0;
  int plain = 0, profiled = 0;
  for (int k = 0; k < measured_steps; ++k) {
    const bool profile = k % 2 == 1;
    dev.finish();
    const auto t0 = std::chrono::steady_clock::now();
    {
      Profiling on(dev, profile ? &times : nullptr);
      sim.step();
    }
    dev.finish();
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    (profile ? profiled_wall : plain_wall) += wall;
    ++(profile ? profiled : plain);
    // the work this step did (type G: the zone's DEM with the bucket kinematic, one pass)
    cost.particles += sim.particle_count();
    if (dem.buffers().row_layout == RowLayout::Runs)
      cost.sweep_parts_used = std::max(cost.sweep_parts_used, dem.buffers().run_parts);
    if (type_g) {
      // the zone's DEM steps only while it holds particles (its stats are the last step's
      // otherwise), then with the level's sweeps (solvers/tool_world)
      if (sim.particle_count() > 0) {
        cost.contacts += dem.stats().contacts;
        cost.boundary_rows += dem.stats().boundary_rows;
        cost.passes += 1;
        cost.sweeps += preset.iterations;
      }
    } else {
      cost.contacts += dem.stats().contacts;
      cost.boundary_rows += dem.stats().boundary_rows;
      cost.bucket_contacts += sim.split().stats().bucket_contacts;
      cost.passes += sim.split().stats().passes;
      cost.sweeps += sim.split().stats().sweeps;
    }
    if (progress) progress->update(sim.time(), "measuring");
  }

  // means per step
  cost.steps = measured_steps;
  cost.seconds = measured_steps * preset.dt;
  cost.ms_per_step = 1e3 * plain_wall / plain;
  cost.profiled_ms_per_step = 1e3 * profiled_wall / profiled;
  cost.realtime_factor = preset.dt / (plain_wall / plain);
  for (const auto& [name, total] : times.totals())
    cost.stages.emplace_back(name, 1e3 * total / profiled);
  cost.particles /= measured_steps;
  cost.contacts /= measured_steps;
  cost.boundary_rows /= measured_steps;
  cost.bucket_contacts /= measured_steps;
  cost.passes /= measured_steps;
  cost.sweeps /= measured_steps;
  cost.loaded_mass_kg = sim.loaded_mass();
  return cost;
}

}  // namespace talus
