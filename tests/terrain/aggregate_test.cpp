// terrain/aggregate: the aggregate of a set of particles against the rigid-body sums worked by hand
// (mass, centre, momentum, parallel-axis inertia, spin from the angular momentum), its principal
// axes, and the zone's members.
#include "terrain/aggregate.hpp"

#include <gtest/gtest.h>

#include <random>

namespace talus {
namespace {

// two equal spheres at (±a, 0, 1) moving at (0, ±u, 0): at rest as a whole, spinning about z at
// 2 m a u / I_zz with I_zz = 2 (2/5 m r^2 + m a^2)
TEST(Aggregate, TwoOrbitingSpheresSpinAboutTheirCentre) {
  const double a = 0.3, u = 0.5, r = 0.1, m = 10.0;
  Particles p;
  p.add(Vec3(a, 0, 1), r, 2590.0);
  p.add(Vec3(-a, 0, 1), r, 2590.0);
  p.velocity[0] = Vec3(0, u, 0);
  p.velocity[1] = Vec3(0, -u, 0);
  p.add(Vec3(5, 5, 5), r, 2590.0);  // not a member
  const Aggregate g = aggregate_of(p, {m, m, 99.0}, {0, 1});
  EXPECT_EQ(g.particles, 2);
  EXPECT_DOUBLE_EQ(g.mass, 2 * m);
  EXPECT_LT((g.centre - Vec3(0, 0, 1)).norm(), 1e-15);
  EXPECT_LT(g.velocity.norm(), 1e-15);
  const double izz = 2 * (0.4 * m * r * r + m * a * a);
  EXPECT_NEAR(g.inertia(2, 2), izz, 1e-12);
  EXPECT_NEAR(g.inertia(0, 0), 2 * 0.4 * m * r * r, 1e-12);
  EXPECT_NEAR(g.omega.z(), 2 * m * a * u / izz, 1e-12);
  EXPECT_NEAR(g.omega.head<2>().norm(), 0.0, 1e-12);
}

// an inertia made from known principal axes and moments, turned by a fresh random rotation: the
// axes come back (up to their fixed signs), in ascending order, right-handed, and rebuild it
TEST(Aggregate, PrincipalAxesOfARotatedInertiaComeBack) {
  const std::uint64_t seed = std::random_device{}();
  SCOPED_TRACE("seed " + std::to_string(seed));
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int draw = 0; draw < 50; ++draw) {
    const Eigen::Quaterniond turn = Eigen::Quaterniond(u(rng), u(rng), u(rng), u(rng)).normalized();
    const Vec3 moments(1.0 + 2.0 * std::abs(u(rng)), 4.0 + std::abs(u(rng)),
                       6.0 + std::abs(u(rng)));
    const Eigen::Matrix3d R = turn.toRotationMatrix();
    const Eigen::Matrix3d inertia = R * moments.asDiagonal() * R.transpose();
    const PrincipalAxes axes = principal_axes(inertia);
    EXPECT_LT((axes.moments - moments).norm(), 1e-9 * moments.norm()) << draw;
    const Eigen::Matrix3d A = axes.orientation.toRotationMatrix();
    EXPECT_NEAR(A.determinant(), 1.0, 1e-12) << draw;
    EXPECT_LT((A * axes.moments.asDiagonal() * A.transpose() - inertia).norm(), 1e-9) << draw;
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(std::abs(A.col(c).dot(R.col(c))), 1.0, 1e-9) << draw;
    // the sign convention: the first two axes' largest world component is positive
    for (int c = 0; c < 2; ++c) {
      Eigen::Index largest = 0;
      A.col(c).cwiseAbs().maxCoeff(&largest);
      EXPECT_GT(A(largest, c), 0.0) << draw;
    }
    // the same inertia, the same frame
    EXPECT_EQ(principal_axes(inertia).orientation.coeffs(), axes.orientation.coeffs());
  }
  // no members: no inertia, the identity
  const PrincipalAxes none = principal_axes(Eigen::Matrix3d::Zero());
  EXPECT_EQ(none.orientation.coeffs(), Eigen::Quaterniond::Identity().coeffs());
  EXPECT_EQ(none.moments, Vec3::Zero());
}

// the bucket's payload welded to a free 'bucket': a push accelerates the two together (its
// inertia), and under gravity a push of the two bodies' weight holds them still (its weight comes
// through gravity, no external wrench); with nothing held it is the 1 kg stand-in
TEST(BucketPayload, ALockedLoadAddsItsInertiaAndItsWeight) {
  const double m_bucket = 1000.0, m_load = 500.0, h = 0.01;
  const auto velocity_after_push = [&](bool load, const Vec3& gravity, const Vec3& force,
                                       const Vec3& offset = Vec3::Zero()) {
    vehicle::MultibodySystem system;
    system.set_gravity(gravity);
    vehicle::RigidBody bucket;
    bucket.name = "bucket";
    bucket.mass = m_bucket;
    bucket.inertia = Eigen::Matrix3d::Identity() * 200.0;
    bucket.position = Vec3(2.0, 0.0, 1.0);
    const int b = system.add_body(bucket);
    BucketPayload payload(system, b);
    Particles p;
    p.add(bucket.position + offset, 0.3, 2590.0);  // the load's centre (on the bucket's)
    payload.update(load ? aggregate_of(p, {m_load}, {0}) : aggregate_of(p, {m_load}, {}));
    Vec6 push = Vec6::Zero();
    push.head<3>() = force;
    system.set_external_wrench(b, push);
    system.step(h);
    return system.body(b).velocity;
  };
  const Vec3 f(0.0, 0.0, 3000.0);
  // inertia: the pair moves at F h / (M + m); the idle stand-in adds 1 kg
  EXPECT_NEAR(velocity_after_push(true, Vec3::Zero(), f).z(), f.z() * h / (m_bucket + m_load),
              1e-3 * f.z() * h / (m_bucket + m_load));
  EXPECT_NEAR(velocity_after_push(false, Vec3::Zero(), f).z(), f.z() * h / (m_bucket + 1.0),
              1e-3 * f.z() * h / m_bucket);
  // a load whose centre moved since the lock was made is held where it now is (the lock
  // re-anchored), not pulled back to where the lock began
  EXPECT_LT(velocity_after_push(true, Vec3::Zero(), Vec3::Zero(), Vec3(0.5, 0.2, 0.3)).norm(),
            1e-9);
  // weight: gravity on both bodies, balanced by a push of (M + m) g on the bucket alone (to the
  // lock's compliance, which lets the load sag by micrometres a step), not by M g
  const Vec3 g(0.0, 0.0, -9.81);
  const double unbalanced = m_load * 9.81 * h / (m_bucket + m_load);  // [m/s] without its weight
  EXPECT_LT(velocity_after_push(true, g, -(m_bucket + m_load) * g).norm(), 1e-3 * unbalanced);
  EXPECT_NEAR(velocity_after_push(true, g, -m_bucket * g).z(), -unbalanced, 1e-3 * unbalanced);
}

// one sphere: its own mass, place, velocity and spin
TEST(Aggregate, OneSphereIsItself) {
  Particles p;
  p.add(Vec3(1, 2, 3), 0.2, 2590.0);
  p.velocity[0] = Vec3(0.1, 0.2, 0.3);
  p.omega[0] = Vec3(1, -2, 3);
  const Aggregate g = aggregate_of(p, {7.0}, {0});
  EXPECT_DOUBLE_EQ(g.mass, 7.0);
  EXPECT_EQ(g.centre, Vec3(1, 2, 3));
  EXPECT_LT((g.velocity - Vec3(0.1, 0.2, 0.3)).norm(), 1e-15);
  EXPECT_LT((g.omega - Vec3(1, -2, 3)).norm(), 1e-12);
  EXPECT_TRUE(aggregate_of(p, {7.0}, {}).mass == 0.0);
}

}  // namespace
}  // namespace talus
