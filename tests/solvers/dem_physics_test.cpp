// Physics anchors of the DEM core (SPEC §7): Hertz impact, a sphere at rest, on an incline
// below and above the friction angle, and rolling without slipping. Each runs the OpenCL
// pipeline on the default device and compares a measured value with its analytic solution.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "solvers/dem_world.hpp"

namespace talus {
namespace {

constexpr double kGravity = 9.81;  // [m/s^2]

// one sphere of diameter d resting on (or just above) a plane through the origin with normal n
struct OneSphere {
  OneSphere(Device& dev, const Material& m, const DemSettings& s, const Vec3& plane_normal, double d)
      : world(dev, m, s, Bounds{Vec3(-20, -1, -1), Vec3(20, 1, 1)},
              {StaticGeom::plane(Vec3::Zero(), plane_normal)}) {
    Particles p;
    p.add(plane_normal.normalized() * 0.5 * d, 0.5 * d, m.density);
    world.set_particles(p);
  }
  Vec3 x() const { return world.particles().position[0]; }
  Vec3 v() const { return world.particles().velocity[0]; }
  DemWorld world;
};

// gravity tilted by theta about y: the same as a plane inclined by theta
Vec3 tilted_gravity(double theta) {
  return Vec3(kGravity * std::sin(theta), 0.0, -kGravity * std::cos(theta));
}

TEST(DemPhysics, SphereAtRestOnPlaneStaysPut) {
  Device dev;
  Material m = gravel();
  DemSettings s;
  s.dt = 1e-2;
  s.iterations = 20;
  const double d = 0.1;
  OneSphere one(dev, m, s, Vec3::UnitZ(), d);
  Vec3 x0 = one.x();
  for (int i = 0; i < 1000; ++i) one.world.step();  // 10 s
  double drift = (one.x() - x0).head<2>().norm();
  std::printf("sphere on a plane: lateral drift %.3e D over 10 s\n", drift / d);
  EXPECT_LT(drift, 1e-4 * d);
}

// rolling blocked (large rolling resistance) so the sphere behaves as a block: it stays put
// below the friction angle atan(mu) and slides with a = g (sin - mu cos) above it
TEST(DemPhysics, InclineBelowFrictionAngleHolds) {
  Device dev;
  Material m = gravel();
  m.rolling = 100.0;
  m.ground_rolling = m.rolling;  // the sphere rests on a plane
  DemSettings s;
  s.dt = 1e-2;
  s.iterations = 30;
  s.gravity = tilted_gravity(0.8 * std::atan(m.friction));
  const double d = 0.1;
  OneSphere one(dev, m, s, Vec3::UnitZ(), d);
  for (int i = 0; i < 100; ++i) one.world.step();  // the contact's compliance settles first
  Vec3 x0 = one.x();
  for (int i = 0; i < 1000; ++i) one.world.step();  // 10 s
  double drift = std::abs(one.x().x() - x0.x());  // along the slope
  std::printf("incline at 0.8 friction angle: drift %.3e D over 10 s\n", drift / d);
  EXPECT_LT(drift, 1e-4 * d);
}

TEST(DemPhysics, InclineAboveFrictionAngleSlidesAtAnalyticAcceleration) {
  Device dev;
  Material m = gravel();
  m.rolling = 100.0;
  m.ground_rolling = m.rolling;  // the sphere rests on a plane
  DemSettings s;
  s.dt = 1e-3;
  s.iterations = 30;
  double theta = 1.5 * std::atan(m.friction);
  s.gravity = tilted_gravity(theta);
  const double d = 0.1;
  OneSphere one(dev, m, s, Vec3::UnitZ(), d);
  for (int i = 0; i < 100; ++i) one.world.step();  // contact established
  double v0 = one.v().x();
  const int steps = 1000;
  for (int i = 0; i < steps; ++i) one.world.step();
  double a = (one.v().x() - v0) / (steps * s.dt);
  double expected = kGravity * (std::sin(theta) - m.friction * std::cos(theta));
  std::printf("sliding: a = %.5f m/s^2, analytic %.5f (%.2f%%)\n", a, expected, 100 * (a / expected - 1));
  EXPECT_NEAR(a, expected, 0.02 * expected);
}

// no rolling resistance, enough friction: a sphere rolls without slipping, a = 5/7 g sin
TEST(DemPhysics, SphereRollsWithoutSlippingAtFiveSevenths) {
  Device dev;
  Material m = gravel();
  m.rolling = 0.0;
  m.ground_rolling = m.rolling;  // the sphere rests on a plane
  m.friction = 1.0;
  DemSettings s;
  s.dt = 1e-3;
  s.iterations = 30;
  double theta = 20.0 * M_PI / 180.0;
  s.gravity = tilted_gravity(theta);
  OneSphere one(dev, m, s, Vec3::UnitZ(), 0.1);
  for (int i = 0; i < 100; ++i) one.world.step();
  double v0 = one.v().x();
  const int steps = 1000;
  for (int i = 0; i < steps; ++i) one.world.step();
  double a = (one.v().x() - v0) / (steps * s.dt);
  double expected = 5.0 / 7.0 * kGravity * std::sin(theta);
  std::printf("rolling: a = %.5f m/s^2, analytic %.5f (%.2f%%)\n", a, expected, 100 * (a / expected - 1));
  EXPECT_NEAR(a, expected, 0.02 * expected);
}

// rolling resistance mu_r R* lambda_n holds a sphere on a slope with tan(theta) < mu_r
// (torque balance about the centre: friction r m g sin = resisting torque <= mu_r r m g cos)
TEST(DemPhysics, RollingResistanceHoldsBelowItsAngle) {
  Device dev;
  Material m = gravel();
  m.rolling = 0.1;
  m.ground_rolling = m.rolling;  // the sphere rests on a plane
  DemSettings s;
  s.dt = 5e-3;
  s.iterations = 30;
  const double d = 0.1;
  for (double factor : {0.7, 1.5}) {
    s.gravity = tilted_gravity(std::atan(factor * m.rolling));
    OneSphere one(dev, m, s, Vec3::UnitZ(), d);
    for (int i = 0; i < 20; ++i) one.world.step();  // the contact's compliance settles first
    Vec3 x0 = one.x();
    for (int i = 0; i < 400; ++i) one.world.step();  // 2 s
    double moved = std::abs(one.x().x() - x0.x());  // along the slope
    std::printf("rolling resistance, tan(theta) = %.2f mu_r: moved %.3e D in 2 s\n", factor, moved / d);
    if (factor < 1.0) EXPECT_LT(moved, 1e-4 * d);
    else EXPECT_GT(moved, 0.1 * d);
  }
}


// does a sphere hang from a fixed one above it for 2 s, given the soil's tensile strength [Pa]?
// (the bond holds F_c = kRumpfPerR2 cohesion R*^2, the sphere weighs m g)
bool hangs(Device& dev, double cohesion, double d) {
  Material m = gravel();
  m.cohesion = cohesion;
  DemSettings s;
  s.dt = 1e-2;
  s.iterations = 30;
  DemWorld world(dev, m, s, Bounds{Vec3(-1, -1, -1), Vec3(1, 1, 1)}, {});
  Particles p;
  p.add(Vec3(0, 0, 0.5 * d), 0.5 * d, m.density);
  p.add(Vec3(0, 0, -0.5 * d), 0.5 * d, m.density);
  p.inv_mass[0] = 0.0;  // the upper one is fixed
  p.inv_inertia[0] = 0.0;
  world.set_particles(p);
  for (int i = 0; i < 200; ++i) world.step();
  return world.particles().position[1].z() > -d;  // fell less than half a diameter
}

// the weakest cohesion that holds a sphere hanging under another: the bond F_c must carry its
// weight m g, so cohesion* = m g / (kRumpfPerR2 R*^2) with R* = d/4. Bisection on the measured
// outcome, to 2 %
TEST(DemPhysics, CohesiveBondHoldsItsWeightAtRumpfsStrength) {
  Device dev;
  const double d = 0.04;
  const double mass = gravel().density * M_PI * d * d * d / 6.0;
  const double r_star = 0.25 * d;
  const double expected = mass * kGravity / (kRumpfPerR2 * r_star * r_star);
  EXPECT_FALSE(hangs(dev, 0.0, d));  // dry gravel: it falls
  double lo = 0.25 * expected, hi = 4.0 * expected;
  ASSERT_FALSE(hangs(dev, lo, d));
  ASSERT_TRUE(hangs(dev, hi, d));
  while (hi / lo > 1.02) {
    const double mid = std::sqrt(lo * hi);
    (hangs(dev, mid, d) ? hi : lo) = mid;
  }
  const double measured = std::sqrt(lo * hi);
  std::printf("cohesion that holds a %.0f mm sphere: measured %.1f Pa, Rumpf bond %.1f Pa (%+.1f %%)\n", d * 1e3,
              measured, expected, 100.0 * (measured / expected - 1.0));
  EXPECT_NEAR(measured / expected, 1.0, 0.05);
}

}  // namespace
}  // namespace talus
