// The learned corrections' dictionaries and the three effects that run them (docs/discovery.md).
#include "vehicle/learned_correction.hpp"

#include <algorithm>
#include <cmath>
#include <deque>
#include <utility>

#include "host/error.hpp"
#include "vehicle/sensor_channels.hpp"

namespace talus::vehicle {

namespace {

// below this commanded speed sign(u) ramps linearly to zero [m/s], as cylinder_friction's: a tenth
// of the slowest commands in the scenarios, so moving actuators see ±1 and a held one 0
constexpr double kSignRampSpeed = 1e-3;

double ramp_sign(double a) { return std::clamp(a / kSignRampSpeed, -1.0, 1.0); }

// a dead-band feature clip(u, ±δ₀), its width δ₀ given in mm/s. The dictionary's widths: a valve's
// dead band is a few to about twenty percent of its spool stroke, 10-40 mm/s of the wa320's fastest
// cylinder (218 mm/s, data/machines/wa320.json), on a doubling ladder (10, 20, 40) so any width
// between lies near one of them. Beside sign(u) they say how the loss fades as the command crosses
// zero: a command inside the band moves nothing (Δu = −u), one beyond it loses δ (Δu = −δ sign u)
template <int kWidthMillimetresPerSecond>
double dead_band(const CorrectionInputs& x) {
  constexpr double width = kWidthMillimetresPerSecond * 1e-3;  // m/s
  return std::clamp(x.a, -width, width);
}

// the entries the dictionaries share, written once: the offset and the delayed differences
const CorrectionFeature kOne{"one", "1", "1", [](const CorrectionInputs&) { return 1.0; }};
const CorrectionFeature kDelay01{"delay_01", "{a}(t−0.1 s) − {a}", "{a}",
                                 [](const CorrectionInputs& x) { return x.a_delayed[0] - x.a; }};
const CorrectionFeature kDelay02{"delay_02", "{a}(t−0.2 s) − {a}", "{a}",
                                 [](const CorrectionInputs& x) { return x.a_delayed[1] - x.a; }};
const CorrectionFeature kDelay04{"delay_04", "{a}(t−0.4 s) − {a}", "{a}",
                                 [](const CorrectionInputs& x) { return x.a_delayed[2] - x.a; }};
// the phase: an indicator of the digging phase ([dig] is 1 inside it), alone (a loss or offset
// that only the dig brings) and times the quantity (a gain that changes while the bucket digs)
const CorrectionFeature kDigging{"digging", "[dig]", "1",
                                 [](const CorrectionInputs& x) { return x.digging; }};
const CorrectionFeature kDiggingTimes{"digging_times", "[dig]·{a}", "{a}",
                                      [](const CorrectionInputs& x) { return x.digging * x.a; }};
// the stroke times the quantity: a loss or gain that grows along the stroke (a worn bore, a load
// cell whose lever arm turns with the boom)
const CorrectionFeature kStrokeTimes{"stroke_times", "{s}·{a}", "m·{a}",
                                     [](const CorrectionInputs& x) { return x.stroke * x.a; }};

// the actuator dictionary: offsets, the command and its sign and square (speed-dependent losses),
// the command clipped at three widths (dead bands), the force alone and with the command (leakage
// with pressure, friction), the power, delayed differences (a lag) and a force-scaled one (a delay
// that grows with load), the stroke alone and with the command (a speed that depends on where the
// piston is: end-of-stroke cushioning, a worn bore) and the digging phase alone and with the
// command (a loss only the dig brings). The last four came after the first fifteen (2026-12-01),
// appended so the older entries keep their order. Not the actuator's own achieved speed: the
// regression would learn the tautology "the correction is the measured speed minus the command",
// which in the simulation feeds the previous speed back as the command and stalls the actuator
const std::vector<CorrectionFeature> kActuatorFeatures = {
    kOne,
    {"command", "{a}", "{a}", [](const CorrectionInputs& x) { return x.a; }},
    {"sign_command", "sign({a})", "1", [](const CorrectionInputs& x) { return ramp_sign(x.a); }},
    {"command_squared", "{a}·|{a}|", "{a}^2",
     [](const CorrectionInputs& x) { return x.a * std::abs(x.a); }},
    {"dead_band_001", "clip({a}, ±0.01 m/s)", "{a}", dead_band<10>},
    {"dead_band_002", "clip({a}, ±0.02 m/s)", "{a}", dead_band<20>},
    {"dead_band_004", "clip({a}, ±0.04 m/s)", "{a}", dead_band<40>},
    {"force", "{F}", "N", [](const CorrectionInputs& x) { return x.force; }},
    {"force_sign_command", "{F}·sign({a})", "N",
     [](const CorrectionInputs& x) { return x.force * ramp_sign(x.a); }},
    {"abs_force_command", "|{F}|·{a}", "N·{a}",
     [](const CorrectionInputs& x) { return std::abs(x.force) * x.a; }},
    {"power", "{P}", "W", [](const CorrectionInputs& x) { return x.power; }},
    kDelay01,
    kDelay02,
    kDelay04,
    {"abs_force_delay_02", "|{F}|·({a}(t−0.2 s) − {a})", "N·{a}",
     [](const CorrectionInputs& x) { return std::abs(x.force) * (x.a_delayed[1] - x.a); }},
    {"stroke", "{s}", "m", [](const CorrectionInputs& x) { return x.stroke; }},
    kStrokeTimes,
    kDigging,
    kDiggingTimes,
};

// the sensor dictionary: an offset, a gain, a square law, a load-dependent gain (the lift force
// carries the load), the rate (a first-order sensor lag reads x − τ ẋ), the lift force alone,
// delayed differences (a transport delay), a gain that changes with the boom's stroke and the
// digging phase alone and as a gain (the last three appended 2026-12-01)
const std::vector<CorrectionFeature> kSensorFeatures = {
    kOne,
    {"reading", "{a}", "{a}", [](const CorrectionInputs& x) { return x.a; }},
    {"reading_squared", "{a}·|{a}|", "{a}^2",
     [](const CorrectionInputs& x) { return x.a * std::abs(x.a); }},
    {"abs_force_reading", "|{F}|·{a}", "N·{a}",
     [](const CorrectionInputs& x) { return std::abs(x.force) * x.a; }},
    {"rate", "{v}", "{v}", [](const CorrectionInputs& x) { return x.rate; }},
    {"force", "{F}", "N", [](const CorrectionInputs& x) { return x.force; }},
    kDelay01,
    kDelay02,
    kDelay04,
    kStrokeTimes,
    kDigging,
    kDiggingTimes,
};

// sign(v) of the drive's speed, linear below kTractionSignRampSpeed
double speed_sign(double v) { return std::clamp(v / kTractionSignRampSpeed, -1.0, 1.0); }

// the traction dictionary: a constant force (a load dragged along), a force against the motion
// (rolling resistance) alone and growing with the load the axles carry (|f_lift|), forces
// growing with the speed (driveline drag) and its square (ploughing), the 0.1 s delayed difference
// of the speed (−0.1 s times the acceleration: a mass the model lacks), and the digging phase
// alone and against the motion (a resistance only the pile brings)
const std::vector<CorrectionFeature> kTractionFeatures = {
    kOne,
    {"sign_speed", "sign({a})", "1", [](const CorrectionInputs& x) { return speed_sign(x.a); }},
    {"abs_force_sign_speed", "|{F}|·sign({a})", "N",
     [](const CorrectionInputs& x) { return std::abs(x.force) * speed_sign(x.a); }},
    {"speed", "{a}", "{a}", [](const CorrectionInputs& x) { return x.a; }},
    {"speed_squared", "{a}·|{a}|", "{a}^2",
     [](const CorrectionInputs& x) { return x.a * std::abs(x.a); }},
    kDelay01,
    kDigging,
    {"digging_sign_speed", "[dig]·sign({a})", "1",
     [](const CorrectionInputs& x) { return x.digging * speed_sign(x.a); }},
};

// every "{key}" in text replaced by its value
std::string substitute(std::string text,
                       const std::vector<std::pair<std::string, std::string>>& values) {
  for (const auto& [key, value] : values) {
    for (std::size_t at = text.find(key); at != std::string::npos;
         at = text.find(key, at + value.size()))
      text.replace(at, key.size(), value);
  }
  return text;
}

// the unit of a coefficient: the correction's unit per the feature's
std::string coefficient_unit(const std::string& correction_unit, const std::string& feature_unit) {
  if (feature_unit == "1") return correction_unit;
  return "(" + correction_unit + ")/(" + feature_unit + ")";
}

// the value of a series pushed in time order at an earlier time, linear between pushes and the
// first value before the first push (the machine is at rest before a run)
class DelayLine {
 public:
  void clear() { past_.clear(); }
  // forgets what no delay reaches any more: keeps one entry at or before t − the longest delay
  void push(double t, double value) {
    past_.emplace_back(t, value);
    while (past_.size() > 1 && past_[1].first <= t - kCorrectionDelays.back()) past_.pop_front();
  }
  void save_state(ByteWriter& w) const {
    w.u64(past_.size());
    for (const auto& [t, v] : past_) {
      w.f64(t);
      w.f64(v);
    }
  }
  void restore_state(ByteReader& r) {
    const std::uint64_t n = r.u64("delay line");
    r.need_elements(n, 2 * 8, "delay line");
    past_.clear();
    for (std::uint64_t k = 0; k < n; ++k) {
      const double t = r.f64("delay line");
      past_.emplace_back(t, r.f64("delay line"));
    }
  }
  double at(double when) const {
    if (past_.empty()) return 0.0;
    if (when <= past_.front().first) return past_.front().second;
    for (std::size_t i = 1; i < past_.size(); ++i) {
      const auto& [t1, v1] = past_[i];
      if (when <= t1) {
        const auto& [t0, v0] = past_[i - 1];
        return v0 + (when - t0) / (t1 - t0) * (v1 - v0);
      }
    }
    return past_.back().second;
  }

