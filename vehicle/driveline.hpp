// The driveline (SPEC §2.4, paper §4.2): the engine is a hinge motor on the propeller shaft, whose
// speed is the gear ratio times the mean wheel speed (relative to each wheel's frame); open
// differentials split its torque equally left/right, and a rigid transfer case ties the front and
// rear axles (one velocity row: mean front wheel speed = mean rear wheel speed).
// The motor's torque limit depends on its speed: T_max(ω) = min(T_stall, P_max / |ω|); the power
// part is settled after each solve (update_bounds) so the delivered power never exceeds P_max.
// The engine and hydrostatic transmission have no inertia of their own here (not in the baseline).
// The power limit starts at P_max and may be lowered step by step (set_power_limit): the engine
// power left to the driveline when the work hydraulics share the engine (vehicle/effect.hpp).
#pragma once
#include <array>

#include "vehicle/constraint.hpp"

namespace talus::vehicle {

struct DrivelineParameters {
  double max_power = 127e3;      // W
  double stall_torque = 2000.0;  // N m at the motor shaft
  double gear_ratio = 40.0;      // motor speed / wheel speed
  double wheel_radius = 0.695;   // m
  double max_speed = 3.6;        // m/s: the target drive speed is clipped to ±this
  double viscous_compliance = 1e-10;  // m/(N s) analogue for the shaft rows
};

class Driveline : public Constraint {
 public:
  // wheels front-left, front-right, rear-left, rear-right; each with the frame it is hinged to and
  // its spin axis in the wheel's body frame (positive spin = forward)
  Driveline(std::array<int, 4> wheels, std::array<int, 4> frames, const Vec3& local_axis, DrivelineParameters p);
  void set_target_drive_speed(double v) { target_drive_speed_ = v; }
  double target_drive_speed() const { return target_drive_speed_; }
  void add_rows(const std::vector<RigidBody>& bodies, std::vector<ConstraintRow>& rows) override;
  bool update_bounds(const double* row_velocity, const double* impulse, ConstraintRow* rows, int count) override;
  // motor speed [rad/s] and drive speed from wheel revolution [m/s] at the bodies' state
  double motor_speed(const std::vector<RigidBody>& bodies) const;
  double drive_speed(const std::vector<RigidBody>& bodies) const;
  double motor_torque() const { return forces_.empty() ? 0.0 : forces_[0]; }
  double torque_limit(double motor_speed) const;
  const DrivelineParameters& parameters() const { return p_; }
  // the power the motor may deliver from the next step on [W] (> 0); parameters().max_power stays
  // the rated value
  void set_power_limit(double watts);
  double power_limit() const { return power_limit_; }
  // the base's forces, the target speed and the power limit
  void save_state(ByteWriter& w) const override;
  void restore_state(ByteReader& r) override;

 private:
  ConstraintRow motor_row(const std::vector<RigidBody>& bodies) const;
  std::array<int, 4> wheels_, frames_;
  Vec3 axis_;
  DrivelineParameters p_;
  double target_drive_speed_ = 0.0;
  double power_limit_ = 0.0;  // W, P_max unless lowered
};

}  // namespace talus::vehicle
