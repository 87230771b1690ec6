// The built-in effects (issue 6, SPEC §6); equations, ranges and signatures in docs/effects.md.
#include <algorithm>
#include <array>
#include <cmath>
#include <deque>
#include <utility>

#include "host/error.hpp"
#include "vehicle/effect.hpp"
#include "vehicle/sensor_channels.hpp"

namespace talus::vehicle {

namespace {

// a Coulomb law's sign regularised below a speed: linear through zero, so a machine at rest is not
// pushed and a held cylinder reads no friction (the sign of a zero speed is undefined)
double regularised_sign(double speed, double ramp_speed) { return std::clamp(speed / ramp_speed, -1.0, 1.0); }

// the largest bias accepted on each channel but time, in the channel's unit
// (vehicle/sensor_channels.hpp): about a tenth of the channel's full scale on this machine class
// (lift force to 830 kN, traction 120 kN, speed 3.6 m/s, strokes 0.4-1.2 m, angles tens of
// degrees, positions metres, power 127 kW); a larger offset is a broken sensor, not a bias
struct BiasLimit {
  Channel channel;
  double max_bias;
};
constexpr std::array<BiasLimit, kChannelCount - 1> kMaxBias = {{
    {Channel::f_lift, 100e3},
    {Channel::f_tilt, 100e3},
    {Channel::f_traction, 20e3},
    {Channel::v_drive, 0.5},
    {Channel::d_lift, 0.1},
    {Channel::d_tilt, 0.05},
    {Channel::boom_deg, 10.0},
    {Channel::bucket_deg, 10.0},
    {Channel::pitch_deg, 5.0},
    {Channel::x_vehicle, 1.0},
    {Channel::bucket_tip_x, 1.0},
    {Channel::bucket_tip_z, 1.0},
    {Channel::power, 20e3},
}};

// the limit of column c, or a negative value when the table has none
constexpr double max_bias_of(std::size_t c) {
  for (const BiasLimit& b : kMaxBias) {
    if (static_cast<std::size_t>(b.channel) == c) return b.max_bias;
  }
  return -1.0;
}
// every channel but time has its limit
constexpr bool every_channel_has_a_bias_limit() {
  for (std::size_t c = 1; c < kChannelCount; ++c) {
    if (max_bias_of(c) < 0.0) return false;
  }
  return true;
}
static_assert(every_channel_has_a_bias_limit(), "kMaxBias lacks a channel of the contract");

// a sensor channel an effect may act on: every channel of the contract but time
struct ChannelInfo {
  const char* name;
  double SensorSample::*field;
  const char* unit;
  double max_bias;
};

ChannelInfo channel_info(const std::string& name) {
  for (std::size_t c = 1; c < kChannelCount; ++c) {
    const SensorChannel& ch = kSensorChannels[c];
    if (name == ch.name) return ChannelInfo{ch.name, ch.field, ch.unit, max_bias_of(c)};
  }
  throw Error("effects: no sensor channel '" + name + "'");
}

std::vector<std::string> channel_names() {
  std::vector<std::string> names;
  for (std::size_t c = 1; c < kChannelCount; ++c) names.emplace_back(kSensorChannels[c].name);
  return names;
}

// the extension rate that goes with a stroke channel (delayed with it), or nullptr
double SensorSample::*rate_of(const std::string& channel) {
  if (channel == "d_lift") return &SensorSample::lift_rate;
  if (channel == "d_tilt") return &SensorSample::tilt_rate;
  return nullptr;
}

// --- engine_power_sharing -------------------------------------------------------------------
// one engine (P_max, 127 kW) drives the driveline and the work pumps: the driveline gets what the
// lift and tilt hydraulics leave, P_drive <= max(floor, P_max - P_hyd / η), with
// P_hyd = (f_l ḋ_l)+ + (f_t ḋ_t)+ of the previous (true) sample
class EnginePowerSharing : public Effect {
 public:
  // the driveline's share never drops below this fraction of P_max: with no power left its torque
  // limit would vanish at any speed and the machine freewheel, which no loader does (the engine's
  // anti-stall control destrokes the work pumps first); 10 % is a plausible choice, not the paper's
  static constexpr double kMinDriveShare = 0.1;