 private:
  std::deque<std::pair<double, double>> past_;
};

// a force and the power through the pressure lag kForceLag (the first update starts it at the
// readings): what the actuator and traction corrections read, and their memory between steps
class LaggedReadings {
 public:
  void clear() { started_ = false; }
  void update(double force, double power, double h) {
    force_ = started_ ? lag_step(force_, force, h) : force;
    power_ = started_ ? lag_step(power_, power, h) : power;
    started_ = true;
  }
  double force() const { return force_; }
  double power() const { return power_; }
  void save_state(ByteWriter& w) const {
    w.u8(started_ ? 1 : 0);
    w.f64(force_);
    w.f64(power_);
  }
  void restore_state(ByteReader& r, const char* what) {
    started_ = r.u8(what) != 0;
    force_ = r.f64(what);
    power_ = r.f64(what);
  }

 private:
  bool started_ = false;
  double force_ = 0.0, power_ = 0.0;  // N, W
};

// Σ c_k φ_k over the nonzero coefficients
double correction_of(const std::vector<CorrectionFeature>& features, const std::vector<double>& c,
                     const CorrectionInputs& x) {
  double sum = 0.0;
  for (std::size_t k = 0; k < features.size(); ++k)
    if (c[k] != 0.0) sum += c[k] * features[k].value(x);
  return sum;
}

// the common part of the three effects: one parameter per dictionary feature, reported when
// nonzero
class LearnedCorrection : public Effect {
 public:
  LearnedCorrection(const char* name, const char* summary, CorrectionKind kind)
      : Effect(name, summary), features_(correction_features(kind)) {}

