#include "sim2real/replay.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "digging/digging.hpp"
#include "host/device.hpp"
#include "host/error.hpp"
#include "host/interrupt.hpp"
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
  vehicle::start_with_effects(loader, effects, log);
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
  if (scenario_.pile) {
    level_preset(options_.fidelity);  // an unknown level fails now, listing the known ones
    if (!device_) throw Error("replay of " + measured.run.dir.string() + ": a pile scenario needs an OpenCL device");
  }
}

Replay::~Replay() = default;

Run Replay::simulate(vehicle::EffectSet& effects) {
  const auto start = std::chrono::steady_clock::now();
  Run run;
  if (!scenario_.pile) {
    run = vehicle_run(scenario_, simulate_on_flat_ground(scenario_, effects));
  } else {
    // the pile at the level, once; every simulation digs a copy of it
    const FidelityPreset& preset = level_preset(options_.fidelity);
    DiggingOptions digging;
    digging.pile.seed = options_.pile_seed;
    if (!pile_) {
      const PileProfile placed = scenario_pile_profile(scenario_);
      Progress progress("pile " + preset.name, 1.5 * digging.pile.max_time, options_.progress);
      pile_ = std::make_unique<PileBuild>(build_scenario_pile(*device_, scenario_, placed, preset, digging, &progress));
      progress.finish(std::to_string(pile_->particles.size()) + " particles");
      scan_rms_ = scan_difference(measured_.meta.pile_scan,
                                  scan_scenario_pile(*pile_, placed, preset).points);
    }
    DiggingSimulation sim(*device_, scenario_, preset, *pile_, digging, &effects);
    sim.run([&](int) {
      if (interrupt_requested())
        throw_if_interrupted("the replay of " + scenario_.name +
                             " at t = " + std::to_string(sim.time()) + " s");
    });
    run = dig_run(scenario_, preset.name, sim);
  }
  run.dir = measured_.run.dir;
  const std::lock_guard<std::mutex> lock(count_mutex_);
  ++simulations_;
  wall_s_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
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
