// The stepper as a whole: free fall, momentum, and the mobility coupling hook.
#include "vehicle/multibody.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <string>

#include "host/error.hpp"
#include "vehicle/joints.hpp"

namespace talus::vehicle {
namespace {

TEST(MultibodyTest, FreeFallIsSymplecticEuler) {
  MultibodySystem s;
  RigidBody b;
  b.mass = 2.0;
  const int i = s.add_body(b);
  for (int k = 0; k < 100; ++k) s.step(0.01);
  // v_n = -g n h, z_n = -g h² n(n+1)/2
  EXPECT_NEAR(s.body(i).velocity.z(), -9.81, 1e-12);
  EXPECT_NEAR(s.body(i).position.z(), -9.81 * 1e-4 * 100 * 101 / 2, 1e-10);
}

// a non-finite velocity stops the step with a message naming the time, not a body moved to NaN
TEST(MultibodyTest, NonFiniteStateStopsWithTheTime) {
  MultibodySystem s;
  RigidBody b;
  b.mass = 2.0;
  const int i = s.add_body(b);
  s.step(0.01);
  s.body(i).velocity.x() = std::numeric_limits<double>::quiet_NaN();
  try {
    s.step(0.01);
    FAIL() << "expected an Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("non-finite at t = 0.01 s"), std::string::npos)
        << e.what();
  }
  EXPECT_TRUE(s.body(i).position.allFinite());
}

TEST(MultibodyTest, SpinningBodyKeepsUnitQuaternionAndAngle) {
  MultibodySystem s;
  s.set_gravity(Vec3::Zero());
  RigidBody b;
  b.angular_velocity = Vec3(0, 0, 2.0);
  const int i = s.add_body(b);
  for (int k = 0; k < 1000; ++k) s.step(0.001);
  EXPECT_NEAR(s.body(i).orientation.norm(), 1.0, 1e-14);
  const double angle = Eigen::AngleAxisd(s.body(i).orientation).angle();
  EXPECT_NEAR(angle, 2.0, 1e-9);
}

// an arm on a hinge with a motor, a second arm on a hinge: the mobility of the tip body matches a
// finite difference of re-solving the same step with a small extra impulse
TEST(MultibodyTest, MobilityMatchesFiniteDifference) {
  MultibodySystem s;
  RigidBody arm;
  arm.name = "arm";
  arm.mass = 50.0;
  arm.inertia = Vec3(1.0, 4.0, 4.5).asDiagonal();
  arm.position = Vec3(1.0, 0, 0);
  const int a = s.add_body(arm);
  RigidBody tip = arm;
  tip.name = "tip";
  tip.mass = 20.0;
  tip.position = Vec3(2.5, 0, 0.1);
  const int b = s.add_body(tip);
  auto& j0 = s.add_constraint(std::make_unique<HingeJoint>(s.bodies(), kWorld, a, Vec3::Zero(), Vec3::UnitY()));
  j0.motor.enabled = true;
  j0.motor.force_min = -1e5;
  j0.motor.force_max = 1e5;
  s.add_constraint(std::make_unique<HingeJoint>(s.bodies(), a, b, Vec3(2.0, 0, 0), Vec3::UnitY()));
  const double h = 0.01;
  s.assemble(h);
  s.solve();
  const Mat6 W = s.mobility(b);
  const Vec6 v0 = s.solved_twist(b);
  const double p = 1e-3;  // N s
  Mat6 fd;
  for (int k = 0; k < 6; ++k) {
    s.set_external_wrench(b, Vec6::Unit(k) * (p / h));
    s.solve();
    fd.col(k) = (s.solved_twist(b) - v0) / p;
  }
  EXPECT_LT((W - fd).cwiseAbs().maxCoeff(), 1e-6 * W.cwiseAbs().maxCoeff());
  EXPECT_LT((W - W.transpose()).cwiseAbs().maxCoeff(), 1e-9 * W.cwiseAbs().maxCoeff());
  // the tip cannot move along y except by the joints' compliance (ε/h² per joint, ~1e-6):
  // below 1e-4 of a free body's 1/m
  EXPECT_LT(std::abs(W(1, 1)), 1e-4 / tip.mass);
  EXPECT_GT(W(0, 0), 0.0);
}

}  // namespace
}  // namespace talus::vehicle
