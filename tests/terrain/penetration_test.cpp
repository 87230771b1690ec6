// terrain/penetration: the bearing factors behind the edge's resistance against the published
// table (Vesić 1973, as tabulated by Das), the ramp from the surface to full depth, nothing above
// the surface.
#include "terrain/penetration.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

namespace talus {
namespace {

// F / (rho g B w faces) at two depths below the ramp's end gives N_q (slope) and N_gamma (offset)
void factors(double phi_total_deg, double* n_q, double* n_gamma) {
  BulkSoil soil;
  soil.internal_friction_deg = phi_total_deg;
  soil.dilatancy_deg = 0.0;
  soil.tool_friction = 0.0;  // faces without friction: F = q B w
  PenetrationParameters edge;
  const double b = 2.0 * edge.edge_max_radius, unit = 1000.0 * 9.81 * b;
  const double f1 = penetration_resistance(1.0, 1.0, soil, edge, 1000.0) / unit;
  const double f2 = penetration_resistance(2.0, 1.0, soil, edge, 1000.0) / unit;
  *n_q = f2 - f1;
  *n_gamma = 2.0 * (f1 - *n_q) / b;
}

TEST(Penetration, BearingFactorsMatchTheTable) {
  double n_q = 0.0, n_gamma = 0.0;
  factors(30.0, &n_q, &n_gamma);
  EXPECT_NEAR(n_q, 18.40, 0.01);
  EXPECT_NEAR(n_gamma, 22.40, 0.01);
  factors(40.0, &n_q, &n_gamma);
  EXPECT_NEAR(n_q, 64.20, 0.01);
  EXPECT_NEAR(n_gamma, 109.41, 0.01);
}

TEST(Penetration, RampsFromATenthAtTheSurfaceToAllAtHalfAMetre) {
  const BulkSoil soil;  // the paper's: 40 deg effective, mu 0.2
  const double w = 2.685;
  EXPECT_EQ(penetration_resistance(0.0, w, soil), 0.0);
  EXPECT_EQ(penetration_resistance(-0.3, w, soil), 0.0);
  const double f02 = penetration_resistance(0.2, w, soil),
               f05 = penetration_resistance(0.5, w, soil);
  std::printf("[ measured ] the paper's bucket edge: %.1f kN at 0.2 m, %.1f kN at 0.5 m\n",
              1e-3 * f02, 1e-3 * f05);
  // just under the surface a tenth of the bearing force acts; from 0.5 m all of it
  PenetrationParameters full;
  full.ramp_start = 1.0;
  const double d = 1e-6;
  EXPECT_NEAR(penetration_resistance(d, w, soil) / penetration_resistance(d, w, soil, full), 0.1,
              1e-5);
  EXPECT_NEAR(penetration_resistance(0.5, w, soil) / penetration_resistance(0.5, w, soil, full),
              1.0, 1e-12);
  EXPECT_NEAR(penetration_resistance(0.2, w, soil) / penetration_resistance(0.2, w, soil, full),
              0.1 + 0.9 * 0.4, 1e-12);
}

}  // namespace
}  // namespace talus
