// vehicle/plane_contact: a block on an inclined plane held by a four-point patch. Below the
// friction angle it stays, with the normal force m g cos(theta); above it, it slides down with
// the acceleration g (sin theta - mu cos theta); an inactive patch lets it fall freely; a point
// with nothing under it (gap +infinity) carries nothing, so a block on half its patch tips.
#include "vehicle/plane_contact.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>

#include "host/error.hpp"
#include "vehicle/multibody.hpp"

namespace talus::vehicle {
namespace {

struct Incline {
  double speed = 0.0;         // down the slope after the run [m/s]
  double normal = 0.0;        // the patch's normal force [N]
  double acceleration = 0.0;  // down the slope over the last half of the run [m/s^2]
  Vec3 force = Vec3::Zero();  // on the block
};

// a 100 kg block (1 m cube) on the world's plane tilted theta about y, patch at its four bottom
// corners, friction mu; 1 s of steps of 10 ms
Incline on_incline(double theta_deg, double mu, bool active = true) {
  const double theta = theta_deg * M_PI / 180.0;
  const Vec3 n(std::sin(theta), 0.0, std::cos(theta));      // up out of the plane
  const Vec3 down(std::cos(theta), 0.0, -std::sin(theta));  // down the slope (towards +x)
  MultibodySystem s;
  RigidBody block;
  block.mass = 100.0;
  block.inertia = Mat3::Identity() * (100.0 / 6.0);
  block.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(theta, Vec3::UnitY()));
  block.position = 0.5 * n;
  const int b = s.add_body(block);
  PlaneContactParameters p;
  p.stiffness = 1e8;
  p.friction = mu;
  auto& c = s.add_constraint(std::make_unique<PlaneContact>(kWorld, b, 4, p));
  c.name = "incline";
  Incline out;
  double v_half = 0.0;
  for (int k = 0; k < 100; ++k) {
    PlaneContactGeometry g;
    g.active = active;
    g.normal = n;
    for (double u : {-0.5, 0.5})
      for (double w : {-0.5, 0.5}) g.points.push_back(s.body(b).point_to_world(Vec3(u, w, -0.5)));
    // each corner's own gap from the plane through the origin
    for (const Vec3& x : g.points) g.gaps.push_back(x.dot(n));
    c.set_geometry(g);
    s.step(0.01);
    if (k == 49) v_half = s.body(b).velocity.dot(down);
  }
  out.speed = s.body(b).velocity.dot(down);
  out.normal = c.normal_force();
  out.acceleration = (out.speed - v_half) / 0.5;
  out.force = c.force_on_b();
  return out;
}

TEST(PlaneContact, ABlockHoldsBelowTheFrictionAngleAndSlidesAbove) {
  const double g = 9.81, m = 100.0;
  const Incline hold = on_incline(20.0, std::tan(30.0 * M_PI / 180.0));
  std::printf(
      "[ measured ] 20 deg, mu = tan 30 deg: speed %.2e m/s, normal %.1f N (m g cos = %.1f N)\n",
      hold.speed, hold.normal, m * g * std::cos(20.0 * M_PI / 180.0));
  EXPECT_LT(std::abs(hold.speed), 1e-4);
  EXPECT_NEAR(hold.normal, m * g * std::cos(20.0 * M_PI / 180.0), 1e-3 * m * g);
  // the patch carries the whole weight
  EXPECT_NEAR(hold.force.z(), m * g, 1e-3 * m * g);
  EXPECT_NEAR(hold.force.x(), 0.0, 1e-3 * m * g);

  const double mu = 0.2, theta = 30.0 * M_PI / 180.0;
  const Incline slide = on_incline(30.0, mu);
  const double expected = g * (std::sin(theta) - mu * std::cos(theta));
  std::printf("[ measured ] 30 deg, mu = 0.2: acceleration %.4f m/s^2 (g (sin - mu cos) = %.4f)\n",
              slide.acceleration, expected);
  EXPECT_NEAR(slide.acceleration, expected, 1e-3 * expected);

  const Incline fall = on_incline(30.0, mu, false);
  EXPECT_EQ(fall.normal, 0.0);
  EXPECT_NEAR(fall.acceleration, g * std::sin(theta),
              1e-6);  // free fall, along the slope's direction
}

// a 100 kg cube on level ground whose patch has its two corners at x = -0.5 over nothing (gap
// +infinity): the other two carry the whole weight and the cube tips about their edge (the
// terrain's support under a bucket whose heel hangs over the pit); with all four it stands still
TEST(PlaneContact, APointWithNothingUnderItCarriesNothing) {
  for (bool half : {false, true}) {
    MultibodySystem s;
    RigidBody block;
    block.mass = 100.0;
    block.inertia = Mat3::Identity() * (100.0 / 6.0);
    block.position = Vec3(0.0, 0.0, 0.5);
    const int b = s.add_body(block);
    PlaneContactParameters p;
    p.stiffness = 1e8;
    p.friction = 0.5;
    auto& c = s.add_constraint(std::make_unique<PlaneContact>(kWorld, b, 4, p));
    c.name = "ground";
    double fall = 0.0;
    for (int k = 0; k < 20; ++k) {
      PlaneContactGeometry g;
      g.active = true;
      for (double u : {-0.5, 0.5})
        for (double w : {-0.5, 0.5}) {
          const Vec3 x = s.body(b).point_to_world(Vec3(u, w, -0.5));
          g.points.push_back(x);
          g.gaps.push_back(half && u < 0.0 ? std::numeric_limits<double>::infinity() : x.z());
        }
      c.set_geometry(g);
      s.step(0.01);
    }
    fall = s.body(b).angular_velocity.y();
    std::printf("[ measured ] %s patch: spin about y %.3f 1/s, normal force %.1f N\n",
                half ? "half" : "whole", fall, c.normal_force());
    if (half) {
      // tipping towards -x: the spin about y is negative (x cross z = -y)
      EXPECT_LT(fall, -0.5);
    } else {
      EXPECT_NEAR(fall, 0.0, 1e-6);
      EXPECT_NEAR(c.normal_force(), 100.0 * 9.81, 1.0);
    }
  }
}

TEST(PlaneContact, APatchOfTheWrongSizeIsRefused) {
  PlaneContact c(kWorld, 0, 4, PlaneContactParameters{});
  PlaneContactGeometry g;
  g.points.assign(3, Vec3::Zero());
  g.gaps.assign(3, 0.0);
  EXPECT_THROW(c.set_geometry(g), Error);
  g.points.assign(4, Vec3::Zero());
  EXPECT_THROW(c.set_geometry(g), Error);  // three gaps for four points
  EXPECT_THROW(PlaneContact(kWorld, 0, 0, PlaneContactParameters{}), Error);
}

// a gap that is NaN or -infinity says nothing about where the plane is: refused (+infinity is
// "nothing under the point")
TEST(PlaneContact, AGapThatIsNaNOrMinusInfinityIsRefused) {
  PlaneContact c(kWorld, 0, 2, PlaneContactParameters{});
  PlaneContactGeometry g;
  g.points.assign(2, Vec3::Zero());
  for (double bad : {std::nan(""), -std::numeric_limits<double>::infinity()}) {
    g.gaps = {0.0, bad};
    EXPECT_THROW(c.set_geometry(g), Error) << bad;
  }
  g.gaps = {0.0, std::numeric_limits<double>::infinity()};
  EXPECT_NO_THROW(c.set_geometry(g));
}

// a stiffness of zero is an infinite compliance in the machine's system even while the patch is
// inactive (the type-G aggregate's interfaces before the terrain's first step had it, and the
// machine's first step lurched back): refused, as NaN is
TEST(PlaneContact, AStiffnessThatIsNotPositiveAndFiniteIsRefused) {
  for (double k : {0.0, -1.0, std::nan(""), std::numeric_limits<double>::infinity()}) {
    PlaneContactParameters p;
    p.stiffness = k;
    EXPECT_THROW(PlaneContact(kWorld, 0, 4, p), Error) << k;
    PlaneContact c(kWorld, 0, 4, PlaneContactParameters{});
    EXPECT_THROW(c.set_parameters(p), Error) << k;
  }
}

}  // namespace
}  // namespace talus::vehicle
