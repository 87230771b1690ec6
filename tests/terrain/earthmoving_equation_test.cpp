// terrain/earthmoving_equation: the FEE against Rankine's passive thrust where the two coincide
// (a smooth vertical wall), its growth with tool friction and depth, and its failure angle
// against the fine grid it refines, whose best point its search finds.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "host/error.hpp"
#include "terrain/earthmoving_equation.hpp"

namespace talus {
namespace {

constexpr double kDeg = M_PI / 180.0;

TEST(EarthmovingEquation, MeetsRankineForASmoothVerticalWall) {
  // delta = 0, alpha = 90 deg: the least force is Rankine's passive thrust 1/2 gamma d^2 K_p w,
  // K_p = tan^2(45 + phi/2), on the plane beta = 45 - phi/2
  for (double phi : {25.0, 32.0, 40.0}) {
    double beta = 0.0;
    const double f = fee_force(1727.0, 0.3, 2.0, 90.0, 0.0, phi, 0.0, &beta);
    const double kp = std::pow(std::tan((45.0 + 0.5 * phi) * kDeg), 2);
    const double rankine = 0.5 * 1727.0 * 9.81 * 0.09 * kp * 2.0;
    std::printf(
        "[ measured ] phi %.0f: FEE %.1f N, Rankine %.1f N, beta %.2f deg (45 - phi/2 = %.2f)\n",
        phi, f, rankine, beta, 45.0 - 0.5 * phi);
    EXPECT_NEAR(f, rankine, 1e-4 * rankine);
    EXPECT_NEAR(beta, 45.0 - 0.5 * phi, 0.02);
  }
}

TEST(EarthmovingEquation, GrowsWithToolFrictionAndDepthSquared) {
  const double rough = fee_force(1727.0, 0.3, 1.0, 90.0, std::atan(0.2) / kDeg, 32.0);
  const double smooth = fee_force(1727.0, 0.3, 1.0, 90.0, 0.0, 32.0);
  EXPECT_GT(rough, smooth);
  EXPECT_NEAR(fee_force(1727.0, 0.6, 1.0, 90.0, 11.0, 32.0),
              4.0 * fee_force(1727.0, 0.3, 1.0, 90.0, 11.0, 32.0), 1e-6);
}

TEST(EarthmovingEquation, ASurchargeOnASmoothWallAddsRankinesUniformPressure) {
  // delta = 0, alpha = 90 deg: a surcharge h adds K_p q d with q = gamma h, on the same plane
  const double kp = std::pow(std::tan((45.0 + 16.0) * kDeg), 2);
  const double f = fee_force(1727.0, 0.3, 1.0, 90.0, 0.0, 32.0, 0.2);
  const double rankine = 1727.0 * 9.81 * kp * (0.5 * 0.09 + 0.2 * 0.3);
  EXPECT_NEAR(f, rankine, 1e-4 * rankine);
}

// the refined failure angle is the minimum of N_q: no point of a 0.001 deg grid around it does
// better, for leaning, vertical and overhanging tools; and no plane at all is an InputError
TEST(EarthmovingEquation, TheFailureAngleIsTheLeastForceOnAFineGrid) {
  for (double rake : {30.0, 45.0, 60.0, 90.0, 110.0}) {
    const double beta = fee_failure_angle(rake, std::atan(0.2) / kDeg, 40.0);
    const double f = fee_force(1727.0, 0.5, 1.0, rake, std::atan(0.2) / kDeg, 40.0);
    std::printf("[ measured ] rake %.0f deg: failure angle %.4f deg, force %.1f N\n", rake, beta,
                f);
    for (int k = -500; k <= 500; ++k) {
      const double b = beta + 0.001 * k;
      const double nq = fee_n_q(rake, std::atan(0.2) / kDeg, 40.0, b);
      if (b <= 0.0 || std::isinf(nq)) continue;
      const double fb = 1727.0 * 9.81 * 0.125 * nq * std::sin(rake * kDeg + std::atan(0.2));
      EXPECT_GE(fb, f * (1.0 - 1e-12)) << "rake " << rake << " beta " << b;
    }
  }
  EXPECT_THROW(fee_failure_angle(170.0, 20.0, 40.0), InputError);
}

// the failure angle's search tries a tenth of the 0.1 deg grid's points first and then the grid
// near the best of them: on fresh random angles (non-negative, summing below 180 deg) it must end
// where refining the whole grid's best point ends, N_q no larger than there
TEST(EarthmovingEquation, TheFailureAnglesSearchEndsAtTheWholeGridsBestPoint) {
  const unsigned seed = std::random_device{}();
  std::printf("[ measured ] seed %u\n", seed);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> rake_of(0.5, 178.0), delta_of(0.0, 45.0),
      phi_of(0.0, 60.0);
  int draws = 0;
  while (draws < 300) {
    const double rake = rake_of(rng), delta = delta_of(rng), phi = phi_of(rng);
    if (rake + delta + phi >= 180.0) continue;
    ++draws;
    // the whole grid's best point
    double best = INFINITY;
    int best_k = 0;
    for (int k = 1; k < 900; ++k)
      if (const double nq = fee_n_q(rake, delta, phi, 0.1 * k); nq < best) {
        best = nq;
        best_k = k;
      }
    // (a sum within a tenth of a degree of 180 leaves no plane on the grid: refused)
    if (best_k == 0) {
      EXPECT_THROW(fee_failure_angle(rake, delta, phi), InputError);
      continue;
    }
    const double beta = fee_failure_angle(rake, delta, phi);
    EXPECT_GT(beta, 0.1 * (best_k - 1) - 1e-9) << "rake " << rake << " delta " << delta;
    EXPECT_LT(beta, 0.1 * (best_k + 1) + 1e-9) << "rake " << rake << " delta " << delta;
    EXPECT_LE(fee_n_q(rake, delta, phi, beta), best) << "rake " << rake << " phi " << phi;
  }
}

}  // namespace
}  // namespace talus
