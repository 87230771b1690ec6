// Joints, motors and range limits on small systems with known answers.
#include "vehicle/joints.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "vehicle/multibody.hpp"

namespace talus::vehicle {
namespace {

constexpr double kG = 9.81;

RigidBody box(const std::string& name, double m, const Vec3& at) {
  RigidBody b;
  b.name = name;
  b.mass = m;
  b.inertia = Mat3::Identity() * m * 0.1;  // kg m², a 0.77 m cube roughly
  b.position = at;
  return b;
}

// a physical pendulum on a hinge: period against 2π sqrt(I_pivot / (m g d)), anchor held
TEST(JointTest, HingePendulumPeriodAndAnchor) {
  MultibodySystem s;
  const double m = 5.0, d = 1.0;
  const int b = s.add_body(box("bob", m, Vec3(0.2 * d, 0, -d * std::cos(0.2))));
  s.body(b).position = Vec3(d * std::sin(0.05), 0, -d * std::cos(0.05));
  auto& hinge = s.add_constraint(std::make_unique<HingeJoint>(s.bodies(), kWorld, b, Vec3::Zero(), Vec3::UnitY()));
  const double h = 0.001;
  double worst = 0.0, last_cross = -1.0, period = 0.0;
  double prev_x = s.body(b).position.x();
  int crossings = 0;
  for (int k = 0; k < 6000; ++k) {
    s.step(h);
    worst = std::max(worst, s.max_joint_position_violation());
    const double x = s.body(b).position.x();
    if (prev_x > 0.0 && x <= 0.0) {  // downward crossing of x = 0 once per period
      if (last_cross >= 0.0) {
        period = s.time() - last_cross;
        ++crossings;
      }
      last_cross = s.time();
    }
    prev_x = x;
  }
  const double expected = 2 * M_PI * std::sqrt((m * 0.1 + m * d * d) / (m * kG * d));
  ASSERT_GE(crossings, 2);
  EXPECT_NEAR(period, expected, 0.01 * expected);
  EXPECT_LT(worst, 1e-6);  // m
  (void)hinge;
}

// a body on an inclined prismatic joint slides with a = g (axis · down); no rotation
TEST(JointTest, PrismaticSlideAcceleration) {
  MultibodySystem s;
  const int b = s.add_body(box("slider", 3.0, Vec3::Zero()));
  const Vec3 axis = Vec3(1.0, 0.0, -1.0).normalized();
  auto& p = s.add_constraint(std::make_unique<PrismaticJoint>(s.bodies(), kWorld, b, Vec3::Zero(), axis));
  const double h = 0.01;
  for (int k = 0; k < 100; ++k) s.step(h);
  const double a = kG * axis.dot(Vec3(0, 0, -1));
  // symplectic Euler: s_n = a h² n (n + 1) / 2
  const double expected = a * h * h * 100 * 101 / 2;
  EXPECT_NEAR(p.coordinate(s.bodies()), expected, 1e-6 * expected);
  EXPECT_LT(s.body(b).angular_velocity.norm(), 1e-9);
  EXPECT_LT(s.max_joint_position_violation(), 1e-8);
}

// a locked body and a ball-jointed chain under gravity: the lock does not move, the ball holds
TEST(JointTest, LockAndBallHoldUnderGravity) {
  MultibodySystem s;
  const int a = s.add_body(box("locked", 100.0, Vec3(0, 0, 1)));
  const int b = s.add_body(box("hanging", 20.0, Vec3(0.5, 0, 0.2)));
  s.add_constraint(std::make_unique<LockJoint>(s.bodies(), kWorld, a, Vec3(0, 0, 1)));
  s.add_constraint(std::make_unique<BallJoint>(s.bodies(), a, b, Vec3(0, 0, 0.8)));
  double worst = 0.0;
  for (int k = 0; k < 500; ++k) {
    s.step(0.01);
    worst = std::max(worst, s.max_joint_position_violation());
  }
  // static deflection of the lock under its load is (m g) ε: 1.2 kN x 1e-10 m/N
  EXPECT_LT((s.body(a).position - Vec3(0, 0, 1)).norm(), 1e-6);
  // the swinging ball joint drifts by the first-order stepper's O(h² ω² r) ≈ 1e-4 ω² m per step
  // before the SPOOK stabilisation pulls it back: under 1 mm at h = 10 ms
  EXPECT_LT(worst, 1e-3);
}

// a lifting motor: force never leaves [0, f_max]; feasible target speed met; infeasible stalls
TEST(MotorTest, ForceRangeAndTargetSpeed) {
  for (const double mass : {100.0, 1000.0}) {
    MultibodySystem s;
    const int b = s.add_body(box("load", mass, Vec3::Zero()));
    auto& p = s.add_constraint(std::make_unique<PrismaticJoint>(s.bodies(), kWorld, b, Vec3::Zero(), Vec3::UnitZ()));
    p.motor.enabled = true;
    p.motor.target_speed = 0.5;  // m/s up
    p.motor.force_min = 0.0;
    p.motor.force_max = 5000.0;  // N: lifts 100 kg (981 N), not 1000 kg (9810 N)
    const bool feasible = mass * kG < p.motor.force_max;
    const double h = 0.005;
    int met = 0;
    for (int k = 0; k < 200; ++k) {
      // the force that reaches the target speed within this step, if the range allows it
      const double needed = mass * (0.5 - s.body(b).velocity.z()) / h + mass * kG;
      s.step(h);
      ASSERT_GE(p.motor_force(), p.motor.force_min - 1e-9);
      ASSERT_LE(p.motor_force(), p.motor.force_max + 1e-9);
      if (needed <= p.motor.force_max) {
        EXPECT_NEAR(s.body(b).velocity.z(), 0.5, 1e-6) << "step " << k;
        ++met;
      }
    }
    if (feasible) {
      EXPECT_GT(met, 190);
    }
    if (!feasible) {
      // at its force limit the motor stalls: the load falls with (m g - f_max)/m
      EXPECT_NEAR(p.motor_force(), p.motor.force_max, 1e-6);
      const double a = (mass * kG - p.motor.force_max) / mass;
      EXPECT_NEAR(s.body(b).velocity.z(), -a * s.time(), 1e-3 * a * s.time());
    }
  }
}

// an angular motor drives a hinge into its range limit; the limit holds to the damping-time scale
TEST(MotorTest, HingeMotorStopsAtRangeLimit) {
  MultibodySystem s;
  s.set_gravity(Vec3::Zero());
  const int b = s.add_body(box("arm", 10.0, Vec3(0.5, 0, 0)));
  auto& j = s.add_constraint(std::make_unique<HingeJoint>(s.bodies(), kWorld, b, Vec3::Zero(), Vec3::UnitZ()));
  j.motor.enabled = true;
  j.motor.target_speed = 1.0;  // rad/s
  j.motor.force_min = -50.0;
  j.motor.force_max = 50.0;  // N m
  j.range.enabled = true;
  j.range.lower = -0.3;
  j.range.upper = 0.6;  // rad
  for (int k = 0; k < 300; ++k) s.step(0.01);
  EXPECT_NEAR(j.coordinate(s.bodies()), 0.6, 1e-4);
  // the motor pushes at its limit into the stop, which pushes back equally
  EXPECT_NEAR(j.motor_force(), 50.0, 1e-6);
  EXPECT_NEAR(j.limit_force(), -50.0, 1e-3);
}

}  // namespace
}  // namespace talus::vehicle