  EnginePowerSharing()
      : Effect("engine_power_sharing",
               "the engine's power is shared by the driveline and the lift and tilt hydraulics (paper's diagnosis)") {
    efficiency_ = add_parameter({"efficiency", 0.8, 0.5, 1.0, "1",
                                 "hydraulic efficiency: engine power per unit of cylinder power"});
  }
  void on_step(const EffectContext& c, StepControls& controls) override {
    const double p_max = c.loader.max_power();
    const double hydraulic =
        std::max(0.0, c.previous.f_lift * c.previous.lift_rate) + std::max(0.0, c.previous.f_tilt * c.previous.tilt_rate);
    const double left = std::max(kMinDriveShare * p_max, p_max - hydraulic / value(efficiency_));
    controls.set_drive_power_limit(std::min(controls.drive_power_limit(), left));
  }

 private:
  int efficiency_ = 0;
};

// --- hydraulic_lag --------------------------------------------------------------------------
// the cylinders follow their valve commands with a first-order lag τ: u_a' = (u - u_a) / τ,
// backward Euler u_a += h / (τ + h) (u - u_a), stable for any h; drive is not lagged
class HydraulicLag : public Effect {
 public:
  HydraulicLag() : Effect("hydraulic_lag", "first-order lag of the lift and tilt cylinders behind their commands") {
    tau_ = add_parameter({"time_constant", 0.2, 0.0, 2.0, "s", "time constant of the lift and tilt response"});
  }
  void reset(const WheelLoader& loader) override {
    (void)loader;
    lift_ = tilt_ = 0.0;
  }
  void on_commands(const EffectContext& c, ActuatorCommands& u) override {
    const double lift = std::clamp(u.lift, -c.loader.lift_spec().max_speed, c.loader.lift_spec().max_speed);
    const double tilt = std::clamp(u.tilt, -c.loader.tilt_spec().max_speed, c.loader.tilt_spec().max_speed);
    const double a = c.h / (value(tau_) + c.h);
    lift_ += a * (lift - lift_);
    tilt_ += a * (tilt - tilt_);
    u.lift = lift_;
    u.tilt = tilt_;
  }
  void save_state(ByteWriter& w) const override {
    w.f64(lift_);
    w.f64(tilt_);
  }
  void restore_state(ByteReader& r) override {
    lift_ = r.f64("hydraulic lag");
    tilt_ = r.f64("hydraulic lag");
  }

 private:
  int tau_ = 0;
  double lift_ = 0.0, tilt_ = 0.0;  // m/s: the commands the cylinders follow now
};

// --- pump_flow_limit ------------------------------------------------------------------------
// one pump feeds the two lift cylinders and the tilt cylinder: when the commanded flow
// Q = 2 A_l |u_l| + A_t |u_t| (A: piston area extending, annulus area retracting) exceeds Q_max,
// both commands are scaled by Q_max / Q, so the bucket's path keeps its shape but slows
class PumpFlowLimit : public Effect {
 public:
  PumpFlowLimit() : Effect("pump_flow_limit", "one pump's flow limit shared by the lift and tilt cylinders") {
    max_flow_ = add_parameter({"max_flow", 5e-3, 1e-3, 3e-2, "m^3/s",
                               "the work pump's delivery to the cylinders (5e-3 m^3/s = 300 L/min)"});
  }
  // oil per second a cylinder takes at extension rate v [m^3/s]
  static double flow(const CylinderSpec& s, double v) { return (v >= 0.0 ? s.piston_area : s.annulus_area) * std::abs(v); }
  void on_commands(const EffectContext& c, ActuatorCommands& u) override {
    const CylinderSpec& l = c.loader.lift_spec();
    const CylinderSpec& t = c.loader.tilt_spec();
    const double lift = std::clamp(u.lift, -l.max_speed, l.max_speed);
    const double tilt = std::clamp(u.tilt, -t.max_speed, t.max_speed);
    const double q = 2.0 * flow(l, lift) + flow(t, tilt);
    const double scale = q > value(max_flow_) ? value(max_flow_) / q : 1.0;
    u.lift = scale * lift;
    u.tilt = scale * tilt;
  }

