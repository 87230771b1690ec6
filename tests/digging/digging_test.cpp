// The type-D digging simulator (digging/digging): a scenario's pile placed before the machine and
// dug with the feedforward inputs. These tests measure bounds a broken coupling or a broken
// loaded-mass rule would cross.
#include "digging/digging.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "host/binary.hpp"
#include "terrain/bucket_fill.hpp"
#include "terrain/penetration.hpp"
#include "tests/solvers/dem_test_util.hpp"

namespace talus {
namespace {

// the scenario's pile at D400, settled (about 10 s here)
PileBuild pile_at_d400(const vehicle::Scenario& sc, const DiggingOptions& options) {
  return build_scenario_pile(test::shared_device(), sc, scenario_pile_profile(sc), fidelity_preset("D400"), options,
                             nullptr);
}

// HD27 at D400 from start to end: the loaded mass is never more than the bucket's heaped
// capacity in gravel (heaped volume x the field bulk density 1727 kg/m^3, SPEC §2.2; the rule
// counts particle centres, and the bucket's load never packs denser than the pile) and is
// positive after the fill; no particle gets deeper into the plates than a fifth of its radius
TEST(Digging, Hd27AtD400FillsTheBucketWithinItsHeapedCapacity) {
  const vehicle::Scenario sc = vehicle::load_scenario("hd27");
  const FidelityPreset& preset = fidelity_preset("D400");
  DiggingOptions options;
  PileBuild pile = pile_at_d400(sc, options);
  // the pile's toe lies where the scenario puts it, in front of the bucket
  double toe = 1e9;
  for (const Vec3& x : pile.particles.position) toe = std::min(toe, x.x());
  DiggingSimulation sim(test::shared_device(), sc, preset, pile, options);
  EXPECT_GT(toe, sim.loader().bucket_tip_world().x());
  const double capacity = sim.loader().bucket_mesh().heaped_volume * 1727.0;
  // the run loop, the load checked every half second of the run; it calls back after every step
  double largest = 0.0;
  int calls = 0;
  const double wall = sim.run([&](int k) {
    EXPECT_EQ(k, ++calls);
    if (k % static_cast<int>(std::lround(0.5 / preset.dt)) == 0) largest = std::max(largest, sim.loaded_mass());
  });
  EXPECT_EQ(calls, sim.steps_total());
  EXPECT_TRUE(sim.done());
  EXPECT_GT(wall, 0.0);
  const double loaded = sim.loaded_mass();
  std::printf("[ measured ] HD27-D400: %.0f kg loaded (largest on the way %.0f kg, capacity %.0f kg); "
              "%d steps touching the bucket, mean passes %.2f, max %d, coupling residual <= %.1e m/s, "
              "deepest bucket overlap %.1f%% of a radius\n", loaded, largest, capacity, sim.contact_steps(),
              sim.mean_passes(), sim.max_passes(), sim.max_residual(), 100.0 * sim.max_bucket_overlap_rel());
  EXPECT_GT(loaded, 0.0);
  EXPECT_LE(std::max(largest, loaded), capacity);
  EXPECT_GT(sim.contact_steps(), 100);
  EXPECT_LT(sim.max_bucket_overlap_rel(), 0.2);
  // the scenario lifts the load: the bucket tip ends well above the ground
  EXPECT_GT(sim.loader().bucket_tip_world().z(), 1.0);
  // the soil's force on the bucket, one sample a step; over the last second, the load lifted
  // clear of the pile, it is the weight of the particles the bucket holds (the loaded-mass rule
  // counts centres in the heaped volume, so within a quarter)
  ASSERT_EQ(sim.soil_log().size(), static_cast<size_t>(sim.steps_total()));
  EXPECT_NEAR(sim.soil_log().back().t, sim.time(), 1e-9);
  double fz = 0.0;
  int samples = 0;
  for (const SoilForceSample& f : sim.soil_log())
    if (f.t > sim.time() - 1.0) fz += f.force.z(), ++samples;
  fz /= samples;
  std::printf(
      "[ measured ] HD27-D400, the last second: the soil pushes the bucket with %.1f kN "
      "vertically, the weight of %.0f kg\n",
      1e-3 * fz, -fz / 9.81);
  EXPECT_NEAR(-fz / 9.81, loaded, 0.25 * loaded);
}

TEST(Digging, ScenarioWithoutAPileIsRejected) {
  const vehicle::Scenario sc = vehicle::load_scenario("flat-lift");
  DiggingOptions options;
  EXPECT_THROW(build_scenario_pile(test::shared_device(), sc, default_pile_profile(), fidelity_preset("D400"),
                                   options, nullptr),
               InputError);
}

// the bucket's content: at a G level a body welded to the bucket by default (its weight and its
// inertia in the machine's solve), its weight alone on request; a type-D level's content is its
// particles, so asking for the weight alone there is one clear input error (before any pile)
TEST(Digging, TheBucketContentIsABodyAtTypeGAndItsParticlesAtTypeD) {
  const vehicle::Scenario sc = vehicle::load_scenario("hd27");
  const auto payloads = [](const DiggingSimulation& sim) {
    int n = 0;
    for (const auto& b : sim.loader().bodies()) n += b.name == "bucket payload";
    return n;
  };
  const FidelityPreset& g400 = level_preset("G400");
  DiggingOptions options;
  EXPECT_TRUE(options.content_inertia);
  const PileBuild g_pile = build_scenario_pile(test::shared_device(), sc, scenario_pile_profile(sc),
                                               g400, options, nullptr);
  EXPECT_EQ(payloads(DiggingSimulation(test::shared_device(), sc, g400, g_pile, options)), 1);
  options.content_inertia = false;
  EXPECT_EQ(payloads(DiggingSimulation(test::shared_device(), sc, g400, g_pile, options)), 0);
  try {
    const DiggingSimulation refused(test::shared_device(), sc, fidelity_preset("D400"), PileBuild{},
                                    options);
    ADD_FAILURE() << "the weight alone was taken at D400";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("content_inertia"), std::string::npos) << e.what();
  }
}

// the terrain's support under the bucket (the type-G default): on RD21 at G400 it carries force
// while the loaded bucket pushes along the trench its edge cut, and the machine stands nose up
// where without it the loaded bucket noses it down (measured 2026-11-29 over piles 1-3, 4-12 s:
// +0.40 to +0.53 deg against -0.10 to -0.15; D200's pile holds it at +0.99 to +1.28, docs/
// validation.md "The terrain's support under the bucket"); refused at D400
TEST(Digging, TheTerrainHoldsTheTypeGBucketsBottomUp) {
  const vehicle::Scenario sc = vehicle::load_scenario("rd21");
  const FidelityPreset& g400 = level_preset("G400");
  double pitch[2] = {0.0, 0.0};
  for (const bool support : {true, false}) {
    DiggingOptions options;
    EXPECT_TRUE(DiggingOptions{}.bucket_support);
    options.bucket_support = support;
    const PileBuild pile = build_scenario_pile(test::shared_device(), sc, scenario_pile_profile(sc),
                                               g400, options, nullptr);
    DiggingSimulation sim(test::shared_device(), sc, g400, pile, options);
    int samples = 0;
    while (!sim.done()) {
      sim.step();
      if (sim.time() >= 4.0 && sim.time() <= 12.0) {
        pitch[support] += sim.sensors().pitch_deg;
        ++samples;
      }
    }
    pitch[support] /= samples;
    double largest = 0.0;
    for (const AggregateSample& a : sim.aggregate_log())
      largest = std::max(largest, a.support_force.z());
    std::printf(
        "[ measured ] RD21-G400 pile 1, support %s: mean pitch %.2f deg over 4-12 s, the "
        "support's largest lift %.1f kN, loaded %.0f kg\n",
        support ? "on" : "off", pitch[support], 1e-3 * largest, sim.loaded_mass());
    // (off, the pitch below says the support is gone)
    if (support) {
      EXPECT_GT(largest, 5e3);
    }
  }
  EXPECT_GT(pitch[1], pitch[0] + 0.25);
  DiggingOptions d;
  d.bucket_support = false;
  try {
    const DiggingSimulation refused(test::shared_device(), vehicle::load_scenario("hd27"),
                                    fidelity_preset("D400"), PileBuild{}, d);
    ADD_FAILURE() << "the support was turned off at D400";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bucket_support"), std::string::npos) << e.what();
  }
}

// the logs a run writes go through a saved state whole: type G's aggregate log (the support's
// force, the held mass, the soil's and the particles' forces among its fields) and type D's soil
// force log, each sample the same bits after a restore into a simulation of the same inputs
TEST(Digging, ItsLogsGoThroughASavedStateBitForBit) {
  const vehicle::Scenario sc = vehicle::load_scenario("hd27");
  for (const char* level : {"G400", "D400"}) {
    const FidelityPreset& preset = level_preset(level);
    const DiggingOptions options;
    const PileBuild pile = build_scenario_pile(test::shared_device(), sc, scenario_pile_profile(sc),
                                               preset, options, nullptr);
    DiggingSimulation first(test::shared_device(), sc, preset, pile, options);
    // into the pile: the bucket meets it at about 2.4 s
    while (first.time() < 3.5) first.step();
    ByteWriter w;
    first.save_state(w);
    DiggingSimulation second(test::shared_device(), sc, preset, pile, options);
    ByteReader r(w.bytes(), w.bytes().size(), level, "a test's state");
    second.restore_state(r);
    const auto& a = first.aggregate_log();
    const auto& b = second.aggregate_log();
    ASSERT_EQ(a.size(), b.size()) << level;
    double support = 0.0, particles = 0.0, terrain = 0.0, zone = 0.0;
    for (size_t k = 0; k < a.size(); ++k) {
      EXPECT_EQ(a[k].support_force, b[k].support_force) << level << " " << k;
      EXPECT_EQ(a[k].held_mass, b[k].held_mass) << level << " " << k;
      EXPECT_EQ(a[k].soil_force, b[k].soil_force) << level << " " << k;
      EXPECT_EQ(a[k].particle_force, b[k].particle_force) << level << " " << k;
      EXPECT_EQ(a[k].terrain_force, b[k].terrain_force) << level << " " << k;
      EXPECT_EQ(a[k].zone_velocity, b[k].zone_velocity) << level << " " << k;
      EXPECT_EQ(a[k].force_on_bucket, b[k].force_on_bucket) << level << " " << k;
      EXPECT_EQ(a[k].principal_moments, b[k].principal_moments) << level << " " << k;
      support = std::max(support, a[k].support_force.norm());
      particles = std::max(particles, a[k].particle_force.norm());
      terrain = std::max(terrain, a[k].terrain_force.norm());
      zone = std::max(zone, a[k].zone_velocity.norm());
    }
    const auto& c = first.soil_log();
    const auto& d = second.soil_log();
    ASSERT_EQ(c.size(), d.size()) << level;
    double soil = 0.0, below = 0.0, inside = 0.0, across = 0.0;
    for (size_t k = 0; k < c.size(); ++k) {
      EXPECT_EQ(c[k].t, d[k].t) << level << " " << k;
      EXPECT_EQ(c[k].force, d[k].force) << level << " " << k;
      EXPECT_EQ(c[k].torque, d[k].torque) << level << " " << k;
      EXPECT_EQ(c[k].faces.below, d[k].faces.below) << level << " " << k;
      EXPECT_EQ(c[k].faces.inside, d[k].faces.inside) << level << " " << k;
      EXPECT_EQ(c[k].faces.across, d[k].faces.across) << level << " " << k;
      soil = std::max(soil, c[k].force.norm());
      below = std::max(below, c[k].faces.below.norm());
      inside = std::max(inside, c[k].faces.inside.norm());
      across = std::max(across, c[k].faces.across.norm());
    }
    std::printf(
        "[ measured ] HD27-%s to 3.5 s: %zu aggregate and %zu soil samples, largest "
        "support %.1f kN, particles' %.1f kN, type D soil %.1f kN (below the bottom %.1f, on its "
        "inside %.1f, across the cutting direction %.1f)\n",
        level, a.size(), c.size(), 1e-3 * support, 1e-3 * particles, 1e-3 * soil, 1e-3 * below,
        1e-3 * inside, 1e-3 * across);
    // logs with something in them: the type-G zone has pushed the bucket, the type-D pile too
    if (first.multiscale()) {
      EXPECT_GT(a.size(), 0u);
      EXPECT_GT(particles, 0.0);
      EXPECT_GT(terrain, 0.0);
      EXPECT_GT(zone, 0.0);
      EXPECT_TRUE(c.empty());
    } else {
      EXPECT_TRUE(a.empty());
      EXPECT_GT(soil, 1e3);
      // the faces' parts (measured at D400: under the bottom 62 kN at the most, on its inside 33,
      // across the cutting direction 163): the edge cuts and the bucket meets soil below and in it
      EXPECT_GT(across, 0.5 * soil);
      EXPECT_GT(below, 1e4);
      EXPECT_GT(inside, 1e4);
    }
  }
}

// the aggregate's log holds the forces that moved it: over every step the zone is engaged, its mass
// times the change of its velocity over the step equals interface A's force on it
// (-force_on_bucket), interface B's (terrain_force) and its weight, the only forces on the body in
// the machine's solve of a run without effects (the edge's brake acts on the bucket). The step
// starts from the velocity the last solve gave the aggregate when it was engaged then, and from
// its zone's particles' (zone_velocity) when it engages anew (terrain/aggregate.cpp). A force
// logged with a wrong sign, frame or step, a force on the body left out of the log, or a zone
// velocity not the one the step started from breaks it
TEST(Digging, TheAggregatesLoggedForcesAreTheOnesThatMovedIt) {
  const vehicle::Scenario sc = vehicle::load_scenario("hd27");
  const FidelityPreset& g400 = level_preset("G400");
  const DiggingOptions options;
  const PileBuild pile = build_scenario_pile(test::shared_device(), sc, scenario_pile_profile(sc),
                                             g400, options, nullptr);
  DiggingSimulation sim(test::shared_device(), sc, g400, pile, options);
  // through the cut and the breakout (the first 6 s of the dig)
  while (sim.time() < 6.0) sim.step();
  const Vec3 g = sim.loader().system().gravity();
  const std::vector<AggregateSample>& log = sim.aggregate_log();
  int engaged = 0, engaging = 0;
  double worst = 0.0, largest_b = 0.0, largest_a = 0.0;
  for (size_t k = 1; k < log.size(); ++k) {
    const AggregateSample& before = log[k - 1];
    const AggregateSample& a = log[k];
    if (a.particles == 0) continue;
    // the velocity the step started from
    const bool anew = before.particles == 0;
    const Vec3 start = anew ? a.zone_velocity : before.velocity;
    // the mass is this step's (the particles renew it every step): m_k (v_k - v_start) / h
    const Vec3 mass_times_acceleration = a.mass * (a.velocity - start) / g400.dt;
    const Vec3 forces = -a.force_on_bucket + a.terrain_force + a.mass * g;
    // measured against the largest force in the balance
    const double scale =
        std::max({a.force_on_bucket.norm(), a.terrain_force.norm(), a.mass * g.norm()});
    worst = std::max(worst, (mass_times_acceleration - forces).norm() / scale);
    largest_a = std::max(largest_a, a.force_on_bucket.norm());
    largest_b = std::max(largest_b, a.terrain_force.norm());
    ++(anew ? engaging : engaged);
  }
  std::printf(
      "[ measured ] HD27-G400 to 6 s: %d steps engaged since the last, %d engaging anew, largest "
      "|A| %.1f kN, |B| %.1f kN, worst imbalance %.2e of the step's largest force\n",
      engaged, engaging, 1e-3 * largest_a, 1e-3 * largest_b, worst);
  EXPECT_GT(engaged, 10);
  EXPECT_GT(engaging, 0);
  EXPECT_GT(largest_b, 1e3);
  EXPECT_LT(worst, 1e-6);
}

// the cutting edge's penetration resistance, a study factor at type G: the brake's bound each step
// is the factor times terrain/penetration's law at the depth and width of the zone the aggregate
// was placed on (the terrain's zone before the step), the law's own at 1, nothing at 0 (no edge
// force all dig long, where the law's acts); any other factor is refused at a type-D level
TEST(Digging, TheCuttingEdgesResistanceIsTheLawTimesItsStudyFactor) {
  const vehicle::Scenario sc = vehicle::load_scenario("hd27");
  const FidelityPreset& g400 = level_preset("G400");
  for (const double factor : {1.0, 2.5, 0.0}) {
    DiggingOptions options;
    options.edge_resistance = factor;
    const PileBuild pile = build_scenario_pile(test::shared_device(), sc, scenario_pile_profile(sc),
                                               g400, options, nullptr);
    DiggingSimulation sim(test::shared_device(), sc, g400, pile, options);
    int engaged = 0;
    double largest = 0.0;
    while (!sim.done()) {
      const ActiveZone zone = sim.terrain().last_step().zone;
      sim.step();
      const double law = penetration_resistance(zone.depth, zone.width, BulkSoil{});
      EXPECT_NEAR(sim.aggregate().edge_limit(), factor * law, 1e-9 * (1.0 + law))
          << "factor " << factor << " at t " << sim.time();
      engaged += zone.depth > 0.0 && law > 0.0;
      largest = std::max(largest, sim.aggregate().edge_force());
    }
    std::printf(
        "[ measured ] HD27-G400, edge resistance x%.1f: %d steps under the soil, the "
        "edge's largest force %.1f kN\n",
        factor, engaged, 1e-3 * largest);
    EXPECT_GT(engaged, 10) << factor;
    if (factor == 0.0)
      EXPECT_EQ(largest, 0.0);
    else
      EXPECT_GT(largest, 0.0) << factor;
  }
  DiggingOptions d;
  d.edge_resistance = 0.5;
  EXPECT_THROW(
      DiggingSimulation(test::shared_device(), sc, fidelity_preset("D400"), PileBuild{}, d),
      InputError);
  d.edge_resistance = 1.0;
  d.excavation_reach = 0.6;  // the zone's excavation reach: type G only
  EXPECT_THROW(
      DiggingSimulation(test::shared_device(), sc, fidelity_preset("D400"), PileBuild{}, d),
      InputError);
  d.excavation_reach = 0.0;
  d.merge_speed = 4.0;  // the zone particles' merge speed: type G only
  EXPECT_THROW(
      DiggingSimulation(test::shared_device(), sc, fidelity_preset("D400"), PileBuild{}, d),
      InputError);
  d.merge_speed = kMergeSpeed;
  d.rest_in_bucket = false;  // the bucket's resting load kept in the DEM: a type-G study
  EXPECT_THROW(
      DiggingSimulation(test::shared_device(), sc, fidelity_preset("D400"), PileBuild{}, d),
      InputError);
  d.rest_in_bucket = true;
  d.failure_plane_floor = false;  // the zone's floor of voxel columns: type G only
  EXPECT_THROW(
      DiggingSimulation(test::shared_device(), sc, fidelity_preset("D400"), PileBuild{}, d),
      InputError);
  d.failure_plane_floor = true;
  d.avalanche.repose_deg = 20.0;  // the voxel surface's avalanche: type G only
  EXPECT_THROW(
      DiggingSimulation(test::shared_device(), sc, fidelity_preset("D400"), PileBuild{}, d),
      InputError);
  d.avalanche = AvalancheOptions{};
  d.avalanche.rate = 30.0;
  EXPECT_THROW(
      DiggingSimulation(test::shared_device(), sc, fidelity_preset("D400"), PileBuild{}, d),
      InputError);
  d.avalanche = AvalancheOptions{};
  // the coloured bucket sweep: type D only (a type-G bucket has no chain of particle rows)
  d.coupling.bucket_sweep = BucketSweep::Coloured;
  EXPECT_THROW(DiggingSimulation(test::shared_device(), sc, g400,
                                 build_scenario_pile(test::shared_device(), sc,
                                                     scenario_pile_profile(sc), g400, d, nullptr),
                                 d),
               InputError);
  d.coupling.bucket_sweep = BucketSweep::Serial;
  d.edge_resistance = -0.1;
  EXPECT_THROW(DiggingSimulation(test::shared_device(), sc, g400,
                                 build_scenario_pile(test::shared_device(), sc,
                                                     scenario_pile_profile(sc), g400, d, nullptr),
                                 d),
               InputError);
}

// the aggregate's interfaces' damping time, a type-G study: two of the level's steps by default,
// the study's in seconds when given, on both interfaces every step; and at G200 it, not the step,
// sets HD27's breakout (docs/validation.md "HD27's breakout follows the interfaces' damping time":
// on piles 1-3 at G200 the largest lift over 3.1-3.7 s was 263-309 kN with the default 40 ms and
// 200-220 kN with 10 ms when measured). One pile's peak is a chaotic realisation: re-measured
// 2026-12-02 with three orders of the zone's rows (DemSettings::serial_lanes 0, 8, 16) the ratio
// of a pile's peaks was 0.74-0.86, of the three piles' summed peaks 0.78-0.82. So the sum is held
// below 0.85 and each pile below 0.95. Refused at a type-D level and outside
// [kMinDampingTime, kMaxDampingTime] unless 0
TEST(Digging, TheInterfacesDampingTimeIsTwoStepsOrTheStudys) {
  const vehicle::Scenario sc = vehicle::load_scenario("hd27");
  const FidelityPreset& g200 = level_preset("G200");
  double summed[2] = {0.0, 0.0};
  for (const unsigned seed : {1u, 2u, 3u}) {
    double breakout[2] = {0.0, 0.0};
    for (const double tau : {0.0, 0.01}) {
      DiggingOptions options;
      options.pile.seed = seed;
      options.interface_damping_time = tau;
      const PileBuild pile = build_scenario_pile(test::shared_device(), sc,
                                                 scenario_pile_profile(sc), g200, options, nullptr);
      DiggingSimulation sim(test::shared_device(), sc, g200, pile, options);
      const double expected = tau > 0.0 ? tau : 2.0 * g200.dt;
      while (sim.time() < 3.7) {
        sim.step();
        ASSERT_EQ(sim.aggregate().interface_a().parameters().damping_time, expected);
        ASSERT_EQ(sim.aggregate().interface_b().parameters().damping_time, expected);
        if (sim.time() >= 3.1)
          breakout[tau > 0.0] = std::max(breakout[tau > 0.0], sim.sensors().f_lift);
      }
    }
    std::printf(
        "[ measured ] HD27-G200 pile %u: the largest lift over 3.1-3.7 s %.1f kN with the "
        "interfaces damped over two steps (40 ms), %.1f kN over 10 ms\n",
        seed, 1e-3 * breakout[0], 1e-3 * breakout[1]);
    EXPECT_LT(breakout[1], 0.95 * breakout[0]) << seed;
    summed[0] += breakout[0];
    summed[1] += breakout[1];
  }
  std::printf("[ measured ] the three piles' peaks: %.3f of the default's with 10 ms\n",
              summed[1] / summed[0]);
  EXPECT_LT(summed[1], 0.85 * summed[0]);
  DiggingOptions d;
  d.interface_damping_time = 0.01;
  EXPECT_THROW(
      DiggingSimulation(test::shared_device(), sc, fidelity_preset("D400"), PileBuild{}, d),
      InputError);
  // (the options are checked before the pile is used)
  for (const double tau : {kMaxDampingTime * 1.4, 0.5 * kMinDampingTime, -0.01}) {
    d.interface_damping_time = tau;
    EXPECT_THROW(DiggingSimulation(test::shared_device(), sc, g200, PileBuild{}, d), InputError)
        << tau;
  }
}

// the merge speed (DiggingOptions::merge_speed, a type-G study) reaches the terrain: FB35 at G400
// with particles allowed to merge below 4 m/s instead of 0.1 m/s holds fewer of them on average
// over the run (docs/multiscale.md "How many particles": pile 1, 84.3 -> 76.9 measured by talus
// run, 2026-12-01), the most at a step about the same (the zone and the bucket set those)
TEST(Digging, TheMergeSpeedReachesTheTypeGTerrain) {
  const vehicle::Scenario sc = vehicle::load_scenario("fb35");
  const FidelityPreset& g400 = level_preset("G400");
  double mean[2] = {0.0, 0.0};
  size_t most[2] = {0, 0};
  for (const int fast : {0, 1}) {
    DiggingOptions options;
    options.merge_speed = fast ? 4.0 : kMergeSpeed;
    const PileBuild pile = build_scenario_pile(test::shared_device(), sc, scenario_pile_profile(sc),
                                               g400, options, nullptr);
    DiggingSimulation sim(test::shared_device(), sc, g400, pile, options);
    sim.run([&](int) {
      mean[fast] += static_cast<double>(sim.particle_count()) / sim.steps_total();
      most[fast] = std::max(most[fast], sim.particle_count());
    });
  }
  std::printf(
      "[ measured ] FB35-G400 pile 1: %.1f particles on average, %zu at most, merging below "
      "0.1 m/s; %.1f and %zu below 4 m/s\n",
      mean[0], most[0], mean[1], most[1]);
  EXPECT_LT(mean[1], 0.97 * mean[0]);
  EXPECT_NEAR(static_cast<double>(most[1]), static_cast<double>(most[0]), 0.05 * most[0]);
}

// the bucket's resting load riding with it (DiggingOptions::rest_in_bucket, type G's default)
// reaches the terrain: FB35 at G400 on pile 1 carries some of its load as fixed particles after
// the dig, and loads what the study without it loads within 3 % (over five piles at G400 and G200
// the three scenarios' loads moved by -2.7 to +2.1 %: docs/multiscale.md "The bucket's resting
// load")
TEST(Digging, TheBucketsRestingLoadReachesTheTypeGTerrain) {
  const vehicle::Scenario sc = vehicle::load_scenario("fb35");
  const FidelityPreset& g400 = level_preset("G400");
  double loaded[2] = {0.0, 0.0}, resting[2] = {0.0, 0.0};
  for (const int rest : {0, 1}) {
    DiggingOptions options;
    options.rest_in_bucket = rest == 1;
    const PileBuild pile = build_scenario_pile(test::shared_device(), sc, scenario_pile_profile(sc),
                                               g400, options, nullptr);
    DiggingSimulation sim(test::shared_device(), sc, g400, pile, options);
    sim.run([&](int) {
      resting[rest] += static_cast<double>(sim.terrain().last_step().resting) / sim.steps_total();
    });
    loaded[rest] = sim.loaded_mass();
  }
  std::printf(
      "[ measured ] FB35-G400 pile 1: %.0f kg loaded; with the resting load riding %.0f kg, %.1f "
      "particles riding on average\n",
      loaded[0], loaded[1], resting[1]);
  EXPECT_EQ(resting[0], 0.0);
  EXPECT_GT(resting[1], 3.0);
  EXPECT_NEAR(loaded[1], loaded[0], 0.03 * loaded[0]);
}

// cohesive soil (the soil_cohesion effect) resists the bucket more: FB35 at D400 pushes the flat
// bucket deep into the pile at the traction the driveline has, and in cohesive gravel it gets less
// far by breakout (7 s). Measured with the inputs retuned in issue 11: 3.10 m dry, 2.95 m at
// 20 kPa (before them: 3.00 m dry, 2.81 m at 5 kPa, 2.74 m at 20 kPa; the mean traction barely
// moves, +5 %: the driveline is near its limit, so the soil's resistance shows as speed, not force)
TEST(Digging, CohesiveSoilResistsPenetration) {
  const vehicle::Scenario sc = vehicle::load_scenario("fb35");
  const FidelityPreset& preset = fidelity_preset("D400");
  DiggingOptions options;
  const PileBuild pile = pile_at_d400(sc, options);
  // how far the machine got [m] by breakout, and the soil's cohesion [Pa] the particles had
  auto penetration = [&](vehicle::EffectSet* effects) {
    DiggingSimulation sim(test::shared_device(), sc, preset, pile, options, effects);
    while (sim.time() < 7.0) sim.step();
    return std::make_pair(sim.log().samples().back().x_vehicle, sim.dem().material().cohesion);
  };
  vehicle::EffectSet moist;
  moist.add(vehicle::make_builtin_effect("soil_cohesion"));
  moist[0].set("cohesion", 20e3);
  const auto [dry, dry_cohesion] = penetration(nullptr);
  const auto [wet, wet_cohesion] = penetration(&moist);
  std::printf("[ measured ] FB35-D400 at breakout: machine at %.2f m in dry gravel, %.2f m with 20 kPa cohesion\n",
              dry, wet);
  EXPECT_EQ(dry_cohesion, 0.0);
  EXPECT_EQ(wet_cohesion, 20e3);
  EXPECT_LT(wet, dry - 0.1);
}

}  // namespace
}  // namespace talus