  nlohmann::json to_json() const override {
    nlohmann::json params = nlohmann::json::object();
    for (const auto& o : options()) params[o.name] = o.value;
    for (const auto& p : parameters())
      if (p.value != 0.0) params[p.name] = p.value;
    return {{"name", name()}, {"params", params}};
  }

 protected:
  // one coefficient per feature, zero, in the units of `symbols`
  void declare_coefficients(const CorrectionSymbols& symbols) {
    for (const auto& f : features_) {
      coefficient_index_.push_back(
          add_parameter({f.name, 0.0, -kMaxCorrectionCoefficient, kMaxCorrectionCoefficient,
                         coefficient_unit(symbols.corrected_unit, correction_unit(f, symbols)),
                         "coefficient of " + correction_expression(f, symbols)}));
    }
  }
  void redefine_units(const CorrectionSymbols& symbols) {
    for (std::size_t k = 0; k < features_.size(); ++k)
      redefine_parameter(
          coefficient_index_[k], -kMaxCorrectionCoefficient, kMaxCorrectionCoefficient,
          coefficient_unit(symbols.corrected_unit, correction_unit(features_[k], symbols)));
  }
  // the correction at x (the coefficients read once per call: a handful of features)
  double correction(const CorrectionInputs& x) const {
    std::vector<double> c(features_.size());
    for (std::size_t k = 0; k < c.size(); ++k) c[k] = value(coefficient_index_[k]);
    return correction_of(features_, c, x);
  }
  // the inputs' delayed values from the delay line, after pushing (t, a)
  void delay(double t, CorrectionInputs& x) {
    line_.push(t, x.a);
    for (std::size_t i = 0; i < kCorrectionDelays.size(); ++i)
      x.a_delayed[i] = line_.at(t - kCorrectionDelays[i]);
  }
  void clear_history() { line_.clear(); }
  // the delay line is the memory every kind carries between steps
  void save_state(ByteWriter& w) const override { line_.save_state(w); }
  void restore_state(ByteReader& r) override { line_.restore_state(r); }
  // the pushed quantity at an earlier time (the delay line's interpolation)
  double history_at(double when) const { return line_.at(when); }

