// Rigid-body helpers: frames and merged payload mass properties.
#include "vehicle/rigid_body.hpp"

#include <gtest/gtest.h>

namespace talus::vehicle {
namespace {

TEST(MultibodyRigidBodyTest, PointMassMergesByParallelAxis) {
  RigidBody b;
  b.mass = 2.0;
  b.inertia = Mat3::Identity();
  b.position = Vec3(0, 0, 0);
  add_point_mass(b, 2.0, Vec3(2, 0, 0));
  EXPECT_DOUBLE_EQ(b.mass, 4.0);
  EXPECT_TRUE(b.position.isApprox(Vec3(1, 0, 0)));
  // about the new centre: I + 2 (1² ) + 2 (1²) for y and z, I for x
  EXPECT_NEAR(b.inertia(0, 0), 1.0, 1e-12);
  EXPECT_NEAR(b.inertia(1, 1), 5.0, 1e-12);
  EXPECT_NEAR(b.inertia(2, 2), 5.0, 1e-12);
}

TEST(MultibodyRigidBodyTest, WorldLocalRoundTrip) {
  RigidBody b;
  b.position = Vec3(1, 2, 3);
  b.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Vec3(1, 1, 0).normalized()));
  const Vec3 p(0.3, -0.2, 0.9);
  EXPECT_TRUE(b.point_to_local(b.point_to_world(p)).isApprox(p, 1e-14));
  EXPECT_NEAR((b.point_to_world(p) - b.position).norm(), p.norm(), 1e-14);
}

}  // namespace
}  // namespace talus::vehicle
