// The sweep's measures (digging/feedback_sweep): best productivity and the paper's domain gap,
// domain shift and performance drop (paper §7.2), on results whose answers are known by hand.
#include "digging/feedback_sweep.hpp"

#include <algorithm>
#include <cstdio>

#include <gtest/gtest.h>

#include "terrain/aggregate.hpp"
#include "tests/solvers/dem_test_util.hpp"
#include "vehicle/wheel_loader.hpp"

namespace talus {
namespace {

// FB35's pile at a level, placed 5 m ahead (paper §7.1) with a 40 s cycle
CyclePile fb35_cycle_pile(const FidelityPreset& level, const DiggingOptions& options) {
  return build_cycle_pile(test::shared_device(), vehicle::load_scenario("fb35"), 5.0, 40.0, level,
                          options, nullptr);
}

CycleResult result(double s, double mass, double time, bool completed = true) {
  CycleResult r;
  r.s = s;
  r.loaded_mass_kg = mass;
  r.cycle_time_s = time;
  r.work_J = 1e5;
  r.completed = completed;
  return r;
}

TEST(FeedbackSweep, BestProductivityIgnoresUnfinishedCycles) {
  // M/T = 300, 400, 350 kg/s; an unfinished cycle would read 1000 kg/s
  const std::vector<CycleResult> r = {result(0.0, 3000, 10), result(0.5, 3200, 8), result(1.0, 2800, 8),
                                      result(0.25, 5000, 5, false)};
  const SweepOptimum best = best_productivity(r);
  EXPECT_DOUBLE_EQ(best.s, 0.5);
  EXPECT_DOUBLE_EQ(best.productivity, 400.0);
}

TEST(FeedbackSweep, DomainTransferAsThePaperDefinesIt) {
  // tuned in A (best 416 kg/s at s = 0.42), used in B (best 366 kg/s at s = 0.36): gap 50 kg/s
  // (13.7 % of B's best), shift 0.06; B at A's optimum, halfway between B's samples at 0.36 and
  // 0.48 (366 and 346 kg/s), gives 356 kg/s: a drop of 10/366
  const std::vector<CycleResult> a = {result(0.30, 3900, 10), result(0.42, 4160, 10), result(0.54, 4000, 10)};
  const std::vector<CycleResult> b = {result(0.24, 3400, 10), result(0.36, 3660, 10), result(0.48, 3460, 10)};
  const DomainTransfer d = domain_transfer(a, b);
  EXPECT_NEAR(d.gap_kg_s, 50.0, 1e-9);
  EXPECT_NEAR(d.gap_rel, 50.0 / 366.0, 1e-12);
  EXPECT_NEAR(d.shift, 0.06, 1e-12);
  EXPECT_NEAR(d.drop_rel, 10.0 / 366.0, 1e-12);
}

TEST(FeedbackSweep, FeedbackScenarioStartsFiveMetresFromThePile) {
  const vehicle::Scenario base = vehicle::load_scenario("fb35");
  const vehicle::Scenario s = feedback_scenario(base, 5.0, 30.0);
  // the machine's reference pose has its bucket tip at x = 2.70 m (data/machines/wa320.json)
  EXPECT_NEAR(s.pile_toe_x, 2.70 + 5.0, 1e-9);
  EXPECT_DOUBLE_EQ(s.duration, 30.0);
  EXPECT_THROW(feedback_scenario(vehicle::load_scenario("flat-lift"), 5.0, 30.0), InputError);
}

// a force-feedback cycle on the type-G terrain completes and fills the bucket (~3 s): the cycle
// finds the pile by the voxels' laser scan, and a one-particle aggregate once left the vehicle's
// direct solver cycling here (issue 14)
TEST(FeedbackSweep, ACycleOnTheTypeGTerrainCompletesAndFills) {
  const FidelityPreset& g400 = level_preset("G400");
  const DiggingOptions options;
  const CyclePile cycle = fb35_cycle_pile(g400, options);
  ASSERT_GT(cycle.surface.back().second, 1.5);  // the scan sees the pile, not bare ground
  const CycleResult r = run_feedback_cycle(test::shared_device(), cycle, g400, options, 0.0);
  std::printf(
      "[ measured ] FB35-G400 force-feedback cycle at s = 0: %.0f kg in %.1f s, work %.0f kJ\n",
      r.loaded_mass_kg, r.cycle_time_s, 1e-3 * r.work_J);
  EXPECT_TRUE(r.completed);
  EXPECT_GT(r.loaded_mass_kg, 500.0);
}

// the caller commands the fill (what an agent does): given the controller's own targets it gives
// the controller's cycle bit for bit, and outside the fill it is refused
TEST(FeedbackSweep, ACallerCommandingTheFillWithTheControllersTargetsGivesTheSameCycle) {
  const FidelityPreset& g400 = level_preset("G400");
  const DiggingOptions options;
  const CyclePile cycle = fb35_cycle_pile(g400, options);
  const double s = 0.7;
  const CycleResult own = run_feedback_cycle(test::shared_device(), cycle, g400, options, s);

  LoadingCycle run(test::shared_device(), cycle, g400, options, vehicle::gains_on_search_line(s));
  ASSERT_EQ(run.phase(), vehicle::CyclePhase::Approach);
  EXPECT_THROW(run.step_fill({}), Error);
  int fill_steps = 0;
  while (!run.done()) {
    if (run.phase() != vehicle::CyclePhase::Fill) {
      run.step();
      continue;
    }
    // the controller's law, computed here from the machine's sensors as a caller would
    const vehicle::SensorSample now =
        vehicle::read_sensors(run.simulation().loader(), run.simulation().time());
    run.step_fill(run.cycle().targets(now));
    ++fill_steps;
  }
  const CycleResult mine = run.result(s);
  EXPECT_GT(fill_steps, 10);
  EXPECT_TRUE(mine.completed);
  EXPECT_EQ(mine.loaded_mass_kg, own.loaded_mass_kg);
  EXPECT_EQ(mine.cycle_time_s, own.cycle_time_s);
  EXPECT_EQ(mine.work_J, own.work_J);
  EXPECT_EQ(mine.breakout_s, own.breakout_s);
  EXPECT_EQ(run.cycle().broke_out(), own.breakout_s - own.fill_start_s <= 15.0);
}

// the s = 0.45 cycle at G400 drives its bucket into the pile's rear wall during the fill: the wall
// stops the bucket (it used to pass through while the wall held its load back: the s = 0.35 cycle
// ended with 0 kg after 708 kJ; docs/multiscale.md), and the cycle ends with its load (4.67 t
// measured). Since the bucket's body pushes the soil it overlaps aside (aecd10d) the s = 0.35
// cycle no longer reaches the wall, so the test takes one that does (388 kN on the wall). Since
// the terrain holds the bucket's bottom up (2026-11-29, terrain/bucket_support) no cycle on the
// search line reaches the wall at G400 (s = 0 ... 1 in tenths, 0.35, 0.45, 0.55: 0.28 m short at
// the closest), so the test lets the soil under the bucket give way (the study option) to drive a
// bucket into the wall. Since the zone's particles stand on its failure plane (2026-11-30) the
// s = 0.45 cycle stops 0.22 m short of it and s = 0.40 meets it (316 kN; 0.30-0.55 and 0.80 reach
// it too, 0.60-0.70 do not)
TEST(FeedbackSweep, ABucketDrivenIntoThePilesRearWallStopsThereWithItsLoad) {
  constexpr double kS = 0.40;  // the controller's point on its search line
  const FidelityPreset& g400 = level_preset("G400");
  DiggingOptions options;
  options.bucket_support = false;
  const CyclePile cycle = fb35_cycle_pile(g400, options);
  const double wall_x = scenario_pile_profile(cycle.scenario).rear_wall_x;
  LoadingCycle run(test::shared_device(), cycle, g400, options, vehicle::gains_on_search_line(kS));
  double deepest = -INFINITY, most_force = 0.0;
  while (!run.done()) {
    run.step();
    const vehicle::WheelLoader& loader = run.simulation().loader();
    for (int v = 0; v < static_cast<int>(loader.bucket_mesh().vertices.size()); ++v)
      deepest = std::max(deepest, loader.bucket_mesh_vertex_world(v).x() - wall_x);
    for (const vehicle::PointGroundContact* w : loader.bucket_walls())
      most_force = std::max(most_force, w->normal_force());
  }
  const CycleResult r = run.result(kS);
  std::printf(
      "[ measured ] FB35-G400 s = %.2f: %.0f kg in %.1f s, bucket at most %.4f m past the rear "
      "wall, largest wall force %.0f kN\n",
      kS, r.loaded_mass_kg, r.cycle_time_s, deepest, 1e-3 * most_force);
  EXPECT_TRUE(r.completed);
  EXPECT_GT(most_force, 0.0);  // it did reach the wall
  // the machine (17 t at 2.2 m/s) meets the wall within a 50 ms step and the stiff rows push the
  // bucket out over their damping time: about a centimetre in at the worst (before: 3 m through)
  EXPECT_LT(deepest, 0.03);
  EXPECT_GT(r.loaded_mass_kg, 3000.0);
}

// the zone's soil surface once counted the bucket's own load: a full bucket at the rear wall, its
// edge above the terrain, read as 1.6-1.8 m of soil over its edge, so the penetration resistance
// (about 100 kN) and the interfaces held it while the controller lifted, the chassis pitched nose
// down to -38 degrees in the fill and -56 in the retreat, and the uncurled bucket spilled all but
// 0.33 t (s = 0.40, docs/multiscale.md). The machine now stays on its wheels and keeps its load
TEST(FeedbackSweep, AFullBucketAtTheRearWallDoesNotTipTheMachineOntoIt) {
  constexpr double kS = 0.40;  // the cycle that stood on its bucket
  const FidelityPreset& g400 = level_preset("G400");
  const DiggingOptions options;
  const CyclePile cycle = fb35_cycle_pile(g400, options);
  LoadingCycle run(test::shared_device(), cycle, g400, options, vehicle::gains_on_search_line(kS));
  double most_nose_down = 0.0;
  while (!run.done()) {
    run.step();
    most_nose_down = std::min(most_nose_down, run.simulation().sensors().pitch_deg);
  }
  const CycleResult r = run.result(kS);
  std::printf(
      "[ measured ] FB35-G400 s = %.2f: %.0f kg in %.1f s, pitch at most %.1f deg nose down\n", kS,
      r.loaded_mass_kg, r.cycle_time_s, -most_nose_down);
  EXPECT_TRUE(r.completed);
  // a loader pitches a few degrees as it pushes and lifts into the pile (the G400 sweep's
  // 21 cycles: at most 10.3); the handstand reached 56
  EXPECT_GT(most_nose_down, -15.0);
  EXPECT_GT(r.loaded_mass_kg, 3000.0);
}

// before the terrain's first step the aggregate's interfaces stood on an empty zone of zero width:
// zero stiffness, an infinite compliance in the machine's system, and the first step of every
// type-G run pushed the machine back at up to 1 m/s. Now the first step of the approach is the
// machine's own: the same as the machine alone, settled the same way, to round-off with the
// bucket's content as a weight; as a body (the default) the empty bucket carries the payload's
// 1 kg stand-in, whose share of the machine's mass is its share of the speed (measured 2.2e-5
// m/s of 0.33, 7e-5)
TEST(FeedbackSweep, TheTypeGApproachStartsAsTheMachineAlone) {
  const FidelityPreset& g400 = level_preset("G400");
  // the machine alone: settled 1 s at rest (digging/digging's settling), then one step driving
  vehicle::WheelLoader alone(vehicle::machine_file(vehicle::load_scenario("fb35")),
                             vehicle::load_scenario("fb35").payload);
  alone.set_drive_speed(0.0);
  alone.set_lift_speed(0.0);
  alone.set_tilt_speed(0.0);
  for (int k = 0; k < static_cast<int>(std::lround(1.0 / g400.dt)); ++k) alone.step(g400.dt);
  alone.set_drive_speed(vehicle::CycleSettings().drive_speed);  // the approach's
  alone.step(g400.dt);
  const double alone_speed = alone.system().body(alone.front_frame()).velocity.x();
  double machine_mass = 0.0;
  for (const auto& b : alone.bodies()) machine_mass += b.mass;

  for (const bool content_inertia : {false, true}) {
    DiggingOptions options;
    options.content_inertia = content_inertia;
    const CyclePile cycle = fb35_cycle_pile(g400, options);
    LoadingCycle run(test::shared_device(), cycle, g400, options,
                     vehicle::gains_on_search_line(0.0));
    run.step();
    const vehicle::WheelLoader& in_cycle = run.simulation().loader();
    const double cycle_speed = in_cycle.system().body(in_cycle.front_frame()).velocity.x();
    std::printf(
        "[ measured ] first step of the approach (content %s): %.6f m/s in the G400 cycle, "
        "%.6f alone\n",
        content_inertia ? "a body" : "a weight", cycle_speed, alone_speed);
    EXPECT_GT(cycle_speed, 0.0);
    const double share = content_inertia ? 2.0 * kIdlePayloadMass / machine_mass : 0.0;
    EXPECT_NEAR(cycle_speed, alone_speed, 1e-6 + share * alone_speed) << content_inertia;
  }
}

}  // namespace
}  // namespace talus
