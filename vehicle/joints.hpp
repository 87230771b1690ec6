// Joints between two bodies (or a body and the world, index kWorld), each with optional range
// limit and motor on its free coordinate (SPEC §2.1, paper eq. 1-3):
//   BallJoint       3 rows: the anchors coincide
//   HingeJoint      5 rows: anchors coincide, axes aligned; free coordinate: angle about the axis
//   PrismaticJoint  5 rows: no rotation, no motion across the axis; free coordinate: slide
//   LockJoint       6 rows: no relative motion
//   CylinderJoint   0 rows of its own: a hydraulic cylinder pinned at both ends, i.e. a prismatic
//                   pair (barrel, rod) whose masses are lumped into the bodies it connects; with its
//                   lateral freedoms taken by the end pins, only the pin-to-pin length remains, and
//                   that is where its motor (the hydraulics) and stroke limits act.
// A motor is a velocity row G v⁺ = target speed with its force range [force_min, force_max].
// A range limit adds one-sided holonomic rows at each end (an equality row when lower == upper).
#pragma once
#include <vector>

#include "vehicle/constraint.hpp"

namespace talus::vehicle {

struct Motor {
  bool enabled = false;
  double target_speed = 0.0;        // m/s or rad/s of the free coordinate
  double force_min = -kInfinity;    // N or N m
  double force_max = kInfinity;
  double viscous_compliance = 1e-10;  // m/(N s): keeps redundant motors (parallel cylinders) regular
};

struct RangeLimit {
  bool enabled = false;
  double lower = -kInfinity;  // m or rad
  double upper = kInfinity;
};

// common part: two frames, joint row parameters, motor and range on one free coordinate
class Joint : public Constraint {
 public:
  Joint(BodyFrame a, BodyFrame b, RowParameters parameters) : a_(a), b_(b), parameters_(parameters) {}
  Motor motor;
  RangeLimit range;
  // free coordinate and its rate at the bodies' current state (0 for joints without one)
  virtual double coordinate(const std::vector<RigidBody>& bodies) const = 0;
  double coordinate_rate(const std::vector<RigidBody>& bodies) const;
  // last step's forces along the free coordinate: motor, range limit, and their sum
  double motor_force() const { return motor_force_; }
  double limit_force() const { return limit_force_; }
  double actuator_force() const { return motor_force_ + limit_force_; }
  // largest violation of the joint's bilateral rows at the start of the last step [m] and [rad]
  double position_violation() const { return position_violation_; }
  double angle_violation() const { return angle_violation_; }
  const BodyFrame& frame_a() const { return a_; }
  const BodyFrame& frame_b() const { return b_; }
  void store_forces(const double* impulse, int count, double h) override;
  // the base's forces, the motor as last commanded, the coordinate's forces and the violations
  void save_state(ByteWriter& w) const override;
  void restore_state(ByteReader& r) override;

 protected:
  // the row of the free coordinate (Jacobian only), for motor and limits
  virtual ConstraintRow coordinate_row(const std::vector<RigidBody>& bodies) const = 0;
  // start this step's rows at the end of `rows`: no bilateral rows yet, violations reset
  void begin_rows(const std::vector<ConstraintRow>& rows);
  // append the bilateral rows, then limit and motor rows
  void add_joint_row(std::vector<ConstraintRow>& rows, ConstraintRow row, RowUnit unit, double violation);
  void add_motor_and_limits(const std::vector<RigidBody>& bodies, std::vector<ConstraintRow>& rows);
  // the three point rows: anchors coincide
  void add_point_rows(const std::vector<RigidBody>& bodies, std::vector<ConstraintRow>& rows);
  BodyFrame a_, b_;
  RowParameters parameters_;
  int first_row_ = 0;          // rows of this step, counted from this joint's first
  int limit_lower_row_ = -1, limit_upper_row_ = -1, motor_row_ = -1;
  int bilateral_rows_ = 0;
  double motor_force_ = 0.0, limit_force_ = 0.0;
  double position_violation_ = 0.0, angle_violation_ = 0.0;
};

class BallJoint : public Joint {
 public:
  BallJoint(const std::vector<RigidBody>& bodies, int a, int b, const Vec3& world_anchor, RowParameters p = {});
  void add_rows(const std::vector<RigidBody>& bodies, std::vector<ConstraintRow>& rows) override;
  double coordinate(const std::vector<RigidBody>&) const override { return 0.0; }

 protected:
  ConstraintRow coordinate_row(const std::vector<RigidBody>&) const override { return {}; }
};

class HingeJoint : public Joint {
 public:
  HingeJoint(const std::vector<RigidBody>& bodies, int a, int b, const Vec3& world_anchor, const Vec3& world_axis,
             RowParameters p = {});
  void add_rows(const std::vector<RigidBody>& bodies, std::vector<ConstraintRow>& rows) override;
  // angle of b relative to a about the axis, zero at assembly, in (-π, π]
  double coordinate(const std::vector<RigidBody>& bodies) const override;

 protected:
  ConstraintRow coordinate_row(const std::vector<RigidBody>& bodies) const override;
};

class PrismaticJoint : public Joint {
 public:
  PrismaticJoint(const std::vector<RigidBody>& bodies, int a, int b, const Vec3& world_anchor,
                 const Vec3& world_axis, RowParameters p = {});
  void add_rows(const std::vector<RigidBody>& bodies, std::vector<ConstraintRow>& rows) override;
  // slide of b's anchor along a's axis, zero at assembly
  double coordinate(const std::vector<RigidBody>& bodies) const override;

 protected:
  ConstraintRow coordinate_row(const std::vector<RigidBody>& bodies) const override;
};

class LockJoint : public Joint {
 public:
  LockJoint(const std::vector<RigidBody>& bodies, int a, int b, const Vec3& world_anchor, RowParameters p = {});
  // the two frames made again at the bodies' current poses, both at `world_anchor` with the
  // world's axes: a lock whose owner moves one body every step (the type-G bucket's payload)
  // holds them as they now stand, with no violation to correct
  void reanchor(const std::vector<RigidBody>& bodies, const Vec3& world_anchor);
  void add_rows(const std::vector<RigidBody>& bodies, std::vector<ConstraintRow>& rows) override;
  double coordinate(const std::vector<RigidBody>&) const override { return 0.0; }

 protected:
  ConstraintRow coordinate_row(const std::vector<RigidBody>&) const override { return {}; }
};

class CylinderJoint : public Joint {
 public:
  // pins at world points at assembly; the free coordinate is the pin-to-pin length
  CylinderJoint(const std::vector<RigidBody>& bodies, int a, const Vec3& world_pin_a, int b,
                const Vec3& world_pin_b, RowParameters p = {});
  void add_rows(const std::vector<RigidBody>& bodies, std::vector<ConstraintRow>& rows) override;
  double coordinate(const std::vector<RigidBody>& bodies) const override;

 protected:
  ConstraintRow coordinate_row(const std::vector<RigidBody>& bodies) const override;
};

}  // namespace talus::vehicle
