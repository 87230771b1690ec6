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

CyclePile build_cycle_pile(Device& dev, const vehicle::Scenario& base, double approach,
                           double max_time, const FidelityPreset& preset,
                           const DiggingOptions& options, Progress* progress) {
  CyclePile c;
  c.scenario = feedback_scenario(base, approach, max_time);
  const PileProfile placed = scenario_pile_profile(c.scenario);
  c.pile = build_scenario_pile(dev, c.scenario, placed, preset, options, progress);
  for (const auto& q : scan_scenario_pile(c.pile, placed, preset).points)
    c.surface.emplace_back(q.x(), q.y());
  if (c.surface.empty())
    throw Error("the pile's laser scan found no surface; the cycle cannot find the pile");
  // hits come in ray order; the surface is a function of x
  std::sort(c.surface.begin(), c.surface.end());
  return c;
}

namespace {
// where the bucket reaches the pile: the first scanned point higher than half a grain
double cycle_toe(const CyclePile& cycle, const FidelityPreset& preset) {
  for (const auto& [x, z] : cycle.surface) {
    if (z > 0.5 * preset.diameter) return x;
  }
  return cycle.scenario.pile_toe_x;
}

// the cycle's speeds and force scale from the machine (paper §7.1)
vehicle::CycleSettings cycle_settings(const vehicle::WheelLoader& loader) {
  vehicle::CycleSettings settings;
  settings.boom_force_scale = loader.lift_cylinders().size() * loader.lift_spec().force_push;
  settings.lift_max_speed = loader.lift_spec().max_speed;
  settings.tilt_max_speed = loader.tilt_spec().max_speed;
  return settings;
}
}  // namespace

LoadingCycle::LoadingCycle(Device& dev, const CyclePile& cycle, const FidelityPreset& preset,
                           const DiggingOptions& options, const vehicle::FeedbackGains& gains,
                           vehicle::EffectSet* effects)
    : sim_(dev, cycle.scenario, preset, cycle.pile, options, effects),
      cycle_(gains, cycle_settings(sim_.loader()), cycle.surface, cycle_toe(cycle, preset),
             sim_.sensors().x_vehicle) {
  // the phase at the start, before the first step
  cycle_.advance(reading());
}

void LoadingCycle::step_with(const vehicle::CycleTargets& c) {
  sim_.step(c.drive, c.lift, c.tilt);
  // the cycle reads the sensors only while it has time left (as the sweep always did: a cycle
  // at its time limit ends in the phase it was in)
  if (!sim_.done()) cycle_.advance(reading());
}

void LoadingCycle::step() { step_with(cycle_.targets(reading())); }

void LoadingCycle::step_fill(const vehicle::CycleTargets& fill) {
  if (cycle_.phase() != vehicle::CyclePhase::Fill)
    throw Error(std::string("the loading cycle is in its ") + vehicle::phase_name(cycle_.phase()) +
                " phase, not the fill: only the fill takes the caller's targets; step with the "
                "cycle's own");
  step_with(fill);
}

void LoadingCycle::save_state(ByteWriter& w) const {
  sim_.save_state(w);
  w.tag("loading cycle");
  cycle_.save_state(w);
}

void LoadingCycle::restore_state(ByteReader& r) {
  sim_.restore_state(r);
  r.expect("loading cycle");
  cycle_.restore_state(r);
}

CycleResult LoadingCycle::result(double s) const {
  CycleResult r;
  r.s = s;
  r.completed = cycle_.done();
  r.cycle_time_s = r.completed ? cycle_.phase_start(vehicle::CyclePhase::Done) : sim_.time();
  r.loaded_mass_kg = sim_.loaded_mass();
  r.work_J = sim_.log().work();
  r.fill_start_s = cycle_.phase_start(vehicle::CyclePhase::Fill);
  r.breakout_s = cycle_.phase_start(vehicle::CyclePhase::Hold);
  return r;
}

CycleResult run_feedback_cycle(Device& dev, const CyclePile& cycle, const FidelityPreset& preset,
                               const DiggingOptions& options, double s, vehicle::SensorLog* trace) {
  LoadingCycle run(dev, cycle, preset, options, vehicle::gains_on_search_line(s));
  // the cycle, step by step, until the machine is back at its start or the time is up
  while (!run.done()) run.step();
  if (trace) *trace = run.simulation().log();
  return run.result(s);
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
