#include "vehicle/effect.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "host/error.hpp"

namespace talus::vehicle {

namespace {

// a number for messages: shortest form that reads back ("0.3", "1e+05")
std::string number_text(double x) {
  std::ostringstream s;
  s << x;
  return s.str();
}

std::string range_text(const EffectParameter& p) {
  const std::string unit = p.unit.empty() || p.unit == "1" ? "" : " " + p.unit;
  return "[" + number_text(p.min) + ", " + number_text(p.max) + "]" + unit;
}

// the names an effect accepts, for "unknown parameter" messages
std::string accepted_names(const std::vector<EffectParameter>& parameters, const std::vector<EffectOption>& options) {
  std::string list;
  for (const auto& o : options) list += (list.empty() ? "" : ", ") + o.name;
  for (const auto& p : parameters) list += (list.empty() ? "" : ", ") + p.name + " " + range_text(p);
  return list.empty() ? "none" : list;
}

// P = f_tr v + f_l ḋ_l + f_t ḋ_t (vehicle/sensors.cpp)
double derived_power(const SensorSample& s) {
  return s.f_traction * s.v_drive + s.f_lift * s.lift_rate + s.f_tilt * s.tilt_rate;
}

bool power_inputs_differ(const SensorSample& a, const SensorSample& b) {
  return a.f_lift != b.f_lift || a.f_tilt != b.f_tilt || a.f_traction != b.f_traction || a.v_drive != b.v_drive ||
         a.lift_rate != b.lift_rate || a.tilt_rate != b.tilt_rate;
}

}  // namespace

// step controls

StepControls::StepControls(WheelLoader& loader)
    : loader_(loader), wrenches_(loader.bodies().size(), Vec6::Zero()) {}

void StepControls::set_lift_force_range(double force_min, double force_max) {
  if (!(force_min <= force_max))
    throw Error("effects: lift force range [" + number_text(force_min) + ", " + number_text(force_max) +
                "] N is empty; an effect must keep min <= max");
  for (auto* c : loader_.lift_cylinders()) {
    c->motor.force_min = force_min;
    c->motor.force_max = force_max;
  }
}

void StepControls::set_tilt_force_range(double force_min, double force_max) {
  if (!(force_min <= force_max))
    throw Error("effects: tilt force range [" + number_text(force_min) + ", " + number_text(force_max) +
                "] N is empty; an effect must keep min <= max");
  loader_.tilt_cylinder().motor.force_min = force_min;
  loader_.tilt_cylinder().motor.force_max = force_max;
}

double StepControls::lift_force_min() const { return loader_.lift_cylinders()[0]->motor.force_min; }
double StepControls::lift_force_max() const { return loader_.lift_cylinders()[0]->motor.force_max; }
double StepControls::tilt_force_min() const { return loader_.tilt_cylinder().motor.force_min; }
double StepControls::tilt_force_max() const { return loader_.tilt_cylinder().motor.force_max; }

void StepControls::set_drive_power_limit(double watts) { loader_.set_drive_power_limit(watts); }
double StepControls::drive_power_limit() const { return loader_.driveline().power_limit(); }

void StepControls::add_wrench(int body, const Vec6& wrench) {
  if (body < 0 || body >= static_cast<int>(wrenches_.size()))
    throw Error("effects: a wrench on body " + std::to_string(body) + ", which the machine does not have");
  if (body == loader_.bucket_body())
    throw Error("effects: a wrench on the bucket; the particle coupling sets the bucket's wrench every step, "
                "so put the force on another body (boom, front_frame, ...)");
  wrenches_[body] += wrench;
}

// effect

Effect::Effect(std::string name, std::string summary) : name_(std::move(name)), summary_(std::move(summary)) {}

int Effect::add_parameter(EffectParameter p) {
  parameters_.push_back(std::move(p));
  return static_cast<int>(parameters_.size()) - 1;
}

int Effect::add_option(EffectOption o) {
  options_.push_back(std::move(o));
  return static_cast<int>(options_.size()) - 1;
}

void Effect::redefine_parameter(int index, double min, double max, const std::string& unit) {
  EffectParameter& p = parameters_.at(index);
  if (p.value < min || p.value > max) {
    throw InputError("effect '" + name_ + "': parameter '" + p.name + "' = " + number_text(p.value) + " is outside [" +
                     number_text(min) + ", " + number_text(max) + "] " + unit +
                     " for this choice; set the option first, then the value");
  }
  p.min = min;
  p.max = max;
  p.unit = unit;
}

double Effect::get(const std::string& parameter) const {
  for (const auto& p : parameters_)
    if (p.name == parameter) return p.value;
  throw Error("effect '" + name_ + "' has no parameter '" + parameter + "'");
}

const std::string& Effect::option(const std::string& name) const {
  for (const auto& o : options_)
    if (o.name == name) return o.value;
  throw Error("effect '" + name_ + "' has no option '" + name + "'");
}

void Effect::set(const std::string& parameter, double value) {
  for (auto& p : parameters_) {
    if (p.name != parameter) continue;
    if (!std::isfinite(value) || value < p.min || value > p.max) {
      throw InputError("effect '" + name_ + "': parameter '" + p.name + "' = " + number_text(value) +
                       " is outside its range " + range_text(p) + " (" + p.meaning + "); give a value in range");
    }
    p.value = value;
    changed();
    return;
  }
  throw InputError("effect '" + name_ + "' has no parameter '" + parameter +
                   "'; it accepts: " + accepted_names(parameters_, options_));
}

void Effect::set_text(const std::string& name, const std::string& text) {
  for (auto& o : options_) {
    if (o.name != name) continue;
    for (const auto& c : o.choices) {
      if (c == text) {
        // a choice may narrow a parameter's range: on failure the old choice stays
        const std::string old = o.value;
        o.value = text;
        try {
          changed();
        } catch (...) {
          o.value = old;
          changed();
          throw;
        }
        return;
      }
    }
    std::string list;
    for (const auto& c : o.choices) list += (list.empty() ? "" : ", ") + c;
    throw InputError("effect '" + name_ + "': option '" + name + "' = '" + text + "' is not one of " + list +
                     " (" + o.meaning + ")");
  }
  // a parameter: the whole text must be one number
  const char* begin = text.c_str();
  char* end = nullptr;
  const double value = std::strtod(begin, &end);
  bool known = false;
  for (const auto& p : parameters_) known = known || p.name == name;
  if (known && (text.empty() || end != begin + text.size()))
    throw InputError("effect '" + name_ + "': parameter '" + name + "' = '" + text + "' is not a number");
  set(name, value);
}

nlohmann::json Effect::to_json() const {
  nlohmann::json params = nlohmann::json::object();
  for (const auto& o : options_) params[o.name] = o.value;
  for (const auto& p : parameters_) params[p.name] = p.value;
  return {{"name", name_}, {"params", params}};
}

// effect set

void EffectSet::add(std::unique_ptr<Effect> effect) {
  if (!effect) throw Error("effects: add() got no effect");
  effects_.push_back(std::move(effect));
  reset_done_ = false;
}

SoilProperties EffectSet::soil(SoilProperties base) const {
  SoilProperties soil = base;
  for (const auto& e : effects_) e->on_soil(soil);
  return soil;
}

nlohmann::json EffectSet::to_json() const {
  nlohmann::json list = nlohmann::json::array();
  for (const auto& e : effects_) list.push_back(e->to_json());
  return list;
}

void EffectSet::reset(WheelLoader& loader, double t) {
  loader_ = &loader;
  const auto& lift = loader.lift_cylinders();
  force_range_[0] = {lift[0]->motor.force_min, lift[0]->motor.force_max};
  force_range_[1] = {lift[1]->motor.force_min, lift[1]->motor.force_max};
  force_range_[2] = {loader.tilt_cylinder().motor.force_min, loader.tilt_cylinder().motor.force_max};
  power_limit_ = loader.driveline().power_limit();
  previous_ = read_sensors(loader, t);
  for (auto& e : effects_) e->reset(loader);
  reset_done_ = true;
}

void EffectSet::set_dig_phase(double start, double end) {
  if (!std::isfinite(start) || !std::isfinite(end))
    throw Error("effects: the digging phase [" + std::to_string(start) + ", " +
                std::to_string(end) + ") s is not finite");
  dig_start_ = start;
  dig_end_ = end;
}

ActuatorCommands EffectSet::commands(double t, double h, ActuatorCommands commands) {
  if (!reset_done_) throw Error("effects: reset() the effect set on the machine before the first step");
  const EffectContext context{t, h, previous_, *loader_, digging(t)};
  for (auto& e : effects_) e->on_commands(context, commands);
  return commands;
}

void EffectSet::before_step(double t, double h, WheelLoader& loader) {
  if (!reset_done_ || &loader != loader_)
    throw Error("effects: reset() the effect set on this machine before stepping it");
  // the machine's own limits, then each effect's changes on top
  const auto& lift = loader.lift_cylinders();
  for (int i = 0; i < 2; ++i) {
    lift[i]->motor.force_min = force_range_[i].first;
    lift[i]->motor.force_max = force_range_[i].second;
  }
  loader.tilt_cylinder().motor.force_min = force_range_[2].first;
  loader.tilt_cylinder().motor.force_max = force_range_[2].second;
  loader.set_drive_power_limit(power_limit_);
  if (effects_.empty()) return;
  StepControls controls(loader);
  const EffectContext context{t, h, previous_, loader, digging(t)};
  for (auto& e : effects_) e->on_step(context, controls);
  // the summed wrenches (set_external_wrench replaces a body's wrench; only bodies that got one)
  const auto& wrenches = controls.wrenches();
  for (size_t b = 0; b < wrenches.size(); ++b) {
    if (!wrenches[b].isZero(0.0)) loader.system().set_external_wrench(static_cast<int>(b), wrenches[b]);
  }
}

SensorSample EffectSet::sensors(double h, const SensorSample& truth) {
  if (!reset_done_) throw Error("effects: reset() the effect set on the machine before reading sensors");
  SensorSample s = truth;
  const EffectContext context{truth.t, h, previous_, *loader_, digging(truth.t)};
  for (auto& e : effects_) {
    const SensorSample before = s;
    e->on_sensors(context, s);
    // power is derived from the readings unless the effect acts on the power channel itself
    if (power_inputs_differ(before, s) && s.power == before.power) s.power = derived_power(s);
  }
  previous_ = truth;
  return s;
}

void EffectSet::save_state(ByteWriter& w) const {
  if (!reset_done_) throw Error("effects: save_state() before the set was reset on its machine");
  for (const auto& e : effects_)
    if (!e->savable())
      throw Error("effects: the state of effect '" + e->name() +
                  "' (a plug-in's, opaque to talus) cannot be saved yet (issue 16); save a run "
                  "without it");
  w.u64(effects_.size());
  for (const auto& e : effects_) {
    w.tag(e->name());
    e->save_state(w);
  }
  write_sample(w, previous_);
}

void EffectSet::restore_state(ByteReader& r) {
  if (!reset_done_) throw Error("effects: restore_state() before the set was reset on its machine");
  const std::uint64_t n = r.u64("effects");
  if (n != effects_.size())
    throw InputError(r.where() + ": the saved run has " + std::to_string(n) +
                     " effects, this one " + std::to_string(effects_.size()) +
                     "; restore into a run with the same effects");
  for (const auto& e : effects_) {
    if (!e->savable())
      throw Error("effects: the state of effect '" + e->name() + "' cannot be restored yet");
    r.expect(e->name());
    e->restore_state(r);
  }
  previous_ = read_sample(r, "effects' previous sample");
}

SensorSample start_with_effects(WheelLoader& loader, EffectSet& effects, SensorLog& log,
                                const Scenario& scenario) {
  effects.reset(loader, 0.0);
  effects.set_dig_phase(scenario.dig_start, scenario.dig_end);
  const SensorSample reported = effects.sensors(0.0, read_sensors(loader, 0.0));
  log.after_step(reported, 0.0);
  return reported;
}

SensorSample step_with_effects(WheelLoader& loader, EffectSet& effects, double t, double h, double t_end,
                               ActuatorCommands commands, const std::function<void()>& advance,
                               SensorLog* log) {
  // the commands at the step's start, through the effects
  const ActuatorCommands c = effects.commands(t, h, commands);
  loader.set_drive_speed(c.drive);
  loader.set_lift_speed(c.lift);
  loader.set_tilt_speed(c.tilt);
  // the machine's limits and the effects' wrenches, then the step itself
  effects.before_step(t, h, loader);
  advance();
  // what the sensors report after it
  const SensorSample reported = effects.sensors(h, read_sensors(loader, t_end));
  if (log) log->after_step(reported, h);
  return reported;
}

SensorSample step_with_effects(WheelLoader& loader, EffectSet& effects, double t, double h, ActuatorCommands commands,
                               SensorLog* log) {
  return step_with_effects(loader, effects, t, h, t + h, commands, [&] { loader.step(h); }, log);
}

}  // namespace talus::vehicle
