// Learned corrections (issue 17, docs/discovery.md): the generic effects that the sim-to-real
// loop's discovery fits when no candidate effect explains the residual. A learned correction adds
// a sparse sum of dictionary features to one quantity of the machine:
//   actuator  Δu = Σ c_k φ_k   added to the drive, lift or tilt target speed (on_commands), so the
//                              achieved speed moves by Δu while the actuator is not force-limited
//   sensor    Δx = Σ c_k φ_k   added to what one sensor channel reports (on_sensors)
//   traction  Δf = Σ c_k φ_k   a force [N] against the machine's motion the drive must overcome
//                              (on_step: −Δf along each tyre's heading, shared by the tyres), so
//                              the tractive force rises by Δf and, where the engine's power or the
//                              tyres' grip binds, the machine slows (a resistance, a mass the model
//                              lacks; the drive speed target cannot say which)
// Its parameters are the coefficients c_k of every feature of its dictionary (zero: not used), so
// a discovered correction is an ordinary effect: `--effect learned_actuator_correction:
// actuator=lift,force=-1.2e-7` runs it, to_json reports it, diagnose adds it like a candidate.
//
// One law: the dictionary below is evaluated by the effect at run time and by the discovery on
// measured data (sim2real/discovery), from the same CorrectionInputs, so a coefficient fitted on
// data means the same thing in the simulation.
#pragma once
#include <array>
#include <cmath>
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "vehicle/effect.hpp"

namespace talus::vehicle {

// the three kinds of learned correction, each with its own dictionary
enum class CorrectionKind { actuator, sensor, traction };

// the delays of the dictionary's delayed differences [s]: a tenth to about half a second, the
// span of hydraulic and sensor latencies (the built-in sensor_delay's range is 0–1 s)
inline constexpr std::array<double, 3> kCorrectionDelays = {0.1, 0.2, 0.4};

// an actuator correction reads the force and the power through a first-order lag of this time
// constant [s], the pressure dynamics of the hydraulics (a loader's boom has its hydraulic natural
// frequency at a few hertz). Without it a correction fed by the force chatters at the step rate:
// the velocity-controlled actuator's force answers a change of its target within one step, so a
// speed correction of c·F has a loop gain of about c·M/h (M the mass the actuator moves, h the
// step), above one for leakages of a few 1e-7 (m/s)/N; through the lag it is c·M/(τ + h)
inline constexpr double kForceLag = 0.05;

// one step of that lag: the lagged value after dt [s] with input x (exact for x held over dt)
inline double lag_step(double lagged, double x, double dt) {
  return lagged + (1.0 - std::exp(-dt / kForceLag)) * (x - lagged);
}

// a sensor correction's rate is the difference of the true reading over this span [s] (the run
// contract's sample period), at run time from the delay line and on data from the 100 Hz series
// alike, so a reading that jumps from step to step gives both the same rate
inline constexpr double kRateSpan = 0.01;

// what a feature is made of, at one instant
//  actuator: a = its target speed [m/s], force = its force reading [N] (cylinder: positive pushes
//            it longer; drive: traction) and power = the machine's power reading [W], both of the
//            previous sample through the lag kForceLag, a_delayed[i] = a at t −
//            kCorrectionDelays[i], stroke = the cylinder's stroke of the previous sample [m] (the
//            drive's is the boom's, d_lift: where the load sits on the axles); rate is not used
//  sensor:   a = the channel's true reading, rate = its rate of change [unit/s], force = the lift
//            force [N] (the bucket's load shows in it), power [W], a_delayed as above, stroke =
//            the lift stroke d_lift [m] (the boom's position, which turns a load cell's geometry)
//  traction: a = the drive's speed v_drive of the previous sample [m/s], force = the lift force
//            [N] (the load on the axles) and power [W] through the lag kForceLag, a_delayed[i] = v
//            at t − kCorrectionDelays[i] (a delayed difference is an acceleration: a mass), stroke
//            = d_lift; rate is not used
//  all:      digging = 1 inside the run's digging phase [dig_start, dig_end), else 0
//            (EffectContext::digging; a run without phase marks is never digging)
struct CorrectionInputs {
  double a = 0.0;
  double rate = 0.0;
  double force = 0.0;
  double power = 0.0;
  double stroke = 0.0;
  double digging = 0.0;
  std::array<double, kCorrectionDelays.size()> a_delayed{};
};

// one dictionary entry: its parameter name, how it reads in an equation and its unit, both as
// templates where {a}, {v}, {F}, {P}, {s} stand for the quantity, its rate, the force, the power
// and the stroke (correction_expression and correction_unit substitute them), and its value
struct CorrectionFeature {
  const char* name;        // [a-z0-9_]+: the effect's parameter
  const char* expression;  // e.g. "|{F}|·({a}(t−0.2 s) − {a})"
  const char* unit;        // e.g. "N·{a}"
  double (*value)(const CorrectionInputs&);
};

// the dictionary of a kind, in a fixed order
const std::vector<CorrectionFeature>& correction_features(CorrectionKind kind);

// the names and units a kind's quantities take in equations: what it corrects ("u_lift" [m/s],
// "f_tilt" [N], the tractive force "f_traction" [N]), and the quantity a features read: the
// actuator's command and force ("u_lift", "f_lift"), the channel, its rate and the lift force, or
// the drive's speed and the lift force
struct CorrectionSymbols {
  std::string corrected, corrected_unit;
  std::string a, a_unit, rate, rate_unit, force = "f_lift", power = "P", stroke = "d_lift";
};
// the symbols of the actuator ("drive", "lift", "tilt"), the sensor channel ("f_traction", ...)
// or, for the traction kind, "traction"
CorrectionSymbols correction_symbols(CorrectionKind kind, const std::string& target);

// a feature's expression and unit with the symbols substituted: "f_lift·sign(u_lift)", "N"
std::string correction_expression(const CorrectionFeature& f, const CorrectionSymbols& s);
std::string correction_unit(const CorrectionFeature& f, const CorrectionSymbols& s);

// the names of the learned corrections (not among the candidates: they are fitted, not searched)
std::vector<std::string> learned_effect_names();
// a learned correction with all coefficients zero; talus::InputError for another name
std::unique_ptr<Effect> make_learned_effect(const std::string& name);

// below this drive speed a traction feature's sign(v) ramps linearly to zero [m/s]: a machine at
// rest is not pushed (tyre_rolling_resistance's ramp, far below any driving speed, 0.5-3.6 m/s)
inline constexpr double kTractionSignRampSpeed = 0.01;

// the largest magnitude of a coefficient, in SI units of the correction per feature unit: far
// beyond any physical correction (a leakage of 1e6 m/s per N is nonsense), only a guard against
// overflow
inline constexpr double kMaxCorrectionCoefficient = 1e6;

}  // namespace talus::vehicle
