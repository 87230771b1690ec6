// The type-G digging simulator (digging/digging at a G level, issue 14): HD27 at G400 from start to
// end. The soil's mass (voxels + pool + particles) is the pile's at every step to 1e-9, the bucket
// ends loaded within its heaped capacity, the machine's sensors stay finite, and two runs are bit
// for bit the same.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "digging/digging.hpp"
#include "tests/solvers/dem_test_util.hpp"

namespace talus {
namespace {

struct G400Run {
  double loaded = 0.0;
  double work = 0.0;
  double worst_drift = 0.0;
  int most_particles = 0;
  std::vector<double> lift_force;  // the log's lift force, every sample
};

G400Run hd27_at_g400() {
  const vehicle::Scenario sc = vehicle::load_scenario("hd27");
  const FidelityPreset& preset = level_preset("G400");
  DiggingOptions options;
  const PileBuild pile = build_scenario_pile(test::shared_device(), sc, scenario_pile_profile(sc),
                                             preset, options, nullptr);
  EXPECT_TRUE(pile.particles.position.empty());  // a type-G pile is its profile's voxels
  DiggingSimulation sim(test::shared_device(), sc, preset, pile, options);
  EXPECT_TRUE(sim.multiscale());
  EXPECT_THROW(sim.dem(), Error);
  const double start = sim.terrain().mass_balance().total();
  G400Run r;
  sim.run([&](int) {
    r.worst_drift =
        std::max(r.worst_drift, std::abs(sim.terrain().mass_balance().total() - start) / start);
    r.most_particles = std::max(r.most_particles, static_cast<int>(sim.particle_count()));
  });
  r.loaded = sim.loaded_mass();
  r.work = sim.log().work();
  for (const auto& s : sim.log().samples()) r.lift_force.push_back(s.f_lift);
  std::printf(
      "[ measured ] HD27-G400: %.0f kg loaded (field 2700), total work %.1f kJ (the whole run), at "
      "most %d particles, worst mass "
      "drift %.1e\n",
      r.loaded, 1e-3 * r.work, r.most_particles, r.worst_drift);
  const double capacity = sim.loader().bucket_mesh().heaped_volume * kFieldBulkDensity;
  EXPECT_LT(r.loaded, capacity);
  return r;
}

TEST(MultiscaleDigging, Hd27AtG400KeepsTheSoilAndLoadsTheBucket) {
  const G400Run a = hd27_at_g400();
  EXPECT_LT(a.worst_drift, 1e-9);
  EXPECT_GT(a.loaded, 500.0);
  for (double f : a.lift_force) ASSERT_TRUE(std::isfinite(f));
  // the same inputs, the same bits
  const G400Run b = hd27_at_g400();
  EXPECT_EQ(a.loaded, b.loaded);
  EXPECT_EQ(a.lift_force, b.lift_force);
}

}  // namespace
}  // namespace talus