 private:
  const std::vector<CorrectionFeature>& features_;
  std::vector<int> coefficient_index_;
  DelayLine line_;
};

// the part the actuator and traction corrections share: a force and the power read through the
// pressure lag, which they carry between steps beside the delay line
class LaggedCorrection : public LearnedCorrection {
 public:
  using LearnedCorrection::LearnedCorrection;
  void reset(const WheelLoader& loader) override {
    (void)loader;
    clear_history();
    lagged_.clear();
  }
  // the delay line, then the lagged force and power
  void save_state(ByteWriter& w) const override {
    LearnedCorrection::save_state(w);
    lagged_.save_state(w);
  }
  void restore_state(ByteReader& r) override {
    LearnedCorrection::restore_state(r);
    lagged_.restore_state(r, name().c_str());
  }

 protected:
  LaggedReadings lagged_;
};

// --- learned_actuator_correction --------------------------------------------------------------
class LearnedActuatorCorrection : public LaggedCorrection {
 public:
  LearnedActuatorCorrection()
      : LaggedCorrection(
            "learned_actuator_correction",
            "a discovered correction of one actuator's speed: Σ c_k φ_k added to its target",
            CorrectionKind::actuator) {
    actuator_ = add_option({"actuator",
                            "lift",
                            {"drive", "lift", "tilt"},
                            "the actuator whose target speed it corrects"});
    declare_coefficients(correction_symbols(CorrectionKind::actuator, "lift"));
  }
  void changed() override {
    redefine_units(correction_symbols(CorrectionKind::actuator, option_value(actuator_)));
  }
  void on_commands(const EffectContext& c, ActuatorCommands& u) override {
    const std::string& which = option_value(actuator_);
    double& target = which == "drive" ? u.drive : which == "lift" ? u.lift : u.tilt;
    // the force and the power through the pressure lag (the first step starts it at the reading)
    const double force = which == "drive"  ? c.previous.f_traction
                         : which == "lift" ? c.previous.f_lift
                                           : c.previous.f_tilt;
    lagged_.update(force, c.previous.power, c.h);
    CorrectionInputs x;
    x.a = target;
    x.force = lagged_.force();
    x.power = lagged_.power();
    x.stroke = which == "tilt" ? c.previous.d_tilt : c.previous.d_lift;
    x.digging = c.digging ? 1.0 : 0.0;
    delay(c.t, x);
    target += correction(x);
  }

 private:
  int actuator_ = 0;  // the option's index
};

// --- learned_traction_correction ------------------------------------------------------------
class LearnedTractionCorrection : public LaggedCorrection {
 public:
  LearnedTractionCorrection()
      : LaggedCorrection("learned_traction_correction",
                         "a discovered force against the machine's motion: Σ c_k φ_k [N] the "
                         "drive must overcome",
                         CorrectionKind::traction) {
    declare_coefficients(correction_symbols(CorrectionKind::traction, "traction"));
  }
  void on_step(const EffectContext& c, StepControls& controls) override {
    // the load and the power through the pressure lag
    lagged_.update(c.previous.f_lift, c.previous.power, c.h);
    CorrectionInputs x;
    x.a = c.previous.v_drive;
    x.force = lagged_.force();
    x.power = lagged_.power();
    x.stroke = c.previous.d_lift;
    x.digging = c.digging ? 1.0 : 0.0;
    delay(c.t, x);
    const double force = correction(x);
    // −Δf along the headings, the same share at every wheel's centre (as tyre_rolling_resistance
    // acts), so it turns the machine no more than its own tyres do
    const auto& tyres = c.loader.tyres();
    if (force == 0.0) return;
    const double share = force / static_cast<double>(tyres.size());
    for (const TyreContact* tyre : tyres) {
      Vec6 w = Vec6::Zero();
      w.head<3>() = -share * tyre->longitudinal();
      controls.add_wrench(tyre->wheel(), w);
    }
  }
};

// --- learned_sensor_correction ----------------------------------------------------------------
std::vector<std::string> correctable_channels() {
  std::vector<std::string> names;
  for (std::size_t c = 1; c < kChannelCount; ++c) names.emplace_back(kSensorChannels[c].name);
  return names;
}

double SensorSample::*channel_field(const std::string& name) {
  for (std::size_t c = 1; c < kChannelCount; ++c)
    if (name == kSensorChannels[c].name) return kSensorChannels[c].field;
  throw Error("learned_sensor_correction: no channel '" + name + "'");
}

class LearnedSensorCorrection : public LearnedCorrection {
 public:
  LearnedSensorCorrection()
      : LearnedCorrection(
            "learned_sensor_correction",
            "a discovered correction of one sensor channel: Σ c_k φ_k added to its reading",
            CorrectionKind::sensor) {
    channel_ =
        add_option({"channel", "f_lift", correctable_channels(), "the sensor channel it corrects"});
    declare_coefficients(correction_symbols(CorrectionKind::sensor, "f_lift"));
  }
  void changed() override {
    field_ = channel_field(option_value(channel_));
    redefine_units(correction_symbols(CorrectionKind::sensor, option_value(channel_)));
  }
  void reset(const WheelLoader& loader) override {
    (void)loader;
    clear_history();
  }
  void on_sensors(const EffectContext& c, SensorSample& s) override {
    CorrectionInputs x;
    x.a = s.*field_;
    x.force = s.f_lift;
    x.power = s.power;
    x.stroke = s.d_lift;
    x.digging = c.digging ? 1.0 : 0.0;
    delay(s.t, x);
    // the rate over kRateSpan of the true readings the effect saw, as the data path takes it
    x.rate = (x.a - history_at(s.t - kRateSpan)) / kRateSpan;
    s.*field_ += correction(x);
  }
  std::vector<Channel> sensor_channels() const override {
    for (std::size_t c = 1; c < kChannelCount; ++c)
      if (kSensorChannels[c].field == field_) return {static_cast<Channel>(c)};
    return {};
  }

