// Effects: model extensions of the wheel loader (issue 6, SPEC §6; docs/effects.md). An effect is
// a physical effect the baseline model lacks (engine power shared with the hydraulics, hydraulic
// lag, cylinder friction, a sensor's bias, ...) with a few named parameters, each with a range.
// It acts through three hooks, called every step in this order:
//   on_commands  the operator's target speeds (drive, lift, tilt) -> what the actuators get
//   on_step      the limits and forces of this step: the cylinders' motor force ranges, the
//                driveline's power limit, extra wrenches on bodies (for this step only)
//   on_sensors   what the sensors report (a vehicle::SensorSample, changed in place)
// and, once before a run with particles, on_soil: the soil's properties (cohesion)
// Each hook gets an EffectContext: the step's start time t (for on_sensors, the sample's time),
// the timestep h, the true sensor sample before the step, the machine (read only) and whether t
// lies in the run's digging phase.
// An EffectSet applies several effects in order, restores the machine's own limits before each
// step's on_step (so effects never accumulate), and keeps the true previous sample.
// Built-in effects: make_builtin_effect(name) (vehicle/effects_builtin.cpp); effects from shared
// libraries: vehicle/effect_plugin.hpp.
#pragma once
#include <array>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "vehicle/scenario.hpp"
#include "vehicle/sensors.hpp"
#include "vehicle/wheel_loader.hpp"

namespace talus::vehicle {

// whether t lies in the digging phase [start, end) [s] (none when end <= start): the one rule the
// effects' context and the discovery's data path both read
inline bool in_dig_phase(double t, double start, double end) {
  return end > start && t >= start && t < end;
}

// a named number with its range (inclusive), unit and meaning
struct EffectParameter {
  std::string name;
  double value = 0.0;
  double min = 0.0, max = 0.0;
  std::string unit;     // "s", "N", "m^3/s", "1" for dimensionless
  std::string meaning;  // one line
};

// a named choice among words (e.g. the sensor channel a bias acts on)
struct EffectOption {
  std::string name;
  std::string value;
  std::vector<std::string> choices;
  std::string meaning;
};

// what an effect may change in the soil, once before a run with particles (the baseline gravel is
// dry and cohesionless); a run without particles has no soil and ignores it
struct SoilProperties {
  double cohesion = 0.0;  // bulk tensile strength [Pa] (solvers/particles.hpp Material::cohesion)
};

// target speeds [m/s]: drive (forward positive), lift and tilt cylinders (extension positive)
struct ActuatorCommands {
  double drive = 0.0, lift = 0.0, tilt = 0.0;
};

struct EffectContext {
  double t = 0.0;  // s: the step's start (on_sensors: the time of the sample)
  double h = 0.0;  // s: the timestep
  const SensorSample& previous;  // the true sensors before the step (not what effects report)
  const WheelLoader& loader;
  // t lies in the run's digging phase [dig_start, dig_end) (EffectSet::set_dig_phase; the phase
  // the metrics compare and the residuals' "dig" phase); false in a run without one
  bool digging = false;
};

// what on_step may change for the coming step
class StepControls {
 public:
  explicit StepControls(WheelLoader& loader);
  WheelLoader& loader() { return loader_; }
  // every cylinder's motor force range [N] (positive pushes it longer): both lift cylinders at once
  void set_lift_force_range(double force_min, double force_max);
  void set_tilt_force_range(double force_min, double force_max);
  double lift_force_min() const;
  double lift_force_max() const;
  double tilt_force_min() const;
  double tilt_force_max() const;
  // the engine power the driveline may use this step [W] (> 0)
  void set_drive_power_limit(double watts);
  double drive_power_limit() const;
  // adds a wrench [force at the COM [N]; torque [N m]], world frame, for this step; wrenches from
  // several effects on one body add up. Not on the bucket (the particle coupling owns its wrench):
  // talus::Error
  void add_wrench(int body, const Vec6& wrench);
  const std::vector<Vec6>& wrenches() const { return wrenches_; }

 private:
  WheelLoader& loader_;
  std::vector<Vec6> wrenches_;  // per body
};

class Effect {
 public:
  Effect(std::string name, std::string summary);
  virtual ~Effect() = default;
  Effect(const Effect&) = delete;
  Effect& operator=(const Effect&) = delete;

  const std::string& name() const { return name_; }
  const std::string& summary() const { return summary_; }
  const std::vector<EffectParameter>& parameters() const { return parameters_; }
  const std::vector<EffectOption>& options() const { return options_; }
  // a parameter's value; talus::Error for an unknown name
  double get(const std::string& parameter) const;
  const std::string& option(const std::string& name) const;
  // set a parameter; talus::InputError naming the effect, the parameter and its range when the
  // value is out of range, not finite or the name unknown
  void set(const std::string& parameter, double value);
  // set an option (one of its choices) or a parameter from text ("0.3"); InputError as set()
  void set_text(const std::string& name, const std::string& text);
  // name, parameters and options as JSON: {"name": ..., "params": {...}} (plug-ins add "plugin")
  virtual nlohmann::json to_json() const;

