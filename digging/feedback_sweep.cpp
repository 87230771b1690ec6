#include "digging/feedback_sweep.hpp"

#include <algorithm>
#include <cmath>

#include "host/error.hpp"

namespace talus {

vehicle::Scenario feedback_scenario(const vehicle::Scenario& scenario, double approach, double max_time) {
  if (!scenario.pile) throw InputError(scenario.path + ": the force-feedback cycle needs a scenario with a pile");
  if (!(approach > 0.0) || !(max_time > 0.0))
    throw InputError("force feedback: the approach distance and the time limit must be positive");
  // the machine's reference pose puts the bucket tip here (data/machines: "bucket.tip")
  const vehicle::WheelLoader loader(vehicle::machine_file(scenario));
  vehicle::Scenario s = scenario;
  s.pile_toe_x = loader.bucket_tip_world().x() + approach;
  s.duration = max_time;
  s.dig_start = 0.0;
  s.dig_end = max_time;
  return s;
}

CycleResult run_feedback_cycle(Device& dev, const vehicle::Scenario& scenario, const FidelityPreset& preset,
                               const PileBuild& pile, const std::vector<std::pair<double, double>>& surface,
                               const DiggingOptions& options, double s, vehicle::SensorLog* trace) {
  DiggingSimulation sim(dev, scenario, preset, pile, options);
  const vehicle::WheelLoader& loader = sim.loader();
  // where the bucket reaches the pile: the first scanned point higher than half a grain
  double toe = scenario.pile_toe_x;
  for (const auto& [x, z] : surface) {
    if (z > 0.5 * preset.diameter) {
      toe = x;
      break;
    }
  }
  vehicle::CycleSettings settings;
  settings.boom_force_scale = loader.lift_cylinders().size() * loader.lift_spec().force_push;
  settings.lift_max_speed = loader.lift_spec().max_speed;
  settings.tilt_max_speed = loader.tilt_spec().max_speed;
  const double start_x = vehicle::read_sensors(loader, 0.0).x_vehicle;
  vehicle::FeedbackCycle cycle(vehicle::gains_on_search_line(s), settings, surface, toe, start_x);

  // the cycle, step by step, until the machine is back at its start or the time is up
  while (!cycle.done() && !sim.done()) {
    const vehicle::CycleTargets c = cycle.update(vehicle::read_sensors(loader, sim.time()));
    if (cycle.done()) break;
    sim.step(c.drive, c.lift, c.tilt);
  }
  CycleResult r;
  r.s = s;
  r.completed = cycle.done();
  r.cycle_time_s = r.completed ? cycle.phase_start(vehicle::CyclePhase::Done) : sim.time();
  r.loaded_mass_kg = sim.loaded_mass();
  r.work_J = sim.log().work();
  r.fill_start_s = cycle.phase_start(vehicle::CyclePhase::Fill);
  r.breakout_s = cycle.phase_start(vehicle::CyclePhase::Hold);
  if (trace) *trace = sim.log();
  return r;
}

SweepOptimum best_productivity(const std::vector<CycleResult>& results) {
  SweepOptimum best;
  for (const auto& r : results) {
    if (r.completed && r.productivity() > best.productivity) best = {r.s, r.productivity()};
  }
  return best;
}

namespace {
// the productivity of a sweep at s, linear between its completed samples (clamped at the ends)
double productivity_at(std::vector<CycleResult> results, double s) {
  results.erase(std::remove_if(results.begin(), results.end(), [](const CycleResult& r) { return !r.completed; }),
                results.end());
  if (results.empty()) return 0.0;
  std::sort(results.begin(), results.end(), [](const CycleResult& a, const CycleResult& b) { return a.s < b.s; });
  if (s <= results.front().s) return results.front().productivity();
  if (s >= results.back().s) return results.back().productivity();
  for (size_t k = 1; k < results.size(); ++k) {
    if (s <= results[k].s) {
      const CycleResult& a = results[k - 1];
      const CycleResult& b = results[k];
      const double w = b.s > a.s ? (s - a.s) / (b.s - a.s) : 1.0;
      return a.productivity() + w * (b.productivity() - a.productivity());
    }
  }
  return results.back().productivity();
}
}  // namespace

DomainTransfer domain_transfer(const std::vector<CycleResult>& from, const std::vector<CycleResult>& to) {
  const SweepOptimum a = best_productivity(from);
  const SweepOptimum b = best_productivity(to);
  DomainTransfer d;
  d.gap_kg_s = std::abs(a.productivity - b.productivity);
  d.gap_rel = b.productivity > 0.0 ? d.gap_kg_s / b.productivity : 0.0;
  d.shift = std::abs(a.s - b.s);
  d.drop_rel = b.productivity > 0.0 ? (b.productivity - productivity_at(to, a.s)) / b.productivity : 0.0;
  return d;
}

}  // namespace talus