 private:
  int channel_ = 0;
  double SensorSample::*field_ = &SensorSample::f_lift;
};

}  // namespace

const std::vector<CorrectionFeature>& correction_features(CorrectionKind kind) {
  switch (kind) {
    case CorrectionKind::actuator:
      return kActuatorFeatures;
    case CorrectionKind::sensor:
      return kSensorFeatures;
    case CorrectionKind::traction:
      return kTractionFeatures;
  }
  throw Error("learned correction: unknown kind");
}

CorrectionSymbols correction_symbols(CorrectionKind kind, const std::string& target) {
  CorrectionSymbols s;
  if (kind == CorrectionKind::actuator) {
    if (target != "drive" && target != "lift" && target != "tilt")
      throw Error("learned correction: no actuator '" + target + "' (drive, lift, tilt)");
    s.a = "u_" + target;
    s.a_unit = "m/s";
    s.corrected = s.a;
    s.corrected_unit = s.a_unit;
    s.force = target == "drive" ? "f_traction" : "f_" + target;
    s.stroke = target == "tilt" ? "d_tilt" : "d_lift";
    return s;
  }
  if (kind == CorrectionKind::traction) {
    if (target != "traction")
      throw Error("learned correction: the traction kind's target is 'traction', not '" + target +
                  "'");
    s.corrected = "f_traction";
    s.corrected_unit = "N";
    s.a = "v_drive";
    s.a_unit = "m/s";
    return s;
  }
  for (std::size_t c = 1; c < kChannelCount; ++c) {
    if (target == kSensorChannels[c].name) {
      s.a = target;
      s.a_unit = kSensorChannels[c].unit;
      s.corrected = s.a;
      s.corrected_unit = s.a_unit;
      s.rate = "d" + target + "/dt";
      s.rate_unit = s.a_unit + "/s";
      return s;
    }
  }
  throw Error("learned correction: no sensor channel '" + target + "'");
}

std::string correction_expression(const CorrectionFeature& f, const CorrectionSymbols& s) {
  return substitute(
      f.expression,
      {{"{a}", s.a}, {"{v}", s.rate}, {"{F}", s.force}, {"{P}", s.power}, {"{s}", s.stroke}});
}

std::string correction_unit(const CorrectionFeature& f, const CorrectionSymbols& s) {
  return substitute(f.unit, {{"{a}", s.a_unit}, {"{v}", s.rate_unit}});
}

std::vector<std::string> learned_effect_names() {
  return {"learned_actuator_correction", "learned_traction_correction",
          "learned_sensor_correction"};
}

std::unique_ptr<Effect> make_learned_effect(const std::string& name) {
  if (name == "learned_actuator_correction") return std::make_unique<LearnedActuatorCorrection>();
  if (name == "learned_traction_correction") return std::make_unique<LearnedTractionCorrection>();
  if (name == "learned_sensor_correction") return std::make_unique<LearnedSensorCorrection>();
  throw InputError("no learned correction named '" + name +
                   "'; they are learned_actuator_correction, learned_traction_correction and "
                   "learned_sensor_correction");
}

}  // namespace talus::vehicle