  // before a run: forget all state; the machine is at rest at the start
  virtual void reset(const WheelLoader& loader) { (void)loader; }
  virtual void on_commands(const EffectContext& context, ActuatorCommands& commands) {
    (void)context;
    (void)commands;
  }
  virtual void on_step(const EffectContext& context, StepControls& controls) {
    (void)context;
    (void)controls;
  }
  virtual void on_sensors(const EffectContext& context, SensorSample& sample) {
    (void)context;
    (void)sample;
  }
  // the soil's properties, once before a run with particles
  virtual void on_soil(SoilProperties& soil) { (void)soil; }
  // what it carries from one step to the next, for a saved state (digging/saved_state): nothing
  // by default; an effect with a memory (a lag, a delay line) writes it and reads it back. One
  // whose memory talus cannot see (a plug-in's, behind the C ABI) is not savable
  virtual bool savable() const { return true; }
  virtual void save_state(ByteWriter& w) const { (void)w; }
  virtual void restore_state(ByteReader& r) { (void)r; }
  // does it act only through on_soil (so a run without particles cannot show it)?
  virtual bool soil_only() const { return false; }
  // the channels it changes when it acts only on what fixed sensors report (its signature, which
  // the diagnosis searches first); empty when it acts on the machine or the soil, and so on every
  // channel. An effect with a `channel` option acts on the chosen channel instead.
  virtual std::vector<Channel> sensor_channels() const { return {}; }

 protected:
  // derived classes declare their parameters and options in their constructors; the index reads
  // the value fast in the hooks
  int add_parameter(EffectParameter p);
  int add_option(EffectOption o);
  double value(int index) const { return parameters_[index].value; }
  const std::string& option_value(int index) const { return options_[index].value; }
  // a derived class may narrow a parameter's range and unit when an option changes
  void redefine_parameter(int index, double min, double max, const std::string& unit);
  // called after a parameter or option changed
  virtual void changed() {}

 private:
  std::string name_, summary_;
  std::vector<EffectParameter> parameters_;
  std::vector<EffectOption> options_;
};

class EffectSet {
 public:
  void add(std::unique_ptr<Effect> effect);
  bool empty() const { return effects_.empty(); }
  size_t size() const { return effects_.size(); }
  Effect& operator[](size_t i) { return *effects_.at(i); }
  const Effect& operator[](size_t i) const { return *effects_.at(i); }
  // [{"name": ..., "params": {...}}, ...]
  nlohmann::json to_json() const;
  // the soil `base` (by default the dry baseline) with every effect's on_soil applied in order
  SoilProperties soil(SoilProperties base = {}) const;

  // before a run, at time t: resets every effect, takes the machine's current limits as its own
  // (restored before every step) and the true sensors now as the previous sample
  void reset(WheelLoader& loader, double t);
  // the run's digging phase [start, end) [s] (a scenario's dig_start and dig_end, or a measured
  // run's marks), which the hooks' EffectContext::digging reports; none (always false) until set
  // or when end <= start
  void set_dig_phase(double start, double end);
  // the hooks of one step [t, t + h], in order; `commands` at the step's start
  ActuatorCommands commands(double t, double h, ActuatorCommands commands);
  // restores the machine's limits, runs on_step, applies the summed wrenches to the bodies
  void before_step(double t, double h, WheelLoader& loader);
  // what the sensors report for `truth` (read at truth.t after the step); keeps truth as the next
  // step's previous sample. When an effect changes a force or speed reading but not power, power
  // follows: P = f_tr v + f_l ḋ_l + f_t ḋ_t of the readings
  SensorSample sensors(double h, const SensorSample& truth);
  const SensorSample& previous() const { return previous_; }
  // the set's state between steps, for a saved state: each effect's under its name, then the true
  // previous sample (the machine's own limits are the reset's, the same in a set reset on the same
  // machine). talus::Error naming an effect that is not savable (a plug-in's); restore_state
  // reads into a set of the same effects, reset on its machine (InputError otherwise)
  void save_state(ByteWriter& w) const;
  void restore_state(ByteReader& r);

 private:
  std::vector<std::unique_ptr<Effect>> effects_;
  const WheelLoader* loader_ = nullptr;
  SensorSample previous_;
  // the machine's own limits: per cylinder (lift, lift, tilt) [N], and the driveline's power [W]
  std::array<std::pair<double, double>, 3> force_range_{};
  double power_limit_ = 0.0;
  bool reset_done_ = false;
  double dig_start_ = 0.0, dig_end_ = 0.0;  // s: the digging phase, none while equal
  bool digging(double t) const { return in_dig_phase(t, dig_start_, dig_end_); }
};

// the built-in effects' names, in the order docs/effects.md lists them
std::vector<std::string> builtin_effect_names();
// a built-in effect with its defaults; talus::InputError listing the names for an unknown one
std::unique_ptr<Effect> make_builtin_effect(const std::string& name);

// Stepping with effects, the one loop every run uses (the machine alone, a dig, a replay). An
// empty effect set is the identity: commands pass unchanged, the machine keeps its own limits and
// the sensors report the truth, so a run without effects takes the same path bit for bit.

// the start of a run at t = 0: resets the effects on the settled machine, gives them the
// scenario's digging phase [dig_start, dig_end) (none when dig_end <= dig_start) and logs the
// first sample through them; returns what the sensors report
SensorSample start_with_effects(WheelLoader& loader, EffectSet& effects, SensorLog& log,
                                const Scenario& scenario);

// one step [t, t_end] (t_end = t + h, passed so a run's clock can count steps rather than add
// them up): commands through on_commands, limits and wrenches through on_step, `advance` moves
// the machine by h (the machine alone: its own step; in a pile: the coupled split step), then the
// sensors at t_end through on_sensors into the log; returns what the sensors report. The effect
// set must have been started on this loader.
SensorSample step_with_effects(WheelLoader& loader, EffectSet& effects, double t, double h, double t_end,
                               ActuatorCommands commands, const std::function<void()>& advance,
                               SensorLog* log);
// the same for the machine alone on its own step, ending at t + h
SensorSample step_with_effects(WheelLoader& loader, EffectSet& effects, double t, double h,
                               ActuatorCommands commands, SensorLog* log = nullptr);

}  // namespace talus::vehicle
