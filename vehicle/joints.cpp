#include "vehicle/joints.hpp"

#include <algorithm>
#include <cmath>

#include "host/error.hpp"

namespace talus::vehicle {

namespace {

double row_rate(const ConstraintRow& row, const std::vector<RigidBody>& bodies) {
  double r = 0.0;
  for (const auto& blk : row.blocks) r += blk.jacobian.dot(bodies[blk.body].twist());
  return r;
}

void check_body(const std::vector<RigidBody>& bodies, int b) {
  if (b != kWorld && (b < 0 || b >= static_cast<int>(bodies.size()))) {
    throw Error("joint: body index " + std::to_string(b) + " out of range");
  }
}

}  // namespace

double Joint::coordinate_rate(const std::vector<RigidBody>& bodies) const {
  return row_rate(coordinate_row(bodies), bodies);
}

void Joint::add_joint_row(std::vector<ConstraintRow>& rows, ConstraintRow row, RowUnit unit, double violation) {
  row.kind = RowKind::holonomic;
  row.unit = unit;
  row.violation = violation;
  row.compliance = parameters_.compliance;
  row.damping_time = parameters_.damping_time;
  row.joint = true;
  rows.push_back(std::move(row));
  ++bilateral_rows_;
  if (unit == RowUnit::length) position_violation_ = std::max(position_violation_, std::abs(violation));
  if (unit == RowUnit::angle) angle_violation_ = std::max(angle_violation_, std::abs(violation));
}

void Joint::begin_rows(const std::vector<ConstraintRow>& rows) {
  first_row_ = static_cast<int>(rows.size());
  bilateral_rows_ = 0;
  position_violation_ = angle_violation_ = 0.0;
}

void Joint::add_point_rows(const std::vector<RigidBody>& bodies, std::vector<ConstraintRow>& rows) {
  const Vec3 pa = a_.world_anchor(bodies);
  const Vec3 pb = b_.world_anchor(bodies);
  for (int k = 0; k < 3; ++k) {
    const Vec3 n = Vec3::Unit(k);
    add_joint_row(rows, point_row(bodies, a_, b_, pa, pb, n), RowUnit::length, n.dot(pb - pa));
  }
}

void Joint::add_motor_and_limits(const std::vector<RigidBody>& bodies, std::vector<ConstraintRow>& rows) {
  limit_lower_row_ = limit_upper_row_ = motor_row_ = -1;
  if (!range.enabled && !motor.enabled) return;
  const ConstraintRow base = coordinate_row(bodies);
  const double q = coordinate(bodies);
  if (range.enabled) {
    if (range.lower > range.upper) throw Error("joint '" + name + "': range lower > upper");
    // lower end: g = q - lower >= 0, pushing with λ >= 0 (an equality when the range is one point)
    ConstraintRow lower = base;
    lower.kind = RowKind::holonomic;
    lower.violation = q - range.lower;
    lower.compliance = parameters_.compliance;
    lower.damping_time = parameters_.damping_time;
    lower.force_min = range.lower == range.upper ? -kInfinity : 0.0;
    limit_lower_row_ = static_cast<int>(rows.size()) - first_row_;
    rows.push_back(lower);
    if (range.lower != range.upper) {
      // upper end: g = upper - q >= 0 with the Jacobian reversed
      ConstraintRow upper = base;
      for (auto& blk : upper.blocks) blk.jacobian = -blk.jacobian;
      upper.kind = RowKind::holonomic;
      upper.violation = range.upper - q;
      upper.compliance = parameters_.compliance;
      upper.damping_time = parameters_.damping_time;
      upper.force_min = 0.0;
      limit_upper_row_ = static_cast<int>(rows.size()) - first_row_;
      rows.push_back(upper);
    }
  }
  if (motor.enabled) {
    if (motor.force_min > motor.force_max) throw Error("joint '" + name + "': motor force_min > force_max");
    ConstraintRow m = base;
    m.kind = RowKind::velocity;
    m.target_speed = motor.target_speed;
    m.compliance = motor.viscous_compliance;
    m.force_min = motor.force_min;
    m.force_max = motor.force_max;
    motor_row_ = static_cast<int>(rows.size()) - first_row_;
    rows.push_back(m);
  }
}

void Joint::store_forces(const double* impulse, int count, double h) {
  Constraint::store_forces(impulse, count, h);
  motor_force_ = motor_row_ >= 0 ? forces_[motor_row_] : 0.0;
  limit_force_ = 0.0;
  if (limit_lower_row_ >= 0) limit_force_ += forces_[limit_lower_row_];
  if (limit_upper_row_ >= 0) limit_force_ -= forces_[limit_upper_row_];
}

// --- ball -------------------------------------------------------------------------------------

BallJoint::BallJoint(const std::vector<RigidBody>& bodies, int a, int b, const Vec3& world_anchor, RowParameters p)
    : Joint(BodyFrame::from_world(bodies, a, world_anchor, Mat3::Identity()),
            BodyFrame::from_world(bodies, b, world_anchor, Mat3::Identity()), p) {
  check_body(bodies, a);
  check_body(bodies, b);
}

void BallJoint::add_rows(const std::vector<RigidBody>& bodies, std::vector<ConstraintRow>& rows) {
  begin_rows(rows);
  add_point_rows(bodies, rows);
}

// --- hinge ------------------------------------------------------------------------------------

HingeJoint::HingeJoint(const std::vector<RigidBody>& bodies, int a, int b, const Vec3& world_anchor,
                       const Vec3& world_axis, RowParameters p)
    : Joint(BodyFrame::from_world(bodies, a, world_anchor, frame_from_axis(world_axis)),
            BodyFrame::from_world(bodies, b, world_anchor, frame_from_axis(world_axis)), p) {
  check_body(bodies, a);
  check_body(bodies, b);
}

void HingeJoint::add_rows(const std::vector<RigidBody>& bodies, std::vector<ConstraintRow>& rows) {
  begin_rows(rows);
  add_point_rows(bodies, rows);
  // axes aligned: x_a·z_b = 0, y_a·z_b = 0
  const Mat3 fa = a_.world_axes(bodies);
  const Mat3 fb = b_.world_axes(bodies);
  for (int k = 0; k < 2; ++k) {
    add_joint_row(rows, dot_row(a_, b_, fa.col(k), fb.col(2)), RowUnit::angle, fa.col(k).dot(fb.col(2)));
  }
  add_motor_and_limits(bodies, rows);
}

double HingeJoint::coordinate(const std::vector<RigidBody>& bodies) const {
  const Mat3 fa = a_.world_axes(bodies);
  const Mat3 fb = b_.world_axes(bodies);
  return std::atan2(fa.col(1).dot(fb.col(0)), fa.col(0).dot(fb.col(0)));
}

ConstraintRow HingeJoint::coordinate_row(const std::vector<RigidBody>& bodies) const {
  return angular_row(a_, b_, a_.world_axes(bodies).col(2));
}

// --- prismatic --------------------------------------------------------------------------------

PrismaticJoint::PrismaticJoint(const std::vector<RigidBody>& bodies, int a, int b, const Vec3& world_anchor,
                               const Vec3& world_axis, RowParameters p)
    : Joint(BodyFrame::from_world(bodies, a, world_anchor, frame_from_axis(world_axis)),
            BodyFrame::from_world(bodies, b, world_anchor, frame_from_axis(world_axis)), p) {
  check_body(bodies, a);
  check_body(bodies, b);
}

void PrismaticJoint::add_rows(const std::vector<RigidBody>& bodies, std::vector<ConstraintRow>& rows) {
  begin_rows(rows);
  const Vec3 pa = a_.world_anchor(bodies);
  const Vec3 pb = b_.world_anchor(bodies);
  const Mat3 fa = a_.world_axes(bodies);
  const Mat3 fb = b_.world_axes(bodies);
  // no motion across the axis: x_a·(p_b - p_a) = 0, y_a·(p_b - p_a) = 0 (a's point at p_b)
  for (int k = 0; k < 2; ++k) {
    add_joint_row(rows, point_row(bodies, a_, b_, pb, pb, fa.col(k)), RowUnit::length, fa.col(k).dot(pb - pa));
  }
  // no rotation: y_a·z_b = 0, z_a·x_b = 0, x_a·y_b = 0
  for (int k = 0; k < 3; ++k) {
    const Vec3 u = fa.col((k + 1) % 3);
    const Vec3 w = fb.col((k + 2) % 3);
    add_joint_row(rows, dot_row(a_, b_, u, w), RowUnit::angle, u.dot(w));
  }
  add_motor_and_limits(bodies, rows);
}

double PrismaticJoint::coordinate(const std::vector<RigidBody>& bodies) const {
  return a_.world_axes(bodies).col(2).dot(b_.world_anchor(bodies) - a_.world_anchor(bodies));
}

ConstraintRow PrismaticJoint::coordinate_row(const std::vector<RigidBody>& bodies) const {
  const Vec3 pb = b_.world_anchor(bodies);
  return point_row(bodies, a_, b_, pb, pb, a_.world_axes(bodies).col(2));
}

// --- lock -------------------------------------------------------------------------------------

LockJoint::LockJoint(const std::vector<RigidBody>& bodies, int a, int b, const Vec3& world_anchor, RowParameters p)
    : Joint(BodyFrame::from_world(bodies, a, world_anchor, Mat3::Identity()),
            BodyFrame::from_world(bodies, b, world_anchor, Mat3::Identity()), p) {
  check_body(bodies, a);
  check_body(bodies, b);
}

void LockJoint::reanchor(const std::vector<RigidBody>& bodies, const Vec3& world_anchor) {
  a_ = BodyFrame::from_world(bodies, a_.body, world_anchor, Mat3::Identity());
  b_ = BodyFrame::from_world(bodies, b_.body, world_anchor, Mat3::Identity());
}

void LockJoint::add_rows(const std::vector<RigidBody>& bodies, std::vector<ConstraintRow>& rows) {
  begin_rows(rows);
  add_point_rows(bodies, rows);
  const Mat3 fa = a_.world_axes(bodies);
  const Mat3 fb = b_.world_axes(bodies);
  for (int k = 0; k < 3; ++k) {
    const Vec3 u = fa.col((k + 1) % 3);
    const Vec3 w = fb.col((k + 2) % 3);
    add_joint_row(rows, dot_row(a_, b_, u, w), RowUnit::angle, u.dot(w));
  }
}

// --- cylinder ---------------------------------------------------------------------------------

CylinderJoint::CylinderJoint(const std::vector<RigidBody>& bodies, int a, const Vec3& world_pin_a, int b,
                             const Vec3& world_pin_b, RowParameters p)
    : Joint(BodyFrame::from_world(bodies, a, world_pin_a, Mat3::Identity()),
            BodyFrame::from_world(bodies, b, world_pin_b, Mat3::Identity()), p) {
  check_body(bodies, a);
  check_body(bodies, b);
  if ((world_pin_b - world_pin_a).norm() <= 0.0) throw Error("cylinder joint: the two pins coincide");
}

void CylinderJoint::add_rows(const std::vector<RigidBody>& bodies, std::vector<ConstraintRow>& rows) {
  begin_rows(rows);
  add_motor_and_limits(bodies, rows);
}

double CylinderJoint::coordinate(const std::vector<RigidBody>& bodies) const {
  return (b_.world_anchor(bodies) - a_.world_anchor(bodies)).norm();
}

ConstraintRow CylinderJoint::coordinate_row(const std::vector<RigidBody>& bodies) const {
  const Vec3 pa = a_.world_anchor(bodies);
  const Vec3 pb = b_.world_anchor(bodies);
  return point_row(bodies, a_, b_, pa, pb, (pb - pa).normalized());
}

void Joint::save_state(ByteWriter& w) const {
  Constraint::save_state(w);
  w.u8(motor.enabled ? 1 : 0);
  w.f64(motor.target_speed);
  w.f64(motor.force_min);
  w.f64(motor.force_max);
  w.f64(motor.viscous_compliance);
  w.f64(motor_force_);
  w.f64(limit_force_);
  w.f64(position_violation_);
  w.f64(angle_violation_);
}

void Joint::restore_state(ByteReader& r) {
  Constraint::restore_state(r);
  motor.enabled = r.u8("joint motor") != 0;
  motor.target_speed = r.f64("joint motor");
  motor.force_min = r.f64("joint motor");
  motor.force_max = r.f64("joint motor");
  motor.viscous_compliance = r.f64("joint motor");
  motor_force_ = r.f64("joint forces");
  limit_force_ = r.f64("joint forces");
  position_violation_ = r.f64("joint violations");
  angle_violation_ = r.f64("joint violations");
}

}  // namespace talus::vehicle
