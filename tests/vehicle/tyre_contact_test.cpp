// One wheel on flat ground: static deflection from E w, and Coulomb friction at μ N.
#include "vehicle/tyre_contact.hpp"

#include <gtest/gtest.h>

#include <array>
#include <iostream>

#include "vehicle/multibody.hpp"

namespace talus::vehicle {
namespace {

TEST(TyreContactTest, StaticDeflectionIsWeightOverModulusTimesWidth) {
  MultibodySystem s;
  RigidBody w;
  w.mass = 3800.0;  // kg: a quarter of the machine on one wheel
  w.inertia = Vec3(82, 150, 82).asDiagonal();
  w.position = Vec3(0, 0, 0.695);
  const int i = s.add_body(w);
  TyreParameters p;  // paper: E = 1 MPa, μ = 2; width 0.52 m
  auto& t = s.add_constraint(std::make_unique<TyreContact>(i, Vec3::UnitY(), p));
  for (int k = 0; k < 1000; ++k) s.step(0.005);
  const double expected = w.mass * 9.81 / (p.elastic_modulus * p.width);
  std::cout << "[ measured ] deflection " << t.deflection() * 1e3 << " mm (m g / (E w) = " << expected * 1e3 << " mm)\n";
  EXPECT_NEAR(t.deflection(), expected, 0.01 * expected);
  EXPECT_NEAR(t.normal_force(), w.mass * 9.81, 1e-3 * w.mass * 9.81);
}

// a sideways force applied at the contact point (so the lone wheel has no moment to lean)
Vec6 push_at_contact(double force, double radius) {
  return (Vec6() << 0, force, 0, radius * force, 0, 0).finished();
}

TEST(TyreContactTest, FrictionSaturatesAtMuTimesNormal) {
  const TyreParameters p;  // μ = 2 (paper)
  const double m = 1000.0;
  // settle a wheel, push it sideways with factor x μ m g for 0.5 s; lateral force, normal force and
  // the contact point's sideways speed
  auto push = [&](double factor) {
    MultibodySystem s;
    RigidBody w;
    w.mass = m;
    w.inertia = Vec3(80, 150, 80).asDiagonal();
    w.position = Vec3(0, 0, 0.695 - m * 9.81 / 0.52e6);
    const int i = s.add_body(w);
    auto& t = s.add_constraint(std::make_unique<TyreContact>(i, Vec3::UnitY(), p));
    for (int k = 0; k < 200; ++k) s.step(0.005);
    for (int k = 0; k < 100; ++k) {
      s.set_external_wrench(i, push_at_contact(factor * p.friction * m * 9.81, p.radius));
      s.step(0.005);
    }
    const Vec3 contact = s.body(i).position - Vec3(0, 0, p.radius);
    return std::array<double, 3>{t.lateral_force(), t.normal_force(), s.body(i).point_velocity(contact).y()};
  };
  const auto slide = push(1.5);
  EXPECT_NEAR(std::abs(slide[0]), p.friction * slide[1], 1e-6 * slide[1]);
  EXPECT_GT(slide[2], 0.1);
  const auto hold = push(0.5);
  EXPECT_NEAR(std::abs(hold[0]), 0.5 * p.friction * m * 9.81, 1e-3 * m * 9.81);
  EXPECT_LT(std::abs(hold[2]), 1e-4);
}

}  // namespace
}  // namespace talus::vehicle
