// The dense reference on problems whose solution is known in closed form.
#include "vehicle/dense_reference.hpp"

#include <gtest/gtest.h>

#include <limits>

namespace talus::vehicle {
namespace {

BoundedMcp diagonal_problem() {
  // A = diag(2, 4, 1), b = (2, -8, 5): unconstrained λ = (1, -2, 5)
  BoundedMcp p;
  p.A.resize(3, 3);
  p.A.insert(0, 0) = 2.0;
  p.A.insert(1, 1) = 4.0;
  p.A.insert(2, 2) = 1.0;
  p.b = Eigen::Vector3d(2.0, -8.0, 5.0);
  p.lo = Eigen::Vector3d(-10.0, 0.0, -1.0);
  p.hi = Eigen::Vector3d(10.0, 10.0, 3.0);
  return p;
}

TEST(DirectDenseReferenceTest, ClipsToBoundsOnDiagonalProblem) {
  const auto r = solve_dense_reference(diagonal_problem());
  ASSERT_TRUE(r.converged);
  EXPECT_DOUBLE_EQ(r.lambda[0], 1.0);
  EXPECT_DOUBLE_EQ(r.lambda[1], 0.0);  // would be -2, lower bound 0
  EXPECT_DOUBLE_EQ(r.lambda[2], 3.0);  // would be 5, upper bound 3
  EXPECT_EQ(r.state[1], RowState::lower);
  EXPECT_EQ(r.state[2], RowState::upper);
}

// a block on a plane with friction: pushed sideways harder than μ m g allows, it slides
TEST(DirectDenseReferenceTest, FrictionSaturatesAtMuTimesNormal) {
  BoundedMcp p;
  p.A.resize(2, 2);
  p.A.insert(0, 0) = 1.0;  // unit mass, normal and tangent rows decoupled
  p.A.insert(1, 1) = 1.0;
  p.b = Eigen::Vector2d(9.81, 20.0);  // normal impulse wants 9.81; tangent wants 20
  p.lo = Eigen::Vector2d(0.0, 0.0);
  p.hi = Eigen::Vector2d(std::numeric_limits<double>::infinity(), 0.0);
  p.normal = {-1, 0};
  p.mu = Eigen::Vector2d(0.0, 0.5);
  const auto r = solve_dense_reference(p);
  ASSERT_TRUE(r.converged);
  EXPECT_NEAR(r.lambda[0], 9.81, 1e-12);
  EXPECT_NEAR(r.lambda[1], 0.5 * 9.81, 1e-12);
  EXPECT_LT(mcp_residual(p, r.lambda), 1e-6);
}

}  // namespace
}  // namespace talus::vehicle
