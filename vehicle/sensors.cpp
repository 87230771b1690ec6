#include "vehicle/sensors.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <iomanip>
#include <limits>
#include <ostream>
#include <sstream>
#include <string>

#include "host/error.hpp"

namespace talus::vehicle {

namespace {

double degrees(double rad) { return rad * 180.0 / M_PI; }

// angle of a world direction in the x-z plane of a frame, positive towards +z
double plane_angle(const RigidBody& frame, const Vec3& world_direction) {
  const Vec3 d = frame.vector_to_local(world_direction);
  return std::atan2(d.z(), d.x());
}

}  // namespace

std::array<double, kChannelCount> reading_limits(const WheelLoader& loader) {
  // five times the machine's data: far beyond what a working sensor reads (the cylinders' end
  // stops, which relief pressure does not cap, and road speeds above the digging gear's top
  // included), far below the thousandfold of a unit prefix
  constexpr double kMargin = 5.0;
  std::array<double, kChannelCount> limit{};
  auto set = [&](Channel c, double v) { limit[static_cast<std::size_t>(c)] = kMargin * v; };
  // cylinders: the relief pressure's force on the piston or the annulus; two lift cylinders summed
  const CylinderSpec& lift = loader.lift_spec();
  const CylinderSpec& tilt = loader.tilt_spec();
  const double f_lift = 2.0 * std::max(lift.force_push, lift.force_pull);
  const double f_tilt = std::max(tilt.force_push, tilt.force_pull);
  set(Channel::f_lift, f_lift);
  set(Channel::f_tilt, f_tilt);
  // the tyres' grip under the machine carrying its tipping load (braking on the tyres can exceed
  // the driveline's traction limit), or the driveline's limit where that is larger
  double grip = 0.0;
  for (const auto* ty : loader.tyres()) grip = std::max(grip, ty->parameters().friction);
  const double weight =
      (loader.operating_mass() + loader.static_tipping_load()) * loader.system().gravity().norm();
  const double f_traction = std::max(loader.traction_limit(), grip * weight);
  set(Channel::f_traction, f_traction);
  set(Channel::v_drive, loader.top_speed());
  set(Channel::d_lift, lift.length_max - lift.length_min);
  set(Channel::d_tilt, tilt.length_max - tilt.length_min);
  // angles: half a turn either way, whatever the margin
  for (Channel c : {Channel::boom_deg, Channel::bucket_deg, Channel::pitch_deg})
    limit[static_cast<std::size_t>(c)] = 180.0;
  // P = f_tr v + f_l ḋ_l + f_t ḋ_t at the largest forces and speeds
  set(Channel::power,
      f_traction * loader.top_speed() + f_lift * lift.max_speed + f_tilt * tilt.max_speed);
  return limit;
}

SensorSample read_sensors(const WheelLoader& loader, double t) {
  const auto& bodies = loader.bodies();
  SensorSample s;
  s.t = t;
  // cylinder forces: motor plus stroke-limit force, which the pressure sensors would also see
  for (const auto* c : loader.lift_cylinders()) {
    s.f_lift += c->actuator_force();
    s.d_lift += 0.5 * (c->coordinate(bodies) - loader.lift_spec().length_min);
    s.lift_rate += 0.5 * c->coordinate_rate(bodies);
  }
  s.f_tilt = loader.tilt_cylinder().actuator_force();
  s.d_tilt = loader.tilt_cylinder().coordinate(bodies) - loader.tilt_spec().length_min;
  s.tilt_rate = loader.tilt_cylinder().coordinate_rate(bodies);
  // traction: ground friction on the wheels along their heading; speed from wheel revolution
  for (const auto* ty : loader.tyres()) s.f_traction += ty->longitudinal_force();
  s.v_drive = loader.driveline().drive_speed(bodies);
  // angles in the front frame: boom line pivot -> bucket hinge, bucket bottom plate, pitch
  const RigidBody& frame = bodies[loader.front_frame()];
  const auto& pivot = loader.hinge("boom_pivot");
  const auto& hinge = loader.hinge("bucket_hinge");
  const Vec3 boom = hinge.frame_a().world_anchor(bodies) - pivot.frame_a().world_anchor(bodies);
  s.boom_deg = degrees(plane_angle(frame, boom));
  s.bucket_deg = degrees(plane_angle(frame, bodies[loader.bucket_body()].vector_to_world(Vec3::UnitX())));
  const Vec3 x = frame.vector_to_world(Vec3::UnitX());
  s.pitch_deg = degrees(std::atan2(x.z(), std::hypot(x.x(), x.y())));
  // position: front axle centre; bucket tip
  const auto& tyres = loader.tyres();
  s.x_vehicle = 0.5 * (bodies[tyres[0]->wheel()].position.x() + bodies[tyres[1]->wheel()].position.x());
  const Vec3 tip = loader.bucket_tip_world();
  s.bucket_tip_x = tip.x();
  s.bucket_tip_z = tip.z();
  s.power = s.f_traction * s.v_drive + s.f_lift * s.lift_rate + s.f_tilt * s.tilt_rate;
  return s;
}


std::string sensor_csv(const std::vector<SensorSample>& samples) {
  // digits that round-trip a double exactly (std::numeric_limits<double>::max_digits10)
  constexpr int kRoundTripDigits = std::numeric_limits<double>::max_digits10;
  std::ostringstream csv;
  csv << std::setprecision(kRoundTripDigits) << channel_header() << '\n';
  for (const auto& s : samples) {
    for (std::size_t c = 0; c < kChannelCount; ++c) csv << (c ? "," : "") << s.*kSensorChannels[c].field;
    csv << '\n';
  }
  return csv.str();
}

double work_between(const std::vector<SensorSample>& samples, double t0, double t1) {
  // the power at time t by linear interpolation between samples (clamped to the log)
  double w = 0.0;
  for (size_t k = 1; k < samples.size(); ++k) {
    const SensorSample& a = samples[k - 1];
    const SensorSample& b = samples[k];
    const double lo = std::max(a.t, t0), hi = std::min(b.t, t1);
    if (hi <= lo || b.t <= a.t) continue;
    const auto power_at = [&](double t) { return a.power + (b.power - a.power) * (t - a.t) / (b.t - a.t); };
    w += 0.5 * (power_at(lo) + power_at(hi)) * (hi - lo);
  }
  return w;
}

SensorSample interpolate(const SensorSample& a, const SensorSample& b, double s) {
  auto mix = [s](double x, double y) { return x + s * (y - x); };
  SensorSample r;
  r.t = mix(a.t, b.t);
  r.f_lift = mix(a.f_lift, b.f_lift);
  r.f_tilt = mix(a.f_tilt, b.f_tilt);
  r.f_traction = mix(a.f_traction, b.f_traction);
  r.v_drive = mix(a.v_drive, b.v_drive);
  r.d_lift = mix(a.d_lift, b.d_lift);
  r.d_tilt = mix(a.d_tilt, b.d_tilt);
  r.boom_deg = mix(a.boom_deg, b.boom_deg);
  r.bucket_deg = mix(a.bucket_deg, b.bucket_deg);
  r.pitch_deg = mix(a.pitch_deg, b.pitch_deg);
  r.x_vehicle = mix(a.x_vehicle, b.x_vehicle);
  r.bucket_tip_x = mix(a.bucket_tip_x, b.bucket_tip_x);
  r.bucket_tip_z = mix(a.bucket_tip_z, b.bucket_tip_z);
  r.power = mix(a.power, b.power);
  r.lift_rate = mix(a.lift_rate, b.lift_rate);
  r.tilt_rate = mix(a.tilt_rate, b.tilt_rate);
  return r;
}

void SensorLog::after_step(const WheelLoader& loader, double t, double h) { after_step(read_sensors(loader, t), h); }

void SensorLog::after_step(const SensorSample& s, double h) {
  const double t = s.t;
  if (!has_last_ && t != 0.0)
    throw Error("sensor log: the first sample must be taken at t = 0 (got t = " + std::to_string(t) + " s)");
  if (has_last_ && !(h > 0.0 && t > last_.t))
    throw Error("sensor log: after the first sample every call must follow a step (h > 0, t later than before)");
  // work: trapezoids over the step, as work_between integrates the samples
  if (has_last_) work_ += 0.5 * (last_.power + s.power) * h;
  // every sampling instant k period within this step: the step's own state where an instant
  // falls on its end (to within a billionth of the period), interpolated otherwise
  for (;;) {
    const double next = static_cast<double>(samples_.size()) * period_;
    if (next > t + 1e-9 * period_) break;
    if (!has_last_ || next >= t - 1e-9 * period_) {
      samples_.push_back(s);
      samples_.back().t = next;
    } else {
      samples_.push_back(interpolate(last_, s, (next - last_.t) / (t - last_.t)));
    }
  }
  last_ = s;
  has_last_ = true;
}

namespace {
// every field of a sample, the contract's channels first: what a saved state keeps of it
constexpr std::array<double SensorSample::*, kChannelCount + 2> kSampleFields = [] {
  std::array<double SensorSample::*, kChannelCount + 2> f{};
  for (std::size_t c = 0; c < kChannelCount; ++c) f[c] = kSensorChannels[c].field;
  f[kChannelCount] = &SensorSample::lift_rate;
  f[kChannelCount + 1] = &SensorSample::tilt_rate;
  return f;
}();
// a field added to SensorSample must be added to kSampleFields, or saved states lose it
static_assert(sizeof(SensorSample) == kSampleFields.size() * sizeof(double),
              "SensorSample has a field that kSampleFields does not list");
}  // namespace

void write_sample(ByteWriter& w, const SensorSample& s) {
  for (const auto field : kSampleFields) w.f64(s.*field);
}

SensorSample read_sample(ByteReader& r, const char* what) {
  SensorSample s;
  for (const auto field : kSampleFields) s.*field = r.f64(what);
  return s;
}

void SensorLog::save_state(ByteWriter& w) const {
  w.f64(period_);
  w.f64(work_);
  w.u64(samples_.size());
  for (const SensorSample& s : samples_) write_sample(w, s);
  write_sample(w, last_);
  w.u8(has_last_ ? 1 : 0);
}

void SensorLog::restore_state(ByteReader& r) {
  const double period = r.f64("sensor log");
  if (period != period_)
    throw InputError(r.where() + ": the saved sensor log samples every " + std::to_string(period) +
                     " s, this one every " + std::to_string(period_) + " s");
  work_ = r.f64("sensor log");
  const std::uint64_t n = r.u64("sensor log");
  r.need_elements(n, kSampleFields.size() * 8, "sensor log");
  samples_.clear();
  samples_.reserve(n);
  for (std::uint64_t k = 0; k < n; ++k) samples_.push_back(read_sample(r, "sensor log"));
  last_ = read_sample(r, "sensor log");
  has_last_ = r.u8("sensor log") != 0;
}

}  // namespace talus::vehicle
