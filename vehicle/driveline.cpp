#include "vehicle/driveline.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "host/error.hpp"

namespace talus::vehicle {

Driveline::Driveline(std::array<int, 4> wheels, std::array<int, 4> frames, const Vec3& local_axis,
                     DrivelineParameters p)
    : wheels_(wheels), frames_(frames), axis_(local_axis.normalized()), p_(p), power_limit_(p.max_power) {
  if (!(p.max_power > 0.0) || !(p.stall_torque > 0.0) || !(p.gear_ratio > 0.0) || !(p.wheel_radius > 0.0)) {
    throw Error("driveline: power, stall torque, gear ratio and wheel radius must be > 0");
  }
}

void Driveline::set_power_limit(double watts) {
  if (!(watts > 0.0) || !std::isfinite(watts))
    throw Error("driveline: the power limit must be a finite value > 0 W (got " + std::to_string(watts) + ")");
  power_limit_ = watts;
}

double Driveline::torque_limit(double motor_speed) const {
  const double w = std::abs(motor_speed);
  return w > 0.0 ? std::min(p_.stall_torque, power_limit_ / w) : p_.stall_torque;
}

ConstraintRow Driveline::motor_row(const std::vector<RigidBody>& bodies) const {
  // ω_motor = (ratio / 4) Σ (ω_wheel - ω_frame) · axis_wheel
  ConstraintRow r;
  const double k = p_.gear_ratio / 4.0;
  for (int i = 0; i < 4; ++i) {
    const Vec3 a = bodies[wheels_[i]].vector_to_world(axis_);
    r.blocks.push_back({wheels_[i], (Vec6() << Vec3::Zero(), k * a).finished()});
    if (frames_[i] != kWorld) r.blocks.push_back({frames_[i], (Vec6() << Vec3::Zero(), -k * a).finished()});
  }
  return r;
}

double Driveline::motor_speed(const std::vector<RigidBody>& bodies) const {
  double w = 0.0;
  for (const auto& b : motor_row(bodies).blocks) w += b.jacobian.dot(bodies[b.body].twist());
  return w;
}

double Driveline::drive_speed(const std::vector<RigidBody>& bodies) const {
  return motor_speed(bodies) / p_.gear_ratio * p_.wheel_radius;
}

void Driveline::add_rows(const std::vector<RigidBody>& bodies, std::vector<ConstraintRow>& rows) {
  // engine: hinge motor on the propeller shaft, target from the target drive speed
  ConstraintRow motor = motor_row(bodies);
  const double v = std::clamp(target_drive_speed_, -p_.max_speed, p_.max_speed);
  motor.kind = RowKind::velocity;
  motor.target_speed = v / p_.wheel_radius * p_.gear_ratio;
  motor.compliance = p_.viscous_compliance;
  const double t = torque_limit(motor_speed(bodies));
  motor.force_min = -t;
  motor.force_max = t;
  rows.push_back(motor);
  // transfer case: mean front wheel speed = mean rear wheel speed (relative to their frames)
  ConstraintRow transfer;
  transfer.kind = RowKind::velocity;
  transfer.compliance = p_.viscous_compliance;
  for (int i = 0; i < 4; ++i) {
    const double s = i < 2 ? 0.5 : -0.5;
    const Vec3 a = bodies[wheels_[i]].vector_to_world(axis_);
    transfer.blocks.push_back({wheels_[i], (Vec6() << Vec3::Zero(), s * a).finished()});
    if (frames_[i] != kWorld) transfer.blocks.push_back({frames_[i], (Vec6() << Vec3::Zero(), -s * a).finished()});
  }
  rows.push_back(transfer);
}

bool Driveline::update_bounds(const double* row_velocity, const double* impulse, ConstraintRow* rows, int count) {
  if (count < 1) return false;
  (void)impulse;
  // the torque limit at the speed the motor reaches in this step: power never above P_max
  const double limit = torque_limit(row_velocity[0]);
  if (limit < rows[0].force_max * (1.0 - 1e-12)) {
    rows[0].force_min = -limit;
    rows[0].force_max = limit;
    return true;
  }
  return false;
}

void Driveline::save_state(ByteWriter& w) const {
  Constraint::save_state(w);
  w.f64(target_drive_speed_);
  w.f64(power_limit_);
}

void Driveline::restore_state(ByteReader& r) {
  Constraint::restore_state(r);
  target_drive_speed_ = r.f64("driveline");
  power_limit_ = r.f64("driveline");
}

}  // namespace talus::vehicle
