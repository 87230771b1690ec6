// Field-like data for the sim-to-real loop (issue 6, docs/sim2real.md): what real sensors and a
// real operator add to a simulated run. `talus synth` turns a simulation into a measured run with
// these; the diagnosis must then find the effects that made it, through this noise.
#pragma once
#include <map>
#include <string>

#include "sim2real/measured.hpp"
#include "sim2real/timeseries.hpp"
#include "vehicle/scenario.hpp"

namespace talus::sim2real {

// one standard deviation per channel in its SI unit for the "default" noise: load-cell and
// pressure-derived forces about 1 % of their range, a wheel-revolution speed sensor a few cm/s,
// draw-wire extensions a millimetre, potentiometer angles a fifth of a degree, laser positions a
// couple of centimetres, power (computed from forces and speeds) about 1 kW, a percent of the
// engine's (orders of magnitude of the paper's instrumentation, Table 1; no per-sensor data is
// published)
const std::map<std::string, double>& default_sensor_noise();
// the largest noise a channel may be given, over its default (a real sensor's): beyond it the
// noise outgrows what the channel measures (f_lift: 250 kN against a dig's 300 kN), and at five
// of its σ it stays within half of what the machine can read (vehicle::reading_limits), so a
// synthetic run always loads as a measured one (Synthetic.TheLargestNoiseStaysWithinTheReadings)
inline constexpr double kMaxNoiseOverDefault = 50.0;

// "none", "default", or CHANNEL=SIGMA pairs separated by commas ("default,f_lift=1e4" changes one
// of the defaults); InputError starting with `what` (the option or field it came from) and naming
// the bad part
std::map<std::string, double> parse_sensor_noise(const std::string& spec, const std::string& what);

// every channel of `series` named in `sigma` (t never) with zero-mean Gaussian noise of that
// standard deviation, drawn in channel order from `seed`
void add_sensor_noise(TimeSeries& series, const std::map<std::string, double>& sigma, unsigned seed);

// how far a repetition's commands may shift in time at variation 1 [s]: an operator repeats a
// cycle to within a fraction of a second (a guess; the paper publishes one run per test)
inline constexpr double kTimingShiftPerVariation = 1.0;

// one repetition of the scenario by an operator who varies: each target-speed series scaled by
// 1 + v u and its inner breakpoints shifted by v u' kTimingShiftPerVariation (u, u' uniform in
// [-1, 1], drawn per series from `seed`), kept inside (0, duration) and in order; the digging
// phase's marks move with them (its start with the drive's shift, its end with the mean of the
// lift's and the tilt's); v = 0 returns the scenario's own inputs
vehicle::Scenario varied_inputs(vehicle::Scenario scenario, double v, unsigned seed);

// the metadata of a measured run made from `scenario` (its machine, inputs and pile toe), the
// pile's laser scan and the run's loaded mass and work
MeasuredMetadata synthetic_metadata(const vehicle::Scenario& scenario, const Series2& pile_scan,
                                    const RunSummary& summary);

}  // namespace talus::sim2real
