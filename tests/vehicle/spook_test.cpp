// SPOOK coefficients against their closed forms and against the behaviour they must produce.
#include "vehicle/spook.hpp"

#include <gtest/gtest.h>

#include "host/error.hpp"

namespace talus::spook {
namespace {

TEST(SpookTest, CoefficientsMatchClosedForm) {
  // h = 10 ms, τ = 2h: 1 + 4τ/h = 9
  const auto c = holonomic_row(0.01, 1e-6, 0.02);
  EXPECT_DOUBLE_EQ(c.upsilon, 1.0 / 9.0);
  EXPECT_DOUBLE_EQ(c.sigma, 4.0 * 1e-6 / (1e-4 * 9.0));
  EXPECT_DOUBLE_EQ(velocity_row_sigma(0.01, 1e-8), 1e-6);
  EXPECT_DOUBLE_EQ(holonomic_rhs(0.01, c, 0.003, 0.5), -(4.0 / 0.01) * 0.003 / 9.0 + 0.5 / 9.0);
}

TEST(SpookTest, RejectsNonsense) {
  EXPECT_THROW(holonomic_row(0.0, 1e-6, 0.02), Error);
  EXPECT_THROW(holonomic_row(0.01, -1.0, 0.02), Error);
  EXPECT_THROW(velocity_row_sigma(0.01, -1.0), Error);
}

// a compliant row in steady state gives the spring force -g/ε (anchor: Hooke's law)
TEST(SpookTest, CompliantRowHoldsSpringForceAtRest) {
  const double h = 0.005, eps = 2e-6, tau = 0.01, g = 0.004;
  const auto c = holonomic_row(h, eps, tau);
  // at rest: G v⁺ = 0, so Σ λ = rhs and force = λ / h
  const double lambda = holonomic_rhs(h, c, g, 0.0) / c.sigma;
  EXPECT_NEAR(lambda / h, -g / eps, 1e-9 * g / eps);
}

// a stiff spring-mass system stepped with SPOOK decays without overshoot blow-up (stability anchor)
TEST(SpookTest, StiffOscillatorStaysBoundedAndSettles) {
  const double m = 10.0, h = 0.01, eps = 1e-9, tau = 2 * h;
  const auto c = holonomic_row(h, eps, tau);
  double x = 0.01, v = 0.0;
  for (int k = 0; k < 500; ++k) {
    // one row g = x, G = 1: (1/m + Σ) λ = rhs - v
    const double lambda = (holonomic_rhs(h, c, x, v) - v) / (1.0 / m + c.sigma);
    v += lambda / m;
    x += h * v;
    ASSERT_LT(std::abs(x), 0.0101);
  }
  EXPECT_LT(std::abs(x), 1e-8);
}

}  // namespace
}  // namespace talus::spook
