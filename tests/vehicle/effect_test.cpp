// Effects (model extensions, issue 6): each built-in effect's signature measured on the machine
// alone on flat ground (h = 5 ms, no particles), parameter errors, the effect set's bookkeeping,
// and the example plug-in through dlopen.
#include "vehicle/effect.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <iostream>

#include "host/error.hpp"
#include "vehicle/data_file.hpp"
#include "vehicle/effect_plugin.hpp"

namespace talus::vehicle {
namespace {

constexpr double kH = 0.005;  // s, the vehicle scenarios' timestep
constexpr double kG = 9.81;   // m/s^2

std::string machine() { return find_data_file("wa320", "machines"); }

// what the message of a thrown exception contains
template <class E, class F>
std::string message_of(F&& f) {
  try {
    f();
  } catch (const E& e) {
    return e.what();
  }
  ADD_FAILURE() << "no exception";
  return "";
}

// a machine that has settled on its tyres for 0.5 s with the controls at rest
std::unique_ptr<WheelLoader> settled(double payload = 0.0) {
  auto w = std::make_unique<WheelLoader>(machine(), payload);
  for (int k = 0; k < 100; ++k) w->step(kH);
  return w;
}

struct Trace {
  std::vector<SensorSample> reported, truth;  // one per step, from t = h
};

using Commands = std::function<ActuatorCommands(double)>;

// `steps` steps of the machine with the effects (reset first), the commands a function of time
Trace run(WheelLoader& w, EffectSet& effects, const Commands& commands, int steps) {
  Trace trace;
  effects.reset(w, 0.0);
  for (int k = 0; k < steps; ++k) {
    const double t = k * kH;
    trace.reported.push_back(step_with_effects(w, effects, t, kH, commands(t)));
    trace.truth.push_back(effects.previous());
  }
  return trace;
}

// the run with one effect given by its specification, and the same run without effects
std::pair<Trace, Trace> with_and_without(const std::string& spec, const Commands& commands, int steps,
                                         double payload = 0.0) {
  EffectSet none, one;
  one.add(make_effect(spec));
  auto a = settled(payload), b = settled(payload);
  return {run(*a, one, commands, steps), run(*b, none, commands, steps)};
}

// --- parameters, names, the registry ---------------------------------------------------------

TEST(EffectTest, ParameterErrorsNameTheEffectTheParameterAndItsRange) {
  auto lag = make_builtin_effect("hydraulic_lag");
  const std::string range = message_of<InputError>([&] { lag->set("time_constant", 5.0); });
  EXPECT_NE(range.find("hydraulic_lag"), std::string::npos) << range;
  EXPECT_NE(range.find("'time_constant'"), std::string::npos) << range;
  EXPECT_NE(range.find("[0, 2] s"), std::string::npos) << range;
  const std::string unknown = message_of<InputError>([&] { lag->set("tau", 0.1); });
  EXPECT_NE(unknown.find("no parameter 'tau'"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("time_constant"), std::string::npos) << unknown;  // lists what it accepts
  EXPECT_THROW(lag->set("time_constant", std::nan("")), InputError);
  lag->set("time_constant", 0.5);
  EXPECT_DOUBLE_EQ(lag->get("time_constant"), 0.5);

  // from a specification: options first (the channel fixes the bias's unit and range), then numbers
  auto bias = make_effect("sensor_bias:bias=0.2,channel=v_drive");
  EXPECT_EQ(bias->option("channel"), "v_drive");
  EXPECT_DOUBLE_EQ(bias->get("bias"), 0.2);
  const std::string speed = message_of<InputError>([] { make_effect("sensor_bias:channel=v_drive,bias=1000"); });
  EXPECT_NE(speed.find("'bias'"), std::string::npos) << speed;
  EXPECT_NE(speed.find("m/s"), std::string::npos) << speed;
  const std::string channel = message_of<InputError>([] { make_effect("sensor_delay:channel=f_lyft"); });
  EXPECT_NE(channel.find("f_lyft"), std::string::npos) << channel;
  EXPECT_NE(channel.find("f_lift"), std::string::npos) << channel;  // the choices
  EXPECT_THROW(make_effect("hydraulic_lag:time_constant"), InputError);
  EXPECT_THROW(make_effect("hydraulic_lag:time_constant=fast"), InputError);
  EXPECT_EQ(make_effect("pump_flow_limit:max_flow=4e-3")->to_json().dump(),
            R"({"name":"pump_flow_limit","params":{"max_flow":0.004}})");
}

TEST(EffectTest, RegistryListsTheBuiltIns) {
  const auto names = builtin_effect_names();
  EXPECT_EQ(names.size(), 9u);
  for (const auto& n : names) EXPECT_EQ(make_builtin_effect(n)->name(), n);
  const std::string unknown = message_of<InputError>([] { make_builtin_effect("rain"); });
  for (const auto& n : names) EXPECT_NE(unknown.find(n), std::string::npos) << unknown;
}

// soil cohesion acts on the particles alone: it sets the soil, and the machine alone never sees it
TEST(EffectTest, SoilCohesionSetsTheSoilAndNothingElse) {
  EffectSet set;
  set.add(make_effect("soil_cohesion:cohesion=5000"));
  EXPECT_DOUBLE_EQ(set.soil().cohesion, 5000.0);
  EXPECT_TRUE(set[0].soil_only());
  EXPECT_FALSE(make_effect("hydraulic_lag")->soil_only());
  EXPECT_DOUBLE_EQ(EffectSet().soil().cohesion, 0.0);  // the baseline gravel is dry
  EXPECT_THROW(make_effect("soil_cohesion:cohesion=-1"), InputError);
}

// an empty effect set changes nothing: the same run to the last bit
TEST(EffectTest, EmptySetLeavesTheRunUntouched) {
  auto a = settled(), b = settled();
  EffectSet none;
  none.reset(*a, 0.0);
  for (int k = 0; k < 200; ++k) {
    const ActuatorCommands u{1.0, 0.1, 0.05};
    step_with_effects(*a, none, k * kH, kH, u);
    b->set_drive_speed(u.drive);
    b->set_lift_speed(u.lift);
    b->set_tilt_speed(u.tilt);
    b->step(kH);
  }
  for (size_t i = 0; i < a->bodies().size(); ++i) EXPECT_EQ(a->bodies()[i].position, b->bodies()[i].position);
}

// --- the built-in effects' signatures --------------------------------------------------------

// the paper's diagnosis: lifting at full speed while accelerating, the driveline gets what the
// hydraulics leave, so the machine is slower; drive power + hydraulic power / η <= 127 kW
TEST(EffectTest, EnginePowerSharingSlowsTheDriveWhileLifting) {
  const double eta = 0.8;
  EffectSet none, sharing;
  sharing.add(make_effect("engine_power_sharing:efficiency=0.8"));
  auto a = settled(3500.0), b = settled(3500.0);
  // full drive and full lift, the lift ramped in over 0.2 s as the scenarios do
  const Commands full = [](double t) { return ActuatorCommands{3.61, 0.218 * std::min(1.0, t / 0.2), 0.0}; };
  // the engine's own power each step, and the budget the effect kept
  double worst_budget = 0.0, worst_now = 0.0, hydraulic_peak = 0.0, worst_limit = 0.0;
  double v_with = 0.0, v_without = 0.0;
  sharing.reset(*a, 0.0);
  none.reset(*b, 0.0);
  const int steps = 400;  // 2 s: the boom travels 0.44 m of its 1.2 m stroke
  for (int k = 0; k < steps; ++k) {
    const double t = k * kH;
    const SensorSample before = sharing.previous();
    step_with_effects(*a, sharing, t, kH, full(t));
    step_with_effects(*b, none, t, kH, full(t));
    const double drive = a->driveline().motor_torque() * a->driveline().motor_speed(a->bodies());
    auto hydraulic = [](const SensorSample& s) {
      return std::max(0.0, s.f_lift * s.lift_rate) + std::max(0.0, s.f_tilt * s.tilt_rate);
    };
    // the rule itself: drive <= max(floor, P_max - P_hyd / η), floor 10 % of P_max
    const double allowed = std::max(0.1 * 127e3, 127e3 - hydraulic(before) / eta);
    worst_limit = std::max(worst_limit, drive - allowed);
    worst_budget = std::max(worst_budget, drive + hydraulic(before) / eta);
    worst_now = std::max(worst_now, drive + hydraulic(sharing.previous()) / eta);
    hydraulic_peak = std::max(hydraulic_peak, hydraulic(sharing.previous()));
    if (k == 199) {
      v_with = a->driveline().drive_speed(a->bodies());
      v_without = b->driveline().drive_speed(b->bodies());
    }
  }
  std::cout << "[ measured ] lifting at 0.218 m/s with 3.5 t: hydraulic power up to " << hydraulic_peak / 1e3
            << " kW; speed after 1 s " << v_with << " m/s shared vs " << v_without
            << " m/s alone; drive + hydraulic/eta at most " << worst_budget / 1e3 << " kW (previous sample), "
            << worst_now / 1e3 << " kW (same step)\n";
  EXPECT_LE(worst_limit, 1e-9 * 127e3);
  EXPECT_GT(hydraulic_peak, 20e3);
  EXPECT_LT(v_with, v_without - 0.1);
  EXPECT_LE(worst_budget, 127e3 * (1 + 1e-9));
  EXPECT_LE(worst_now, 127e3 * 1.02);
}

// the cylinders follow a step command with lag τ: the stroke runs τ behind
TEST(EffectTest, HydraulicLagDelaysTheLiftByTheTimeConstant) {
  const double tau = 0.3;
  const Commands lift = [](double t) { return ActuatorCommands{0.0, t >= 0.1 ? 0.1 : 0.0, 0.0}; };
  const auto [lagged, baseline] = with_and_without("hydraulic_lag:time_constant=0.3", lift, 400);
  // when each stroke has grown by 0.1 m
  auto crossing = [](const Trace& tr) {
    const double d0 = tr.truth.front().d_lift;
    for (size_t k = 1; k < tr.truth.size(); ++k) {
      const double a = tr.truth[k - 1].d_lift - d0 - 0.1, b = tr.truth[k].d_lift - d0 - 0.1;
      if (a < 0 && b >= 0) return tr.truth[k - 1].t + kH * (-a) / (b - a);
    }
    return -1.0;
  };
  const double shift = crossing(lagged) - crossing(baseline);
  std::cout << "[ measured ] lift lag " << shift << " s for a time constant of " << tau << " s\n";
  EXPECT_NEAR(shift, tau, 0.05 * tau);
}

// one pump for lift and tilt: the total flow stays at the limit, both commands scaled alike
TEST(EffectTest, PumpFlowLimitCapsTheTotalFlow) {
  const double q_max = 4e-3;
  const Commands both = [](double) { return ActuatorCommands{0.0, 0.218, 0.25}; };
  const auto [limited, baseline] = with_and_without("pump_flow_limit:max_flow=4e-3", both, 200);
  auto w = settled();
  const double ap_l = w->lift_spec().piston_area, ap_t = w->tilt_spec().piston_area;
  auto flow = [&](const SensorSample& s) { return 2 * ap_l * std::abs(s.lift_rate) + ap_t * std::abs(s.tilt_rate); };
  double worst = 0.0, free_flow = 0.0;
  for (size_t k = 20; k < limited.truth.size(); ++k) {  // after the first 0.1 s
    worst = std::max(worst, flow(limited.truth[k]));
    free_flow = std::max(free_flow, flow(baseline.truth[k]));
  }
  const SensorSample& s = limited.truth[100];
  std::cout << "[ measured ] total flow at most " << worst * 1e3 << " L/s with a " << q_max * 1e3
            << " L/s limit (" << free_flow * 1e3 << " L/s without); lift/tilt rates " << s.lift_rate << " / "
            << s.tilt_rate << " m/s\n";
  EXPECT_GT(free_flow, 2 * q_max);
  EXPECT_LE(worst, q_max * 1.01);
  EXPECT_GT(worst, q_max * 0.97);
  EXPECT_NEAR(s.lift_rate / s.tilt_rate, 0.218 / 0.25, 0.02);
}

// Coulomb friction: the force sensors read 2 F_c (lift) and F_c (tilt) more while moving, the
// motion is unchanged while the motors are not at their limits, and the limits lose F_c
TEST(EffectTest, CylinderFrictionShowsInTheForceSensorsAndTheLimits) {
  const Commands lift = [](double t) { return ActuatorCommands{0.0, 0.15, t < 0.5 ? 0.1 : 0.0}; };
  const auto [friction, baseline] = with_and_without("cylinder_friction:force=8000", lift, 200, 2000.0);
  const SensorSample& r = friction.reported[80];  // t = 0.4 s: both cylinders moving
  const SensorSample& t = friction.truth[80];
  std::cout << "[ measured ] lift force read " << r.f_lift << " N vs motor " << t.f_lift << " N, tilt " << r.f_tilt
            << " vs " << t.f_tilt << " N\n";
  EXPECT_NEAR(r.f_lift - t.f_lift, 16000.0, 1.0);
  EXPECT_NEAR(r.f_tilt - t.f_tilt, 8000.0, 1.0);
  EXPECT_NEAR(t.d_lift, baseline.truth[80].d_lift, 1e-6);
  EXPECT_EQ(friction.reported[150].f_tilt, friction.truth[150].f_tilt);  // tilt held: no friction read
  // the motor's range after before_step: lift extends (loses F_c on the push side)
  auto w = settled();
  EffectSet set;
  set.add(make_effect("cylinder_friction:force=8000"));
  set.reset(*w, 0.0);
  w->set_lift_speed(0.1);
  w->set_tilt_speed(-0.1);
  set.before_step(0.0, kH, *w);
  EXPECT_DOUBLE_EQ(w->lift_cylinders()[0]->motor.force_max, w->lift_spec().force_push - 8000.0);
  EXPECT_DOUBLE_EQ(w->lift_cylinders()[1]->motor.force_min, -w->lift_spec().force_pull - 8000.0);
  EXPECT_DOUBLE_EQ(w->tilt_cylinder().motor.force_min, -w->tilt_spec().force_pull + 8000.0);
  // the next step starts again from the machine's own limits
  w->set_lift_speed(0.0);
  w->set_tilt_speed(0.0);
  set.before_step(kH, kH, *w);
  EXPECT_DOUBLE_EQ(w->lift_cylinders()[0]->motor.force_max, w->lift_spec().force_push);
}

// the wheel-revolution speed over-reads by k f_tr / F_max under traction
TEST(EffectTest, WheelSlipSensorOverReadsInProportionToTraction) {
  const Commands drive = [](double) { return ActuatorCommands{3.0, 0.0, 0.0}; };
  const auto [slip, baseline] = with_and_without("wheel_slip_sensor:slip_at_limit=0.2", drive, 400);
  auto w = settled();
  double peak_traction = 0.0, worst = 0.0;
  for (size_t k = 0; k < slip.truth.size(); ++k) {
    const SensorSample& t = slip.truth[k];
    if (std::abs(t.v_drive) < 0.05) continue;
    const double over = (slip.reported[k].v_drive - t.v_drive) / std::abs(t.v_drive);
    worst = std::max(worst, std::abs(over - 0.2 * t.f_traction / w->traction_limit()));
    peak_traction = std::max(peak_traction, t.f_traction);
    // power follows the reading
    EXPECT_NEAR(slip.reported[k].power, t.power + (slip.reported[k].v_drive - t.v_drive) * t.f_traction, 1e-6 * 1e5);
  }
  // the machine itself moves as without the effect (a sensor effect)
  EXPECT_EQ(slip.truth.back().x_vehicle, baseline.truth.back().x_vehicle);
  const size_t k = 60;  // 0.3 s: accelerating at full traction
  std::cout << "[ measured ] at " << slip.truth[k].f_traction / 1e3 << " kN traction the speed reads "
            << slip.reported[k].v_drive << " m/s for " << slip.truth[k].v_drive << " m/s\n";
  EXPECT_GT(peak_traction, 0.5 * w->traction_limit());
  EXPECT_LT(worst, 1e-12);
  EXPECT_GT(slip.reported[k].v_drive, slip.truth[k].v_drive * 1.05);
  // it declares the channels it changes (the diagnosis's signature), and changes no other but power
  const auto declared = make_builtin_effect("wheel_slip_sensor")->sensor_channels();
  ASSERT_EQ(declared, std::vector<Channel>{Channel::v_drive});
  for (size_t k2 = 0; k2 < slip.truth.size(); ++k2)
    for (size_t c = 0; c < kChannelCount; ++c) {
      const auto ch = static_cast<Channel>(c);
      if (ch == Channel::v_drive || ch == Channel::power) continue;
      EXPECT_EQ(slip.reported[k2].*kSensorChannels[c].field, slip.truth[k2].*kSensorChannels[c].field) << kChannelNames[c];
    }
  // the machine effects and the soil's declare none: they act on every channel
  for (const char* name : {"engine_power_sharing", "hydraulic_lag", "pump_flow_limit", "cylinder_friction",
                           "tyre_rolling_resistance", "soil_cohesion"})
    EXPECT_TRUE(make_builtin_effect(name)->sensor_channels().empty()) << name;
}

// rolling resistance: coasting (engine power cut) decelerates by c_rr g m / m_eff more, where
// m_eff adds the wheels' spin inertia I / r^2
TEST(EffectTest, TyreRollingResistanceShortensCoasting) {
  const double crr = 0.03, coast = 2.0;  // s
  auto coast_distance = [&](const std::string& spec) {
    // the bucket raised clear of the ground (settled, it rests on its heel and would drag)
    auto w = settled();
    w->set_lift_speed(0.15);
    for (int k = 0; k < 100; ++k) w->step(kH);
    w->set_lift_speed(0.0);
    w->set_drive_speed(2.0);
    for (int k = 0; k < 600; ++k) w->step(kH);  // 3 s: up to speed
    // the engine delivers nothing from here on (a tiny limit keeps the driveline valid) [W]
    w->set_drive_power_limit(1e-3);
    EffectSet set;
    if (!spec.empty()) set.add(make_effect(spec));
    const double x0 = read_sensors(*w, 0.0).x_vehicle, v0 = read_sensors(*w, 0.0).v_drive;
    const Trace tr = run(*w, set, [](double) { return ActuatorCommands{2.0, 0.0, 0.0}; },
                         static_cast<int>(std::lround(coast / kH)));
    EXPECT_GT(w->bucket_ground().clearance(), 0.01);
    return std::make_pair(tr.truth.back().x_vehicle - x0, v0);
  };
  const auto [with, v0] = coast_distance("tyre_rolling_resistance:coefficient=0.03");
  const auto [without, v0b] = coast_distance("");
  auto w = settled();
  double spin = 0.0;
  for (const auto* t : w->tyres()) spin += w->bodies()[t->wheel()].inertia(1, 1) / std::pow(0.695, 2);
  const double m = w->operating_mass();
  const double expected = 0.5 * crr * kG * m / (m + spin) * coast * coast;
  std::cout << "[ measured ] coasting " << coast << " s from " << v0 << " m/s: " << without << " m free, " << with
            << " m with c_rr = " << crr << "; shorter by " << without - with << " m, expected " << expected << " m\n";
  EXPECT_NEAR(v0, v0b, 1e-12);
  EXPECT_NEAR(without - with, expected, 0.03 * expected);
}

// a bias shifts exactly its channel (and power, derived from it)
TEST(EffectTest, SensorBiasShiftsExactlyThatChannel) {
  const Commands lift = [](double) { return ActuatorCommands{0.5, 0.1, 0.0}; };
  const auto [biased, baseline] = with_and_without("sensor_bias:channel=f_lift,bias=1000", lift, 100);
  for (size_t k = 0; k < biased.truth.size(); ++k) {
    const SensorSample& r = biased.reported[k];
    const SensorSample& t = biased.truth[k];
    ASSERT_DOUBLE_EQ(r.f_lift, t.f_lift + 1000.0);
    ASSERT_DOUBLE_EQ(r.power, t.power + 1000.0 * t.lift_rate);
    for (double SensorSample::*f : {&SensorSample::f_tilt, &SensorSample::f_traction, &SensorSample::v_drive,
                                    &SensorSample::d_lift, &SensorSample::d_tilt, &SensorSample::boom_deg,
                                    &SensorSample::bucket_deg, &SensorSample::pitch_deg, &SensorSample::x_vehicle,
                                    &SensorSample::bucket_tip_x, &SensorSample::bucket_tip_z})
      ASSERT_EQ(r.*f, t.*f);
    ASSERT_EQ(t.d_lift, baseline.truth[k].d_lift);  // the machine is untouched
  }
  // a bias on power itself stays on power
  const auto [power, unused] = with_and_without("sensor_bias:channel=power,bias=-5000", lift, 20);
  EXPECT_DOUBLE_EQ(power.reported.back().power, power.truth.back().power - 5000.0);
}

// a delay reports the channel as it was `delay` ago: the stroke and its rate
TEST(EffectTest, SensorDelayShiftsTheChannelByTheDelay) {
  const Commands lift = [](double t) { return ActuatorCommands{0.0, t < 0.3 ? 0.05 : 0.15, 0.0}; };
  const auto [delayed, baseline] = with_and_without("sensor_delay:channel=d_lift,delay=0.2", lift, 300);
  const int lag = 40;  // 0.2 s in steps
  double worst = 0.0;
  for (size_t k = lag; k < delayed.truth.size(); ++k) {
    worst = std::max(worst, std::abs(delayed.reported[k].d_lift - delayed.truth[k - lag].d_lift));
    ASSERT_NEAR(delayed.reported[k].lift_rate, delayed.truth[k - lag].lift_rate, 1e-12);
    ASSERT_EQ(delayed.reported[k].f_lift, delayed.truth[k].f_lift);
  }
  // before the delay has passed: the first value (the effect set's reset sample)
  EXPECT_NEAR(delayed.reported[10].d_lift, delayed.truth.front().d_lift, 1e-4);
  std::cout << "[ measured ] delayed stroke vs the stroke 0.2 s earlier: at most " << worst << " m apart\n";
  EXPECT_LT(worst, 1e-12);
}

// effects apply in order; a wrench on the bucket is refused (the particle coupling owns it)
TEST(EffectTest, SetAppliesInOrderAndRefusesBucketWrenches) {
  EffectSet set;
  set.add(make_effect("pump_flow_limit:max_flow=2e-3"));
  set.add(make_effect("hydraulic_lag:time_constant=0"));
  auto w = settled();
  set.reset(*w, 0.0);
  const ActuatorCommands u = set.commands(0.0, kH, {1.0, 0.2, 0.2});
  const double q = 2 * w->lift_spec().piston_area * u.lift + w->tilt_spec().piston_area * u.tilt;
  EXPECT_NEAR(q, 2e-3, 1e-12);
  EXPECT_DOUBLE_EQ(u.drive, 1.0);
  EXPECT_EQ(set.to_json().size(), 2u);
  StepControls controls(*w);
  EXPECT_THROW(controls.add_wrench(w->bucket_body(), Vec6::Ones()), Error);
  EXPECT_THROW(controls.set_lift_force_range(1.0, -1.0), Error);
}

// an effect that records, per hook, whether its context said the run was digging
class PhaseProbe : public Effect {
 public:
  PhaseProbe() : Effect("phase_probe", "records EffectContext::digging") {}
  void on_commands(const EffectContext& c, ActuatorCommands&) override {
    commands.emplace_back(c.t, c.digging);
  }
  void on_sensors(const EffectContext& c, SensorSample&) override {
    sensors.emplace_back(c.t, c.digging);
  }
  std::vector<std::pair<double, bool>> commands, sensors;
};

TEST(EffectTest, TheContextSaysWhetherTheRunIsInTheScenariosDiggingPhase) {
  // a scenario with a digging phase between steps [0.0525, 0.1025) s and one on steps [10 h, 20 h)
  // (the start in, the end out): every hook inside it reads digging, none outside; without marks
  // (dig_end <= dig_start) nothing is digging
  for (const auto& [dig_start, dig_end] : std::vector<std::pair<double, double>>{
           {0.0525, 0.1025}, {10 * kH, 20 * kH}, {0.0525, 0.0}}) {
    Scenario sc;
    sc.dig_start = dig_start;
    sc.dig_end = dig_end;
    EffectSet set;
    auto probe = std::make_unique<PhaseProbe>();
    PhaseProbe& p = *probe;
    set.add(std::move(probe));
    auto w = settled();
    SensorLog log(100.0);
    start_with_effects(*w, set, log, sc);
    for (int k = 0; k < 40; ++k) step_with_effects(*w, set, k * kH, kH, {});
    ASSERT_EQ(p.commands.size(), 40u);
    ASSERT_EQ(p.sensors.size(), 41u);  // the first sample at t = 0 too
    for (const auto& samples : {p.commands, p.sensors})
      for (const auto& [t, digging] : samples)
        EXPECT_EQ(digging, t >= sc.dig_start && t < dig_end) << "t " << t;
  }
  EffectSet set;
  EXPECT_THROW(set.set_dig_phase(0.0, std::nan("")), Error);
}

// --- plug-ins --------------------------------------------------------------------------------

TEST(EffectPluginTest, ExamplePluginLoadsAndActs) {
  const auto plugins = load_effect_plugins({TALUS_EXAMPLE_EFFECT_PLUGIN});
  ASSERT_EQ(plugins.size(), 1u);
  EXPECT_EQ(plugins[0]->effect_names(), std::vector<std::string>{"flow_relief"});
  auto relief = make_effect("flow_relief:speed=0.05,droop=4", plugins);
  EXPECT_DOUBLE_EQ(relief->get("speed"), 0.05);
  EXPECT_EQ(relief->to_json()["plugin"], TALUS_EXAMPLE_EFFECT_PLUGIN);
  const std::string range = message_of<InputError>([&] { relief->set("droop", 50.0); });
  EXPECT_NE(range.find("'droop'"), std::string::npos) << range;
  // lifting at 0.15 m/s = 3 v0: the force limits fall to 1 / (1 + 4 (3 - 1)) of the machine's
  auto w = settled();
  EffectSet set;
  set.add(std::move(relief));
  const Trace tr = run(*w, set, [](double) { return ActuatorCommands{0.0, 0.15, 0.0}; }, 100);
  const double rate = tr.truth[tr.truth.size() - 2].lift_rate;  // the sample the last step used
  const double factor = 1.0 / (1.0 + 4.0 * (std::abs(rate) / 0.05 - 1.0));
  std::cout << "[ measured ] flow_relief at " << rate << " m/s: lift force limit "
            << w->lift_cylinders()[0]->motor.force_max / 1e3 << " kN of " << w->lift_spec().force_push / 1e3 << " kN\n";
  EXPECT_NEAR(w->lift_cylinders()[0]->motor.force_max, factor * w->lift_spec().force_push, 1e-6);
  EXPECT_NEAR(factor, 1.0 / 9.0, 0.01);
  // a plug-in effect may not take a built-in's name (nor a second plug-in's)
  EXPECT_THROW(load_effect_plugins({TALUS_EXAMPLE_EFFECT_PLUGIN, TALUS_EXAMPLE_EFFECT_PLUGIN}), InputError);
}

// a plug-in effect that reaches the soil (since ABI version 2): cohesion = its parameter
struct SoilPluginEffect {
  double cohesion = 0.0;
};
const talus_effect_parameter kMoisture[] = {
    {"cohesion", 0.0, 0.0, 2e4, "Pa", "the soil's bulk tensile strength"}};
const talus_effect_type kMoistureType[] = {
    {"moisture", "a wet gravel: cohesion", 1, kMoisture,
     [] { return static_cast<void*>(new SoilPluginEffect); },
     [](void* self) { delete static_cast<SoilPluginEffect*>(self); },
     [](void* self, int, double v) { static_cast<SoilPluginEffect*>(self)->cohesion = v; }, nullptr,
     nullptr, nullptr, nullptr,
     [](void* self, talus_soil_properties* soil) {
       soil->cohesion += static_cast<SoilPluginEffect*>(self)->cohesion;
     }}};
const talus_effect_plugin_info kMoistureInfo = {TALUS_EFFECT_ABI_VERSION, "soil test", 1,
                                                kMoistureType};

// a plug-in effect that commands the lift at 1 m/s inside the digging phase and 0 outside (ABI
// version 3: the context's digging)
const talus_effect_type kPhaseGateType[] = {
    {"phase_gate", "the lift moves in the dig only", 0, nullptr,
     [] { return static_cast<void*>(new int); }, [](void* self) { delete static_cast<int*>(self); },
     nullptr, nullptr,
     [](void*, const talus_effect_context* c, talus_commands* u) {
       u->lift = c->digging ? 1.0 : 0.0;
     },
     nullptr, nullptr, nullptr}};
const talus_effect_plugin_info kPhaseGateInfo = {TALUS_EFFECT_ABI_VERSION, "phase test", 1,
                                                 kPhaseGateType};

TEST(EffectPluginTest, PluginsReadTheDiggingPhaseFromTheirContext) {
  const EffectPlugins plugins = {EffectPlugin::from_info(&kPhaseGateInfo, "in-memory")};
  EffectSet set;
  set.add(make_effect("phase_gate", plugins));
  auto w = settled();
  set.reset(*w, 0.0);
  set.set_dig_phase(0.0525, 0.1025);
  for (int k = 0; k < 40; ++k) {
    const double t = k * kH;
    const ActuatorCommands u = set.commands(t, kH, {0.0, 0.5, 0.0});
    EXPECT_EQ(u.lift, t >= 0.0525 && t < 0.1025 ? 1.0 : 0.0) << "t " << t;
  }
}

TEST(EffectPluginTest, PluginsReachTheSoilThroughOnSoil) {
  const EffectPlugins plugins = {EffectPlugin::from_info(&kMoistureInfo, "in-memory")};
  EffectSet set;
  set.add(make_effect("moisture:cohesion=5000", plugins));
  EXPECT_DOUBLE_EQ(set.soil().cohesion, 5000.0);
  // with on_soil alone it acts on the soil only (the diagnosis tries it on pile runs only)
  EXPECT_TRUE(set[0].soil_only());
  EXPECT_FALSE(
      make_effect("flow_relief", load_effect_plugins({TALUS_EXAMPLE_EFFECT_PLUGIN}))->soil_only());
}

TEST(EffectPluginTest, WrongAbiVersionAndMissingFilesAreRejectedNamingTheFile) {
  static const talus_effect_plugin_info stale = {999u, "stale", 0, nullptr};
  const std::string version = message_of<InputError>([] { EffectPlugin::from_info(&stale, "stale.so"); });
  EXPECT_NE(version.find("stale.so"), std::string::npos) << version;
  EXPECT_NE(version.find("ABI version 999"), std::string::npos) << version;
  EXPECT_NE(version.find("version 3"), std::string::npos) << version;
  const std::string missing = message_of<InputError>([] { EffectPlugin::load("/nonexistent/libnothing.so"); });
  EXPECT_NE(missing.find("/nonexistent/libnothing.so"), std::string::npos) << missing;
  // a plug-in whose effect's default lies outside its own range
  static const talus_effect_parameter bad_parameter[] = {{"gain", 5.0, 0.0, 1.0, "1", "a gain"}};
  static const talus_effect_type bad_type[] = {
      {"bad", "a bad effect", 1, bad_parameter, [] { return static_cast<void*>(nullptr); },
       [](void*) {}, [](void*, int, double) {}, nullptr, nullptr, nullptr, nullptr, nullptr}};
  static const talus_effect_plugin_info bad = {TALUS_EFFECT_ABI_VERSION, "bad", 1, bad_type};
  const std::string defaults = message_of<InputError>([] { EffectPlugin::from_info(&bad, "bad.so"); });
  EXPECT_NE(defaults.find("'gain'"), std::string::npos) << defaults;
}

}  // namespace
}  // namespace talus::vehicle