 private:
  int max_flow_ = 0;
};

// --- cylinder_friction ----------------------------------------------------------------------
// Coulomb friction F_c in each lift and tilt cylinder (seals, rod guide). The cylinders are
// velocity-controlled motors, so friction is modelled where it shows: the hydraulic force is the
// net force on the linkage plus F_c against the motion. Approximation: the direction of motion is
// the commanded one, s = sign(u) (regularised below kRampSpeed), since a velocity-controlled
// cylinder moves as commanded unless it stalls; then (1) the motor's force range, which stands for
// the relief-limited hydraulic force, shifts by -F_c s, so a stalled cylinder pushes F_c less, and
// (2) the pressure sensors read f = f_motor + F_c s, never beyond the relief force. A held cylinder
// (u = 0) keeps its range and reads no friction: its static friction is indeterminate (the
// baseline holds it rigidly anyway).
class CylinderFriction : public Effect {
 public:
  // below this commanded speed the friction ramps linearly to zero [m/s]: a tenth of the slowest
  // commands in the scenarios (0.01-0.2 m/s), so moving cylinders see the full F_c, and the
  // scenarios' ramps (0.2 s) switch it on smoothly
  static constexpr double kRampSpeed = 1e-3;

  CylinderFriction() : Effect("cylinder_friction", "Coulomb friction in the lift and tilt cylinders") {
    force_ = add_parameter({"force", 5e3, 0.0, 50e3, "N", "Coulomb friction force of each cylinder"});
  }
  void reset(const WheelLoader& loader) override {
    (void)loader;
    lift_sign_ = tilt_sign_ = 0.0;
  }
  void on_step(const EffectContext& c, StepControls& controls) override {
    (void)c;
    const double f = value(force_);
    lift_sign_ = regularised_sign(controls.loader().lift_cylinders()[0]->motor.target_speed, kRampSpeed);
    tilt_sign_ = regularised_sign(controls.loader().tilt_cylinder().motor.target_speed, kRampSpeed);
    controls.set_lift_force_range(controls.lift_force_min() - f * lift_sign_, controls.lift_force_max() - f * lift_sign_);
    controls.set_tilt_force_range(controls.tilt_force_min() - f * tilt_sign_, controls.tilt_force_max() - f * tilt_sign_);
  }
  void on_sensors(const EffectContext& c, SensorSample& s) override {
    (void)c;
    const double f = value(force_);
    s.f_lift += 2.0 * f * lift_sign_;  // two lift cylinders, summed
    s.f_tilt += f * tilt_sign_;
  }

 private:
  int force_ = 0;
  double lift_sign_ = 0.0, tilt_sign_ = 0.0;  // this step's directions of motion
};

// --- wheel_slip_sensor ----------------------------------------------------------------------
// the drive speed comes from wheel revolution, which runs ahead of the ground under traction
// (tyre slip): v_read = v + k |v| f_tr / F_tr,max, k the slip at the traction limit
class WheelSlipSensor : public Effect {
 public:
  WheelSlipSensor() : Effect("wheel_slip_sensor", "wheel slip under traction seen by the wheel-revolution speed sensor") {
    slip_ = add_parameter({"slip_at_limit", 0.1, 0.0, 0.5, "1", "longitudinal slip at the traction limit"});
  }
  void on_sensors(const EffectContext& c, SensorSample& s) override {
    s.v_drive += value(slip_) * std::abs(s.v_drive) * s.f_traction / c.loader.traction_limit();
  }
  std::vector<Channel> sensor_channels() const override { return {Channel::v_drive}; }

