// Learned corrections (issue 17): the dictionaries, the two effects as the simulator runs them, and
// their specification round trip. The regression that fits them: tests/sim2real/discovery_test.cpp.
#include "vehicle/learned_correction.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <iostream>
#include <map>
#include <random>
#include <set>

#include "host/error.hpp"
#include "vehicle/data_file.hpp"
#include "vehicle/effect_plugin.hpp"

namespace talus::vehicle {
namespace {

constexpr double kH = 0.005;  // s, the vehicle scenarios' timestep

// a settled machine: on_commands needs one in its context
std::unique_ptr<WheelLoader> machine() {
  auto w = std::make_unique<WheelLoader>(find_data_file("wa320", "machines"), 0.0);
  for (int k = 0; k < 20; ++k) w->step(kH);
  return w;
}

TEST(LearnedCorrection, DictionariesHaveUniqueParameterNamesAndFiniteValues) {
  std::mt19937_64 rng(std::random_device{}());
  std::uniform_real_distribution<double> u(-1e5, 1e5);
  for (CorrectionKind kind :
       {CorrectionKind::actuator, CorrectionKind::sensor, CorrectionKind::traction}) {
    std::set<std::string> names;
    for (const auto& f : correction_features(kind)) {
      EXPECT_TRUE(names.insert(f.name).second) << f.name;
      for (const char* c = f.name; *c; ++c)
        EXPECT_TRUE(std::islower(*c) || std::isdigit(*c) || *c == '_') << f.name;
      CorrectionInputs x{u(rng), u(rng), u(rng), u(rng), u(rng), 1.0, {u(rng), u(rng), u(rng)}};
      EXPECT_TRUE(std::isfinite(f.value(x))) << f.name;
    }
  }
  // the actuator's own speed is not in its dictionary (the regression would learn a tautology)
  for (const auto& f : correction_features(CorrectionKind::actuator)) EXPECT_STRNE(f.name, "rate");
}

TEST(LearnedCorrection, ExpressionsAndUnitsUseTheTargetsSymbols) {
  const auto symbols = correction_symbols(CorrectionKind::actuator, "lift");
  const auto& features = correction_features(CorrectionKind::actuator);
  auto find = [&](const std::string& name) {
    return *std::find_if(features.begin(), features.end(),
                         [&](const auto& f) { return name == f.name; });
  };
  EXPECT_EQ(correction_expression(find("force_sign_command"), symbols), "f_lift·sign(u_lift)");
  EXPECT_EQ(correction_unit(find("abs_force_command"), symbols), "N·m/s");
  EXPECT_EQ(correction_expression(find("delay_02"), symbols), "u_lift(t−0.2 s) − u_lift");
  const auto sensor = correction_symbols(CorrectionKind::sensor, "f_traction");
  const auto& sf = correction_features(CorrectionKind::sensor);
  const auto gain = *std::find_if(sf.begin(), sf.end(), [](const auto& f) {
    return std::string(f.name) == "abs_force_reading";
  });
  EXPECT_EQ(correction_expression(gain, sensor), "|f_lift|·f_traction");
  EXPECT_EQ(correction_unit(gain, sensor), "N·N");
  EXPECT_THROW(correction_symbols(CorrectionKind::actuator, "boom"), Error);
}

TEST(LearnedCorrection, SpecificationRoundTripsAndReportsOnlyItsTerms) {
  auto e =
      make_effect("learned_actuator_correction:actuator=tilt,force_sign_command=-2e-7,one=0.01");
  EXPECT_EQ(e->name(), "learned_actuator_correction");
  const auto j = e->to_json();
  EXPECT_EQ(j["params"]["actuator"], "tilt");
  EXPECT_DOUBLE_EQ(j["params"]["force_sign_command"].get<double>(), -2e-7);
  EXPECT_DOUBLE_EQ(j["params"]["one"].get<double>(), 0.01);
  EXPECT_FALSE(j["params"].contains("delay_02"));  // zero: not a term
  // a coefficient's unit follows the actuator
  for (const auto& p : e->parameters()) {
    if (p.name == "force") {
      EXPECT_EQ(p.unit, "(m/s)/(N)");
    }
  }
  // bad input: an unknown feature, a value beyond the guard, an unknown channel
  EXPECT_THROW(make_effect("learned_actuator_correction:actuator=lift,viscosity=1"), InputError);
  EXPECT_THROW(make_effect("learned_actuator_correction:actuator=lift,one=1e9"), InputError);
  EXPECT_THROW(make_effect("learned_sensor_correction:channel=t,one=1"), InputError);
  // the learned names are not candidates of the search, but make_effect knows them
  const auto builtins = builtin_effect_names();
  for (const auto& n : learned_effect_names())
    EXPECT_EQ(std::find(builtins.begin(), builtins.end(), n), builtins.end()) << n;
}

TEST(LearnedCorrection, ActuatorCorrectionAddsItsSumToTheCommandWithDelaysOfThePastCommands) {
  // Δu = 0.5 (u(t − 0.2 s) − u) + 0.01 on the lift, for a ramp u = 0.1 t: Δu = 0.5 (−0.02) + 0.01 =
  // 0 once t ≥ 0.2 s, and before that the delay line holds the first command (the machine at rest)
  auto e = make_effect("learned_actuator_correction:actuator=lift,delay_02=0.5,one=0.01");
  auto w = machine();
  e->reset(*w);
  const SensorSample previous = read_sensors(*w, 0.0);
  for (int k = 0; k < 100; ++k) {
    const double t = k * kH;
    ActuatorCommands u{0.3, 0.1 * t, -0.05};
    const EffectContext c{t, kH, previous, *w};
    e->on_commands(c, u);
    const double delayed = 0.1 * std::max(0.0, t - 0.2);
    EXPECT_NEAR(u.lift, 0.1 * t + 0.5 * (delayed - 0.1 * t) + 0.01, 1e-12) << "t " << t;
    EXPECT_DOUBLE_EQ(u.drive, 0.3);  // the other actuators untouched
    EXPECT_DOUBLE_EQ(u.tilt, -0.05);
  }
}

TEST(LearnedCorrection, ActuatorCorrectionReadsTheForceThroughThePressureLag) {
  // c F_lagged with the lift force stepping from its settled value to F1: after n steps the lag
  // has moved a share 1 − exp(−n h / τ) of the way
  auto e = make_effect("learned_actuator_correction:actuator=lift,force=1e-7");
  auto w = machine();
  e->reset(*w);
  SensorSample s = read_sensors(*w, 0.0);
  const double f0 = s.f_lift, f1 = f0 + 1e5;
  {
    ActuatorCommands u{};
    e->on_commands(EffectContext{0.0, kH, s, *w}, u);
    EXPECT_NEAR(u.lift, 1e-7 * f0, 1e-15);  // the first step starts the lag at the reading
  }
  s.f_lift = f1;
  for (int n = 1; n <= 20; ++n) {
    ActuatorCommands u{};
    e->on_commands(EffectContext{n * kH, kH, s, *w}, u);
    const double lagged = f1 + (f0 - f1) * std::exp(-n * kH / kForceLag);
    EXPECT_NEAR(u.lift, 1e-7 * lagged, 1e-12) << n;
  }
}

TEST(LearnedCorrection, StrokeAndDiggingFeaturesReadTheCylindersStrokeAndTheContextsPhase) {
  // Δu_tilt = 0.3 d_tilt u_tilt + 0.02 [dig] − 0.1 [dig] u_tilt, with random strokes and commands,
  // inside and outside the digging phase; the lift's stroke must not enter the tilt's features
  std::mt19937_64 rng(std::random_device{}());
  std::uniform_real_distribution<double> stroke(0.0, 1.2), command(-0.2, 0.2);
  auto e = make_effect(
      "learned_actuator_correction:actuator=tilt,stroke_times=0.3,digging=0.02,"
      "digging_times=-0.1");
  auto w = machine();
  e->reset(*w);
  SensorSample s = read_sensors(*w, 0.0);
  for (int k = 0; k < 40; ++k) {
    s.d_tilt = stroke(rng);
    s.d_lift = stroke(rng);
    const bool digging = k % 3 == 0;
    const double u0 = command(rng);
    ActuatorCommands u{0.0, 0.0, u0};
    e->on_commands(EffectContext{k * kH, kH, s, *w, digging}, u);
    const double dig = digging ? 1.0 : 0.0;
    EXPECT_NEAR(u.tilt, u0 + 0.3 * s.d_tilt * u0 + 0.02 * dig - 0.1 * dig * u0, 1e-14) << k;
  }
  // the expressions name the tilt's stroke and the phase
  const auto symbols = correction_symbols(CorrectionKind::actuator, "tilt");
  const auto& features = correction_features(CorrectionKind::actuator);
  auto find = [&](const std::string& name) {
    const auto f = std::find_if(features.begin(), features.end(),
                                [&](const auto& g) { return name == g.name; });
    EXPECT_NE(f, features.end()) << name;
    return f;
  };
  if (const auto f = find("stroke_times"); f != features.end()) {
    EXPECT_EQ(correction_expression(*f, symbols), "d_tilt·u_tilt");
  }
  if (const auto f = find("digging_times"); f != features.end()) {
    EXPECT_EQ(correction_expression(*f, symbols), "[dig]·u_tilt");
  }
  // the drive's stroke is the boom's
  EXPECT_EQ(correction_symbols(CorrectionKind::actuator, "drive").stroke, "d_lift");
}

TEST(LearnedCorrection, SensorCorrectionReadsTheLiftStrokeAndThePhase) {
  // Δf_tilt = 1e-2 d_lift f_tilt + 500 [dig]
  auto e = make_effect("learned_sensor_correction:channel=f_tilt,stroke_times=1e-2,digging=500");
  auto w = machine();
  e->reset(*w);
  for (const bool digging : {false, true}) {
    SensorSample s = read_sensors(*w, 0.1);
    s.d_lift = 0.7;
    s.d_tilt = 0.2;
    s.f_tilt = 3e4;
    const SensorSample before = s;
    e->on_sensors(EffectContext{0.1, kH, before, *w, digging}, s);
    EXPECT_DOUBLE_EQ(s.f_tilt, 3e4 + 1e-2 * 0.7 * 3e4 + (digging ? 500.0 : 0.0));
  }
}

TEST(LearnedCorrection, TractionCorrectionIsAForceTheDriveMustOvercome) {
  // Δf = 3 kN sign(v) + 0.01 |f_lift| sign(v): at a steady speed, forward and backward, the
  // tractive force reading moves by Δf (the drive holds its speed against it), and the lift force
  // the machine reads is the load the second term scales with
  auto steady = [](const std::string& spec, double speed) {
    auto w = machine();
    // the bucket raised clear of the ground (settled, it rests on its heel and would drag)
    w->set_lift_speed(0.15);
    for (int k = 0; k < 100; ++k) w->step(kH);
    EffectSet set;
    if (!spec.empty()) set.add(make_effect(spec));
    set.reset(*w, 0.0);
    // 3 s to the speed, then the mean over 1 s
    double f_traction = 0.0, f_lift = 0.0;
    for (int k = 0; k < 800; ++k) {
      const SensorSample s = step_with_effects(*w, set, k * kH, kH, {speed, 0.0, 0.0});
      if (k >= 600) {
        f_traction += s.f_traction / 200.0;
        f_lift += s.f_lift / 200.0;
      }
    }
    return std::make_pair(f_traction, f_lift);
  };
  for (const double speed : {1.5, -1.5}) {
    const auto [with, load] =
        steady("learned_traction_correction:sign_speed=3000,abs_force_sign_speed=0.01", speed);
    const auto [without, load0] = steady("", speed);
    const double expected = (3000.0 + 0.01 * std::abs(load0)) * (speed > 0 ? 1.0 : -1.0);
    std::cout << "[ measured ] v " << speed << " m/s: f_traction " << without << " -> " << with
              << " N, moved " << with - without << " N, expected " << expected << " N\n";
    EXPECT_NEAR(with - without, expected, 0.01 * std::abs(expected)) << speed;
    EXPECT_NEAR(load, load0, 1e-3 * std::abs(load0));
  }
  // its coefficients are forces per feature unit
  auto e = make_effect("learned_traction_correction:speed=100");
  std::map<std::string, std::string> units;
  for (const auto& p : e->parameters()) units[p.name] = p.unit;
  EXPECT_EQ(units["speed"], "(N)/(m/s)");
  EXPECT_EQ(units["one"], "N");
  EXPECT_EQ(units["delay_01"], "(N)/(m/s)");
  EXPECT_THROW(correction_symbols(CorrectionKind::traction, "drive"), Error);
}

TEST(LearnedCorrection, SensorCorrectionChangesOnlyItsChannel) {
  // a load-dependent gain on f_tilt: x (1 + 2e-6 |f_lift|)
  auto e = make_effect("learned_sensor_correction:channel=f_tilt,abs_force_reading=2e-6");
  auto w = machine();
  e->reset(*w);
  SensorSample s = read_sensors(*w, 0.1);
  s.f_lift = -1.5e5;
  s.f_tilt = 3e4;
  const SensorSample before = s;
  e->on_sensors(EffectContext{0.1, kH, before, *w}, s);
  EXPECT_DOUBLE_EQ(s.f_tilt, 3e4 + 2e-6 * 1.5e5 * 3e4);
  EXPECT_DOUBLE_EQ(s.f_lift, before.f_lift);
  EXPECT_DOUBLE_EQ(s.f_traction, before.f_traction);
  ASSERT_EQ(e->sensor_channels().size(), 1u);
  EXPECT_EQ(e->sensor_channels()[0], Channel::f_tilt);
}

}  // namespace
}  // namespace talus::vehicle
