// The sensors of SPEC §2.4 (paper Table 1), sampled from the wheel loader's state after a step, and
// the 100 Hz log with power P = f_tr v + f_l ḋ_l + f_t ḋ_t and work W = ∫ P dt.
// Conventions: forces in N (cylinder: positive pushes it longer; traction: positive forward on the
// machine), lengths in m, angles in degrees positive nose-up / boom-up / bucket-curled, measured in
// the front frame's x-z plane; d_lift and d_tilt are strokes (pin-to-pin length minus closed length),
// d_lift the mean of the two lift cylinders and f_lift their sum.
#pragma once
#include <iosfwd>
#include <string>
#include <vector>

#include "vehicle/wheel_loader.hpp"

namespace talus::vehicle {

struct SensorSample {
  double t = 0.0;
  double f_lift = 0.0, f_tilt = 0.0, f_traction = 0.0;
  double v_drive = 0.0;
  double d_lift = 0.0, d_tilt = 0.0;
  double boom_deg = 0.0, bucket_deg = 0.0, pitch_deg = 0.0;
  double x_vehicle = 0.0;
  double bucket_tip_x = 0.0, bucket_tip_z = 0.0;
  double power = 0.0;
  double lift_rate = 0.0, tilt_rate = 0.0;  // ḋ_l, ḋ_t [m/s] (not in the CSV contract)
};

// the sensors at time t, from the last step's forces and the current state
SensorSample read_sensors(const WheelLoader& loader, double t);

// the CSV header of the run contract
const char* sensor_csv_header();
void write_sensor_csv_row(std::ostream& out, const SensorSample& s);

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

 private:
  double period_;
  double work_ = 0.0;
  std::vector<SensorSample> samples_;
  SensorSample last_;       // the state after the previous step
  bool has_last_ = false;
};

// the whole log as the run contract's timeseries.csv (header and one row per sample, 10 digits)
std::string sensor_log_csv(const SensorLog& log);

// the work [J] of the logged power over [t0, t1] (trapezoids between samples, the window's ends
// interpolated): the work of a phase, e.g. the digging phase the metrics compare
double work_between(const std::vector<SensorSample>& samples, double t0, double t1);

// a + s (b - a), channel by channel (time included)
SensorSample interpolate(const SensorSample& a, const SensorSample& b, double s);

}  // namespace talus::vehicle
