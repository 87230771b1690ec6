// The sensors of SPEC §2.4 (paper Table 1), sampled from the wheel loader's state after a step, and
// the 100 Hz log with power P = f_tr v + f_l ḋ_l + f_t ḋ_t and work W = ∫ P dt.
// The channels, their conventions and units: vehicle/sensor_channels.hpp.
#pragma once
#include <array>
#include <string>
#include <vector>

#include "vehicle/sensor_channels.hpp"
#include "vehicle/wheel_loader.hpp"

namespace talus::vehicle {

// the sensors at time t, from the last step's forces and the current state
SensorSample read_sensors(const WheelLoader& loader, double t);

// the largest magnitude each channel can read on this loader, in its unit (index as
// kSensorChannels; 0: no bound, for t and the positions): five times what the machine's data
// allows, so that a record beyond it holds a unit error (mm for m, mN for N) or a broken sensor,
// never a real reading. Forces from the cylinders' relief-pressure forces and the tyres' grip under
// the machine with its tipping load, the drive speed from its top speed, strokes from the
// cylinders' ranges, angles half a turn, power from those forces at those speeds
std::array<double, kChannelCount> reading_limits(const WheelLoader& loader);

// samples at a fixed rate and integrates the work
class SensorLog {
 public:
  explicit SensorLog(double rate_hz = 100.0) : period_(1.0 / rate_hz) {}
  // call after every step (and once at the start with h = 0); records a sample at every sampling
  // instant k / rate_hz the step reached. Steps longer than the period (D400: 20 ms) get their
  // instants linearly interpolated between the states before and after the step, so the log is
  // at the stated rate whatever the timestep
  void after_step(const WheelLoader& loader, double t, double h);
  // the same with a sample already taken at s.t (what the sensors report when model extensions
  // change the readings, vehicle/effect.hpp)
  void after_step(const SensorSample& s, double h);
  const std::vector<SensorSample>& samples() const { return samples_; }
  double work() const { return work_; }  // J, integrated every step
  double period() const { return period_; }
  // the log for a saved state (digging/saved_state): its samples, work and the state after the
  // last step it interpolates from; restore_state replaces this log's with what save_state wrote
  void save_state(ByteWriter& w) const;
  void restore_state(ByteReader& r);

 private:
  double period_;
  double work_ = 0.0;
  std::vector<SensorSample> samples_;
  SensorSample last_;       // the state after the previous step
  bool has_last_ = false;
};

// one sample bit for bit, every field (the contract's channels and the rates), for saved states
void write_sample(ByteWriter& w, const SensorSample& s);
SensorSample read_sample(ByteReader& r, const char* what);

// samples as the run contract's timeseries.csv: channel_header() and one row per sample, each
// number with the 17 digits that round-trip a double, so the file reads back as the samples
// exactly. The one writer of the contract (sim2real::save_timeseries goes through it too)
std::string sensor_csv(const std::vector<SensorSample>& samples);

// the work [J] of the logged power over [t0, t1] (trapezoids between samples, the window's ends
// interpolated): the work of a phase, e.g. the digging phase the metrics compare
double work_between(const std::vector<SensorSample>& samples, double t0, double t1);

// a + s (b - a), channel by channel (time included)
SensorSample interpolate(const SensorSample& a, const SensorSample& b, double s);

}  // namespace talus::vehicle
