// The gravel against the soil anchors of SPEC §7 (issue 11), measured from particle positions and
// forces with the full tests of terrain/shear_test, collapse_test and cutting_test: the paper's
// parameters (mu 0.3, mu_r 0.02, solvers/particles.hpp) give the paper's soil, and blocking
// rolling (mu_r 1.0, talus's earlier calibration to a heap angle) does not. docs/soil.md has the
// tables these reproduce at CI size.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "terrain/collapse_test.hpp"
#include "terrain/cutting_test.hpp"
#include "terrain/pile.hpp"
#include "terrain/shear_test.hpp"
#include "terrain/soil_sample.hpp"

namespace talus {
namespace {

ShearOptions shear_at(const std::string& level) { return at_level<ShearOptions>(fidelity_preset(level)); }

// dense gravel peaks at the paper's effective internal friction, 32 deg + 8 deg dilatancy = 40 deg
// (paper §4.4), and softens to a critical state below it (D100's D, timestep and sweeps; ~30 s)
TEST(SoilAnchors, DenseGravelShearsAtThePapersEffectiveInternalFriction) {
  Device dev;
  const ShearResult r = run_shear_test(dev, gravel(), shear_at("D100"));
  std::printf("[ measured ] D100 shear: peak %.1f deg at %.2f D, critical state %.1f deg, dilatancy %.1f deg, "
              "%d particles, sample %.0f kg/m^3\n", r.peak_friction_deg, r.peak_travel / 0.1, r.critical_friction_deg,
              r.dilatancy_deg, r.particles, r.bulk_density);
  EXPECT_NEAR(r.peak_friction_deg, 40.0, 4.0);
  EXPECT_LT(r.critical_friction_deg, r.peak_friction_deg - 5.0);
  EXPECT_GT(r.dilatancy_deg, 5.0);
}

// blocked rolling makes a much stronger soil: the critical state rises by more than 8 degrees
// (D400's size and sweeps, ~5 s each)
TEST(SoilAnchors, BlockedRollingMakesTheSoilFarStrongerThanThePapers) {
  Device dev;
  const ShearResult paper = run_shear_test(dev, gravel(), shear_at("D400"));
  Material blocked = gravel();
  blocked.rolling = 1.0;
  const ShearResult strong = run_shear_test(dev, blocked, shear_at("D400"));
  std::printf("[ measured ] D400 shear, mu_r 0.02: peak %.1f, critical %.1f deg; mu_r 1.0: peak %.1f, critical "
              "%.1f deg\n", paper.peak_friction_deg, paper.critical_friction_deg, strong.peak_friction_deg,
              strong.critical_friction_deg);
  EXPECT_GT(strong.critical_friction_deg, paper.critical_friction_deg + 8.0);
  EXPECT_GT(strong.peak_friction_deg, paper.peak_friction_deg + 5.0);
}

// a planar column of aspect ratio ~1 runs out by lambda a with lambda in 1.2-1.8 (Lube et al.
// 2005, Lajeunesse et al. 2005; SPEC §7), at D400's size and sweeps (~5 s)
TEST(SoilAnchors, ColumnCollapseRunsOutAsInTheLaboratory) {
  Device dev;
  const CollapseOptions o = at_level<CollapseOptions>(fidelity_preset("D400"));
  const CollapseResult r = run_collapse_test(dev, gravel(), o);
  const double lambda = r.runout_ratio / r.aspect_ratio;
  std::printf("[ measured ] D400 collapse: a = %.2f, (L - L0)/L0 = %.2f, lambda = %.2f (laboratory 1.2-1.8)\n",
              r.aspect_ratio, r.runout_ratio, lambda);
  EXPECT_GT(r.aspect_ratio, 0.8);
  EXPECT_LT(r.aspect_ratio, 1.5);
  EXPECT_GE(lambda, 1.2);
  EXPECT_LE(lambda, 1.8);
}

// a flat blade cutting 1.5 D deep in D400 gravel needs the force of the fundamental earthmoving
// equation with the paper's phi 32 deg and bucket-soil friction 0.2, under the heap it pushes
// (within 25 %). One bed's cut is one realisation of a chaotic flow: over ten beds on the CI VM the
// ratio was 1.02-1.33 (median 1.07; bench seeds 1-10, docs/soil.md), and one bed on an NVIDIA GPU
// (another rounding of the same law) fell outside the band. So the test takes the median of three
// beds (~11 s). The finer levels' numbers are in docs/soil.md
TEST(SoilAnchors, BladeForceMeetsTheEarthmovingEquation) {
  Device dev;
  std::vector<double> ratios;
  for (unsigned seed : {1u, 2u, 3u}) {
    CuttingOptions o = at_level<CuttingOptions>(fidelity_preset("D400"));
    o.depth = 0.6;
    o.seed = seed;
    const CuttingResult r = run_cutting_test(dev, gravel(), o);
    std::printf(
        "[ measured ] D400 cut 0.6 m deep, %.1f m wide, bed %u: %.1f kN (spread %.1f), equation "
        "%.1f kN "
        "(level bed %.1f kN), ratio %.2f\n",
        r.width, seed, 1e-3 * r.force, 1e-3 * r.force_spread, 1e-3 * r.fee_force,
        1e-3 * r.fee_force_level, r.force / r.fee_force);
    ratios.push_back(r.force / r.fee_force);
  }
  std::sort(ratios.begin(), ratios.end());
  EXPECT_NEAR(ratios[1], 1.0, 0.25) << "the median of three beds' force over the equation's";
}

// the same cut on the type-G terrain at G400 and G200 (~4 s): the force the blade's motor needs
// through the aggregate (less the cutting edge's penetration resistance, which the equation's
// ideally sharp blade does not meet) against the equation for the load the aggregate carries, with
// phi + psi = 40 deg, within 20 % (issue 14)
TEST(SoilAnchors, TypeGBladeForceMeetsTheEarthmovingEquation) {
  Device dev;
  for (const char* level : {"G400", "G200"}) {
    CuttingOptions o;
    o.depth = 0.6;
    const CuttingResult r = run_multiscale_cutting_test(dev, *find_multiscale_preset(level), o);
    std::printf(
        "[ measured ] %s cut 0.6 m deep, %.1f m wide: %.1f kN (spread %.1f), equation %.1f kN "
        "(level bed "
        "%.1f kN, beta %.1f deg), ratio %.2f; the cutting edge %.1f kN more; at most %d "
        "particles\n",
        level, r.width, 1e-3 * r.force, 1e-3 * r.force_spread, 1e-3 * r.fee_force,
        1e-3 * r.fee_force_level, r.fee_failure_angle_deg, r.force / r.fee_force,
        1e-3 * r.edge_force, r.particles);
    EXPECT_NEAR(r.force / r.fee_force, 1.0, 0.2) << level;
  }
}

}  // namespace
}  // namespace talus