 private:
  int slip_ = 0;
};

// --- tyre_rolling_resistance ----------------------------------------------------------------
// a force c_rr N_i at each wheel's centre against its rolling along its heading, N_i the tyre's
// normal force of the last step: c_rr m g in all on flat ground with the bucket up, split by
// axle load
class TyreRollingResistance : public Effect {
 public:
  // below this wheel speed the resistance ramps linearly to zero [m/s], so a machine at rest is
  // not pushed; 1 cm/s is far below any driving speed (0.5-3.6 m/s)
  static constexpr double kRampSpeed = 0.01;

  TyreRollingResistance() : Effect("tyre_rolling_resistance", "rolling resistance of the tyres") {
    crr_ = add_parameter({"coefficient", 0.03, 0.0, 0.3, "1",
                          "rolling resistance per unit of tyre load (0.02-0.04 on gravel, more in soft ground)"});
  }
  void on_step(const EffectContext& c, StepControls& controls) override {
    const auto& bodies = c.loader.bodies();
    for (const TyreContact* tyre : c.loader.tyres()) {
      const Vec3 heading = tyre->longitudinal();
      const double v = bodies[tyre->wheel()].velocity.dot(heading);
      const double force = value(crr_) * std::max(0.0, tyre->normal_force()) * regularised_sign(v, kRampSpeed);
      Vec6 w = Vec6::Zero();
      w.head<3>() = -force * heading;
      controls.add_wrench(tyre->wheel(), w);
    }
  }

 private:
  int crr_ = 0;
};

// --- sensor_bias ----------------------------------------------------------------------------
class SensorBias : public Effect {
 public:
  SensorBias() : Effect("sensor_bias", "a constant offset on one sensor channel") {
    channel_ = add_option({"channel", "f_lift", channel_names(), "the sensor channel (timeseries.csv column)"});
    const ChannelInfo initial = channel_info(option_value(channel_));
    bias_ = add_parameter({"bias", 0.0, -initial.max_bias, initial.max_bias, initial.unit,
                           "offset added to the channel, in the channel's unit"});
  }
  void changed() override {
    const ChannelInfo ch = channel_info(option_value(channel_));
    field_ = ch.field;
    redefine_parameter(bias_, -ch.max_bias, ch.max_bias, ch.unit);
  }
  void on_sensors(const EffectContext& c, SensorSample& s) override {
    (void)c;
    s.*field_ += value(bias_);
  }

