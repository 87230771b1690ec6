// The stepper as a whole: free fall, momentum, and the mobility coupling hook.
#include "vehicle/multibody.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <limits>
#include <random>
#include <string>

#include "host/error.hpp"
#include "vehicle/joints.hpp"
#include "vehicle/spook.hpp"

namespace talus::vehicle {
namespace {

// rows with random Jacobian blocks on random bodies (the world included, and some rows with two
// blocks on one body, as a driveline row has for two wheels on one frame), velocity rows with a
// random compliance; it keeps the rows it gave for the test's own G
class RandomRows : public Constraint {
 public:
  RandomRows(int rows, int bodies, unsigned seed) : rows_(rows), bodies_(bodies), rng_(seed) {}
  void add_rows(const std::vector<RigidBody>&, std::vector<ConstraintRow>& rows) override {
    given.clear();
    std::uniform_int_distribution<int> body(kWorld, bodies_ - 1), blocks(1, 3);
    std::uniform_real_distribution<double> unit(-1.0, 1.0), compliance(1e-7, 1e-5);
    for (int r = 0; r < rows_; ++r) {
      ConstraintRow row;
      row.kind = RowKind::velocity;
      row.compliance = compliance(rng_);
      row.target_speed = unit(rng_);
      const int count = blocks(rng_);
      for (int k = 0; k < count; ++k) {
        JacobianBlock b;
        b.body = body(rng_);
        for (int c = 0; c < 6; ++c) b.jacobian[c] = unit(rng_);
        row.blocks.push_back(b);
      }
      given.push_back(row);
      rows.push_back(row);
    }
  }
  std::vector<ConstraintRow> given;

 private:
  int rows_, bodies_;
  std::mt19937 rng_;
};

// the assembled Schur complement is G M⁻¹ Gᵀ + Σ computed the plain dense way, exactly symmetric,
// and stores every entry of rows that share a moving body (fresh random rows every run)
TEST(MultibodyTest, SchurComplementIsTheDenseProduct) {
  const unsigned seed = std::random_device{}();
  std::mt19937 rng(seed);
  MultibodySystem s;
  const int bodies = 5;
  std::uniform_real_distribution<double> mass(1.0, 100.0), angle(-3.0, 3.0);
  for (int b = 0; b < bodies; ++b) {
    RigidBody body;
    body.mass = mass(rng);
    body.inertia = Vec3(mass(rng), mass(rng), mass(rng)).asDiagonal();
    body.orientation =
        Eigen::AngleAxisd(angle(rng), Vec3(angle(rng), angle(rng), 1.0).normalized());
    body.fixed = b == 2;  // a fixed body is part of the world: no columns
    s.add_body(body);
  }
  auto& rows = s.add_constraint(std::make_unique<RandomRows>(40, bodies, seed));
  const double h = 0.01;
  s.assemble(h);
  // the test's own G (six columns per body, the fixed one's ignored) and M⁻¹
  const int m = static_cast<int>(rows.given.size());
  Eigen::MatrixXd G = Eigen::MatrixXd::Zero(m, 6 * bodies),
                  Minv = Eigen::MatrixXd::Zero(6 * bodies, 6 * bodies);
  for (int r = 0; r < m; ++r) {
    for (const auto& b : rows.given[r].blocks) {
      if (b.body != kWorld && !s.body(b.body).fixed)
        G.block(r, 6 * b.body, 1, 6) += b.jacobian.transpose();
    }
  }
  for (int b = 0; b < bodies; ++b) {
    if (s.body(b).fixed) continue;
    Minv.block(6 * b, 6 * b, 3, 3) = Mat3::Identity() / s.body(b).mass;
    Minv.block(6 * b + 3, 6 * b + 3, 3, 3) = s.body(b).inverse_inertia_world();
  }
  Eigen::MatrixXd expected = G * Minv * G.transpose();
  for (int r = 0; r < m; ++r)
    expected(r, r) += spook::velocity_row_sigma(h, rows.given[r].compliance);
  const Eigen::MatrixXd got = Eigen::MatrixXd(s.problem().A);
  EXPECT_LE((got - expected).cwiseAbs().maxCoeff(), 1e-12 * expected.cwiseAbs().maxCoeff())
      << "seed " << seed;
  EXPECT_EQ(got, got.transpose()) << "seed " << seed;
  // stored entries: the diagonal and every pair of rows acting on one moving body
  const Eigen::MatrixXd shares = (G.cwiseAbs() * Minv.cwiseAbs() * G.cwiseAbs().transpose());
  int missing = 0;
  for (int i = 0; i < m; ++i) {
    for (int j = 0; j < m; ++j)
      missing += (i == j || shares(i, j) > 0.0) && s.problem().A.coeff(i, j) == 0.0;
  }
  EXPECT_EQ(missing, 0) << "seed " << seed;
  // and the step solves (the assembly is well formed for CHOLMOD)
  s.solve();
  EXPECT_TRUE(s.last_result().converged);
}

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
