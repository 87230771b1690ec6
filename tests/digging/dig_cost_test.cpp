// The cost breakdown of the coupled dig (digging/dig_cost): the stages add up to the profiled
// step, the stages the issue names are all measured, and profiling only watches: a dig profiled
// at every step ends bit for bit where an unprofiled one does.
#include "digging/dig_cost.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <set>

#include "host/stage_times.hpp"
#include "tests/solvers/dem_test_util.hpp"

namespace talus {
namespace {

PileBuild hd27_pile_d400(const vehicle::Scenario& sc, const DiggingOptions& options) {
  return build_scenario_pile(test::shared_device(), sc, scenario_pile_profile(sc),
                             fidelity_preset("D400"), options, nullptr);
}

// HD27 at D400, 0.6 s from dig_start (the bucket enters the pile): the stages cover the profiled
// step (their sum within 10 % of its wall time: the rest is the queue drains around the step),
// every stage of SPEC §1's coupled step shows up, and the plain step is not slower than the
// profiled one by more than the noise of a loaded machine
TEST(DigCost, StagesAddUpToTheProfiledStep) {
  const vehicle::Scenario sc = vehicle::load_scenario("hd27");
  DiggingOptions options;
  const PileBuild pile = hd27_pile_d400(sc, options);
  const DigCost cost = measure_dig_cost(test::shared_device(), sc, fidelity_preset("D400"), pile,
                                        options, 0.6, nullptr);
  double sum = 0.0;
  std::set<std::string> names;
  for (const auto& [name, ms] : cost.stages) {
    EXPECT_GE(ms, 0.0) << name;
    sum += ms;
    names.insert(name);
  }
  std::printf(
      "[ measured ] HD27-D400 over %d steps: %.2f ms plain, %.2f ms profiled, stages %.2f ms, "
      "%.0f bucket contacts\n",
      cost.steps, cost.ms_per_step, cost.profiled_ms_per_step, sum, cost.bucket_contacts);
  EXPECT_EQ(cost.steps, 30);
  EXPECT_EQ(cost.particles, pile.particles.size());
  EXPECT_LE(sum, cost.profiled_ms_per_step * 1.001);
  EXPECT_GE(sum, 0.9 * cost.profiled_ms_per_step);
  for (const char* stage :
       {"broad_phase", "narrow_phase", "colouring", "row_preparation", "warm_start",
        "particle_sweeps", "bucket_rows", "bucket_selection", "embree", "bucket_row_setup",
        "transfers", "direct_solve", "integration", "other"})
    EXPECT_EQ(names.count(stage), 1u) << stage;
  EXPECT_GT(cost.bucket_contacts, 0.0);
  EXPECT_NEAR(cost.realtime_factor, cost.dt / (1e-3 * cost.ms_per_step), 1e-12);
}

// a time beyond the scenario's dig phase is refused with the flag's name
TEST(DigCost, TooLongAMeasurementIsRefused) {
  const vehicle::Scenario sc = vehicle::load_scenario("hd27");
  DiggingOptions options;
  const PileBuild pile = hd27_pile_d400(sc, options);
  try {
    measure_dig_cost(test::shared_device(), sc, fidelity_preset("D400"), pile, options, 100.0,
                     nullptr);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::strstr(e.what(), "--seconds"), nullptr) << e.what();
  }
}

// profiling drains the queue but changes no number: the same dig with the stage clock on at
// every step ends with bit-identical particles and machine
TEST(DigCost, ProfilingChangesNoResult) {
  const vehicle::Scenario sc = vehicle::load_scenario("hd27");
  DiggingOptions options;
  const PileBuild pile = hd27_pile_d400(sc, options);
  const FidelityPreset& preset = fidelity_preset("D400");
  Device& dev = test::shared_device();
  const int steps = static_cast<int>(std::lround(2.0 / preset.dt));  // into the pile
  DiggingSimulation plain(dev, sc, preset, pile, options);
  for (int k = 0; k < steps; ++k) plain.step();
  DiggingSimulation profiled(dev, sc, preset, pile, options);
  StageTimes times;
  dev.set_stage_times(&times);
  for (int k = 0; k < steps; ++k) profiled.step();
  dev.set_stage_times(nullptr);
  EXPECT_FALSE(times.totals().empty());
  const Particles a = plain.particles(), b = profiled.particles();
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a.position[i], b.position[i]) << "particle " << i;
    ASSERT_EQ(a.velocity[i], b.velocity[i]) << "particle " << i;
  }
  EXPECT_EQ(plain.loader().bucket_tip_world(), profiled.loader().bucket_tip_world());
  EXPECT_GT(plain.split().stats().bucket_contacts, 0);
}

}  // namespace
}  // namespace talus
