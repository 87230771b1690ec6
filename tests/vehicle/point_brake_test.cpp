// vehicle/point_brake: a body pushed along the brake's direction stays put below the bound and
// then accelerates with what exceeds it; pushed the other way it moves freely.
#include "vehicle/point_brake.hpp"

#include <gtest/gtest.h>

#include "vehicle/multibody.hpp"

namespace talus::vehicle {
namespace {

// a 100 kg body without gravity, pushed along x by `push` [N] for 0.5 s against a brake of
// `bound` [N] on its point (0.2, 0, 0): its velocity along x at the end, and the brake's force
std::pair<double, double> pushed(double push, double bound) {
  MultibodySystem s;
  s.set_gravity(Vec3::Zero());
  RigidBody b;
  b.mass = 100.0;
  b.inertia = Mat3::Identity() * 10.0;
  const int i = s.add_body(b);
  auto& brake = s.add_constraint(std::make_unique<PointBrake>(i));
  for (int k = 0; k < 50; ++k) {
    brake.set(Vec3(0.2, 0.0, 0.0), Vec3::UnitX(), bound);
    Vec6 w = Vec6::Zero();
    w(0) = push;
    s.set_external_wrench(i, w);
    s.step(0.01);
  }
  return {s.body(i).velocity.x(), brake.force()};
}

TEST(PointBrake, HoldsBelowItsBoundAndLetsGoAboveIt) {
  const auto held = pushed(800.0, 1000.0);
  EXPECT_NEAR(held.first, 0.0, 1e-6);
  EXPECT_NEAR(held.second, 800.0, 1e-3);
  const auto slipping = pushed(1500.0, 1000.0);
  EXPECT_NEAR(slipping.first, (1500.0 - 1000.0) / 100.0 * 0.5, 1e-3);
  EXPECT_NEAR(slipping.second, 1000.0, 1e-3);
  const auto backwards = pushed(-300.0, 1000.0);  // the brake resists one way only
  EXPECT_NEAR(backwards.first, -300.0 / 100.0 * 0.5, 1e-6);
  EXPECT_NEAR(backwards.second, 0.0, 1e-9);
  const auto released = pushed(300.0, 0.0);  // a zero bound carries nothing
  EXPECT_NEAR(released.first, 300.0 / 100.0 * 0.5, 1e-6);
}

}  // namespace
}  // namespace talus::vehicle