 private:
  int channel_ = 0, bias_ = 0;
  double SensorSample::*field_ = &SensorSample::f_lift;
};

// --- sensor_delay ---------------------------------------------------------------------------
// the channel reports its value of `delay` seconds ago (linear between past samples; before the
// run's start, its first value); a stroke channel takes its rate along
class SensorDelay : public Effect {
 public:
  SensorDelay() : Effect("sensor_delay", "a transport delay on one sensor channel") {
    channel_ = add_option({"channel", "f_lift", channel_names(), "the sensor channel (timeseries.csv column)"});
    delay_ = add_parameter({"delay", 0.1, 0.0, 1.0, "s", "how late the channel reports"});
  }
  void changed() override {
    field_ = channel_info(option_value(channel_)).field;
    rate_ = rate_of(option_value(channel_));
  }
  void reset(const WheelLoader& loader) override {
    (void)loader;
    past_.clear();
  }
  void on_sensors(const EffectContext& c, SensorSample& s) override {
    (void)c;
    past_.push_back({s.t, s.*field_, rate_ ? s.*rate_ : 0.0});
    const double when = s.t - value(delay_);
    // the ring: keep one sample at or before `when`
    while (past_.size() > 1 && past_[1].t <= when) past_.pop_front();
    const Past& a = past_.front();
    double value_then = a.value, rate_then = a.rate;
    if (past_.size() > 1 && when > a.t) {
      const Past& b = past_[1];
      const double f = (when - a.t) / (b.t - a.t);
      value_then = a.value + f * (b.value - a.value);
      rate_then = a.rate + f * (b.rate - a.rate);
    }
    s.*field_ = value_then;
    if (rate_) s.*rate_ = rate_then;
  }
  void save_state(ByteWriter& w) const override {
    w.u64(past_.size());
    for (const Past& p : past_) {
      w.f64(p.t);
      w.f64(p.value);
      w.f64(p.rate);
    }
  }
  void restore_state(ByteReader& r) override {
    const std::uint64_t n = r.u64("sensor delay");
    r.need_elements(n, 3 * 8, "sensor delay");
    past_.clear();
    for (std::uint64_t k = 0; k < n; ++k) {
      Past p{};
      p.t = r.f64("sensor delay");
      p.value = r.f64("sensor delay");
      p.rate = r.f64("sensor delay");
      past_.push_back(p);
    }
  }

 private:
  struct Past {
    double t, value, rate;
  };
  int channel_ = 0, delay_ = 0;
  double SensorSample::*field_ = &SensorSample::f_lift;
  double SensorSample::*rate_ = nullptr;
  std::deque<Past> past_;
};

// --- soil_cohesion --------------------------------------------------------------------------
// moist or cohesive gravel: touching particles hold tension (kernels/solver.cl, Rumpf's law in
// solvers/particles.hpp), so the soil resists the bucket more, breaks out in lumps and holds
// steeper faces. Acts from the start of the run on the settled pile (whose shape the scan gives)
class SoilCohesion : public Effect {
 public:
  SoilCohesion() : Effect("soil_cohesion", "cohesion of moist soil: particle contacts hold tension") {
    cohesion_ = add_parameter({"cohesion", 2e3, 0.0, 20e3, "Pa",
                               "bulk tensile strength of the soil (moist gravel: about 1-10 kPa of apparent cohesion)"});
  }
  void on_soil(SoilProperties& soil) override { soil.cohesion += value(cohesion_); }
  bool soil_only() const override { return true; }

 private:
  int cohesion_ = 0;
};

using Factory = std::unique_ptr<Effect> (*)();

template <class E>
std::unique_ptr<Effect> make() {
  return std::make_unique<E>();
}

// the built-ins, in the order of docs/effects.md
constexpr std::array<std::pair<const char*, Factory>, 9> kBuiltins = {{
    {"engine_power_sharing", &make<EnginePowerSharing>},
    {"hydraulic_lag", &make<HydraulicLag>},
    {"pump_flow_limit", &make<PumpFlowLimit>},
    {"cylinder_friction", &make<CylinderFriction>},
    {"wheel_slip_sensor", &make<WheelSlipSensor>},
    {"tyre_rolling_resistance", &make<TyreRollingResistance>},
    {"sensor_bias", &make<SensorBias>},
    {"sensor_delay", &make<SensorDelay>},
    {"soil_cohesion", &make<SoilCohesion>},
}};

}  // namespace

std::vector<std::string> builtin_effect_names() {
  std::vector<std::string> names;
  for (const auto& [name, factory] : kBuiltins) names.emplace_back(name);
  return names;
}

std::unique_ptr<Effect> make_builtin_effect(const std::string& name) {
  for (const auto& [n, factory] : kBuiltins)
    if (name == n) return factory();
  std::string list;
  for (const auto& n : builtin_effect_names()) list += (list.empty() ? "" : ", ") + n;
  throw InputError("no built-in effect named '" + name + "'; the built-in effects are " + list +
                   "; load others with --effect-plugin");
}

}  // namespace talus::vehicle
