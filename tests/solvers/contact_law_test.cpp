// solvers/contact_law: the double twin of kernels/contact_law.cl (the kernels are held to it by
// dem_reference_test's sweep comparisons); here its projections against their definitions
#include "solvers/contact_law.hpp"

#include <gtest/gtest.h>

namespace talus::contact_law {
namespace {

// the normal impulse: one SPOOK step when it stays above the bound, the bound otherwise
TEST(ContactLaw, NormalImpulseIsOneStepHeldAtItsLowerBound) {
  // lambda + (B - u - Sigma lambda) / D = 2 + (3 - 1 - 0.5 * 2) * 0.25
  EXPECT_DOUBLE_EQ(normal_impulse(2.0, 3.0, 1.0, 0.5, 0.25, 0.0), 2.25);
  // separating fast: the step would pull, the dry contact holds 0, the bond -h F_c
  EXPECT_DOUBLE_EQ(normal_impulse(0.1, 0.0, 10.0, 0.0, 1.0, 0.0), 0.0);
  EXPECT_DOUBLE_EQ(normal_impulse(0.1, 0.0, 10.0, 0.0, 1.0, -0.5), -0.5);
}

// friction: inside the disc the step is unclamped; outside it is scaled back onto the rim in the
// step's direction; a zero disc holds nothing
TEST(ContactLaw, FrictionImpulseStaysOnItsDisc) {
  const Vec3 lt(0.1, 0.0, 0.0), ut(0.0, -2.0, 0.0);
  const Vec3 inside = friction_impulse(lt, ut, 0.05, 1.0);
  EXPECT_TRUE(inside.isApprox(Vec3(0.1, 0.1, 0.0)));
  const Vec3 clamped = friction_impulse(lt, ut, 10.0, 0.5);
  EXPECT_NEAR(clamped.norm(), 0.5, 1e-15);
  EXPECT_TRUE(clamped.normalized().isApprox((lt - ut * 10.0).normalized()));
  EXPECT_TRUE(friction_impulse(lt, ut, 10.0, 0.0).isZero(0.0));
}

// rolling: the part tangent to n on its disc, the twist about n clamped to the same radius, the
// two independent
TEST(ContactLaw, RollingImpulseBoundsRollAndTwistAlike) {
  const Vec3 n(0.0, 0.0, 1.0);
  const Vec3 lr(0.0, 0.0, 0.0);
  // spinning about x and about n: the roll and the twist both pass the radius 0.2
  const Vec3 wrel(-3.0, 0.0, -5.0);
  const Vec3 r = rolling_impulse(lr, wrel, n, 1.0, 0.2);
  EXPECT_NEAR(Vec3(r.x(), r.y(), 0.0).norm(), 0.2, 1e-15);
  EXPECT_DOUBLE_EQ(r.z(), 0.2);
  // slow spin: one unclamped step, -wrel / D_r
  const Vec3 slow = rolling_impulse(lr, Vec3(-0.01, 0.0, 0.02), n, 1.0, 0.2);
  EXPECT_TRUE(slow.isApprox(Vec3(0.01, 0.0, -0.02)));
  // an old impulse along n is twist, not roll
  const Vec3 twist_only = rolling_impulse(Vec3(0.0, 0.0, 0.1), Vec3::Zero(), n, 1.0, 0.2);
  EXPECT_TRUE(twist_only.isApprox(Vec3(0.0, 0.0, 0.1)));
}

}  // namespace
}  // namespace talus::contact_law
