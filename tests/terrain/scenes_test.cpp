// terrain/scenes: the 10k settling case is the peers' case (shared/peers) and settles as
// bench/RESULTS.md says: max overlap under 1 % of d after the peers' 0.5 s.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "host/device.hpp"
#include "solvers/dem_world.hpp"
#include "terrain/scenes.hpp"
#include "terrain/settle.hpp"

namespace talus {
namespace {

// the whole case as `talus bench dem` runs it, measured from the particles at the end: with the
// piles' gravel-covered ground (rolling resistance on the walls) it had left 5.4 % of d
TEST(Scenes, Settle10kEndsWithOverlapUnderOnePercentOfD) {
  Device dev;
  Scene scene = settle10k_scene();
  DemWorld world(dev, scene.material, scene.settings, scene.bounds, scene.geoms);
  world.set_particles(scene.particles);
  const double sim_time = 0.5;  // [s], the peers' settling time (shared/peers/README.md)
  const int steps = static_cast<int>(std::lround(sim_time / scene.settings.dt));
  for (int i = 0; i < steps; ++i) world.step();
  Particles p = world.particles();
  const double d = 2.0 * p.radius[0];
  const double overlap = max_overlap(p, scene.geoms) / d;
  std::printf("settle10k after %.1f s: max overlap %.3f %% of d, rms speed %.4f m/s\n", sim_time,
              100.0 * overlap, rms_speed(p));
  EXPECT_LT(overlap, 0.01);
  // settled: the grains' speeds are those of a bed at rest, not of grains still falling
  EXPECT_LT(rms_speed(p), 0.05);
}

}  // namespace
}  // namespace talus
