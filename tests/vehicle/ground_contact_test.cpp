// vehicle/ground_contact: points of a body against a rigid plane of the world. A block pushed
// into an upright wall stops at it with the wall carrying the push; sliding along the wall it
// feels Coulomb friction; of a hull with more candidates than rows, the rows go to the points
// nearest the wall, so a corner leading into the wall is held whichever it is; the flat ground
// (the default plane) still carries a block's weight.
#include "vehicle/ground_contact.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>

#include "host/error.hpp"
#include "vehicle/multibody.hpp"

namespace talus::vehicle {
namespace {

constexpr double kG = 9.81;

// a 100 kg cube of 1 m, weightless (gravity off) unless `weight`, at `position`; its 8 corners as
// the contact's candidates
struct Block {
  MultibodySystem system;
  int body = 0;
  std::vector<Vec3> corners;
  Block(const Vec3& position, const Eigen::Quaterniond& orientation, bool weight) {
    if (!weight) system.set_gravity(Vec3::Zero());
    RigidBody b;
    b.mass = 100.0;
    b.inertia = Mat3::Identity() * (100.0 / 6.0);
    b.position = position;
    b.orientation = orientation;
    body = system.add_body(b);
    for (double x : {-0.5, 0.5})
      for (double y : {-0.5, 0.5})
        for (double z : {-0.5, 0.5}) corners.emplace_back(x, y, z);
  }
  // its corners against `plane` with friction mu, rows for the four nearest
  PointGroundContact& add_wall(const RigidPlane& plane, double mu) {
    GroundContactParameters p;
    p.friction = mu;
    auto& c =
        system.add_constraint(std::make_unique<PointGroundContact>(body, corners, p, plane, 4));
    c.name = "wall";
    return c;
  }
  // `steps` steps of 10 ms under the force f [N] at the centre; `after(k)` after step k
  void push(const Vec3& f, int steps, const std::function<void(int)>& after = {}) {
    Vec6 wrench = Vec6::Zero();
    wrench.head<3>() = f;
    for (int k = 0; k < steps; ++k) {
      system.set_external_wrench(body, wrench);
      system.step(0.01);
      if (after) after(k);
    }
  }
  const RigidBody& state() const { return system.body(body); }
};

// the wall x = 2 facing -x (free side x < 2)
const RigidPlane kWall{Vec3(-1.0, 0.0, 0.0), -2.0};

TEST(PointGroundContact, ABlockPushedIntoAWallStopsThereAndTheWallCarriesThePush) {
  Block b(Vec3(0.0, 0.0, 1.0), Eigen::Quaterniond::Identity(), false);
  auto& wall = b.add_wall(kWall, 0.0);
  // a push of 2 kN along +x for 2 s: it reaches the wall (1 m away) within about a second
  const double push = 2000.0;
  double front = 0.0;
  b.push(Vec3(push, 0.0, 0.0), 200,
         [&](int) { front = std::max(front, b.state().position.x() + 0.5); });
  std::printf("[ measured ] deepest front %.5f m (wall at 2), wall force %.1f N (push %.0f N)\n",
              front, wall.normal_force(), push);
  // stiff (1e8 N/m per point): 2 kN over 4 points presses it in by 5 micrometres
  EXPECT_LT(front, 2.0 + 1e-3);
  EXPECT_NEAR(b.state().velocity.x(), 0.0, 1e-4);
  EXPECT_NEAR(wall.normal_force(), push, 1e-3 * push);
  EXPECT_NEAR(wall.force_on_body().x(), -push, 1e-3 * push);
  EXPECT_NEAR(wall.clearance(), 0.0, 1e-4);
}

TEST(PointGroundContact, SlidingAlongAWallFeelsCoulombFriction) {
  // pressed on the wall with 2 kN and pulled along it (y) with 1 kN at mu 0.2: it slides with
  // (1000 - 0.2 * 2000) / 100 = 6 m/s^2
  Block b(Vec3(1.5, 0.0, 1.0), Eigen::Quaterniond::Identity(), false);
  b.add_wall(kWall, 0.2);
  double v_half = 0.0;
  b.push(Vec3(2000.0, 1000.0, 0.0), 100, [&](int k) {
    if (k == 49) v_half = b.state().velocity.y();
  });
  const double a = (b.state().velocity.y() - v_half) / 0.5;
  std::printf("[ measured ] along the wall: %.4f m/s^2 (expected 6)\n", a);
  EXPECT_NEAR(a, 6.0, 6e-3);
}

TEST(PointGroundContact, TheRowsGoToTheHullPointsNearestTheWall) {
  // a cube turned 45 deg about z leads with one vertical edge (two corners); pushed into the wall
  // it stops on that edge, whichever four of its eight corners the rows then hold
  const Eigen::Quaterniond turned(Eigen::AngleAxisd(M_PI / 4.0, Vec3::UnitZ()));
  Block b(Vec3(0.0, 0.0, 1.0), turned, false);
  auto& wall = b.add_wall(kWall, 0.0);
  b.push(Vec3(2000.0, 0.0, 0.0), 200);
  double front = -INFINITY;
  for (const Vec3& c : b.corners) front = std::max(front, b.state().point_to_world(c).x());
  std::printf("[ measured ] turned cube: leading edge at %.5f m, wall force %.1f N\n", front,
              wall.normal_force());
  EXPECT_LT(front, 2.0 + 1e-3);
  EXPECT_GT(front, 2.0 - 1e-3);
  EXPECT_NEAR(wall.normal_force(), 2000.0, 2.0);
  // the rows: 4 points x (normal + two friction)
  EXPECT_EQ(wall.forces().size(), 12u);
}

TEST(PointGroundContact, TheFlatGroundCarriesABlocksWeight) {
  Block b(Vec3(0.0, 0.0, 0.5), Eigen::Quaterniond::Identity(), true);
  GroundContactParameters p;
  std::vector<Vec3> bottom;
  for (const Vec3& c : b.corners)
    if (c.z() < 0.0) bottom.push_back(c);
  auto& ground = b.system.add_constraint(std::make_unique<PointGroundContact>(b.body, bottom, p));
  ground.name = "ground";
  for (int k = 0; k < 100; ++k) b.system.step(0.01);
  EXPECT_NEAR(ground.normal_force(), 100.0 * kG, 1e-3 * 100.0 * kG);
  EXPECT_NEAR(ground.force_on_body().z(), 100.0 * kG, 1e-3 * 100.0 * kG);
  EXPECT_NEAR(ground.clearance(), 0.0, 1e-4);
}

// the flat ground's rows are what they were before the contact took any plane: per point a normal
// row along +z with the gap z - ground_height, then friction along world x and y, exactly
TEST(PointGroundContact, TheGroundsRowsAreTheFlatGroundsExactly) {
  std::vector<RigidBody> bodies(1);
  bodies[0].mass = 100.0;
  bodies[0].inertia = Mat3::Identity();
  bodies[0].position = Vec3(0.3, -0.2, 0.7);
  bodies[0].orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Vec3(1, 2, 3).normalized()));
  GroundContactParameters p;
  p.ground_height = 0.25;
  const std::vector<Vec3> points{Vec3(0.5, 0.1, -0.6), Vec3(-0.4, 0.3, -0.5)};
  PointGroundContact ground(0, points, p);
  std::vector<ConstraintRow> rows;
  ground.add_rows(bodies, rows);
  ASSERT_EQ(rows.size(), 6u);
  for (size_t k = 0; k < points.size(); ++k) {
    const Vec3 at = bodies[0].point_to_world(points[k]);
    const ConstraintRow& n = rows[3 * k];
    EXPECT_EQ(n.violation, at.z() - p.ground_height);
    EXPECT_EQ(n.force_min, 0.0);
    EXPECT_EQ(n.compliance, 1.0 / p.stiffness);
    ASSERT_EQ(n.blocks.size(), 1u);
    EXPECT_EQ(Vec3(n.blocks[0].jacobian.head<3>()), Vec3::UnitZ());
    EXPECT_EQ(Vec3(rows[3 * k + 1].blocks[0].jacobian.head<3>()), Vec3::UnitX());
    EXPECT_EQ(Vec3(rows[3 * k + 2].blocks[0].jacobian.head<3>()), Vec3::UnitY());
    EXPECT_EQ(rows[3 * k + 1].friction_normal, static_cast<int>(3 * k));
    EXPECT_EQ(rows[3 * k + 1].friction_coefficient, p.friction);
  }
  EXPECT_EQ(ground.clearance(), std::min(bodies[0].point_to_world(points[0]).z(),
                                         bodies[0].point_to_world(points[1]).z()) -
                                    p.ground_height);
}

TEST(PointGroundContact, BadPlanesAndStiffnessesAreRefused) {
  GroundContactParameters p;
  const std::vector<Vec3> one{Vec3::Zero()};
  EXPECT_THROW(PointGroundContact(0, {}, p, kWall, 4), Error);
  EXPECT_THROW(PointGroundContact(0, one, p, RigidPlane{Vec3(2.0, 0.0, 0.0), 0.0}, 1), Error);
  p.stiffness = 0.0;
  EXPECT_THROW(PointGroundContact(0, one, p), Error);
}

}  // namespace
}  // namespace talus::vehicle
