// The embedding facade (embed/talus.hpp): a Simulation made from options, stepped with the caller's
// targets or the scenario's, read through plain types. These tests hold it to what the layers
// below do (the machine moves as told, the channels are the contract's, the particles are the
// pile's) and to one clear error per bad option.
#include "embed/talus.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "digging/feedback_sweep.hpp"
#include "solvers/particles.hpp"
#include "tests/solvers/dem_test_util.hpp"
#include "vehicle/effect_plugin.hpp"
#include "vehicle/sensor_channels.hpp"

namespace talus {
namespace {

namespace fs = std::filesystem;

// a fresh folder per test (ctest runs them in separate processes, maybe in parallel)
fs::path fresh_temp_dir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  fs::path dir = fs::temp_directory_path() /
                 ("talus-embed-" + std::string(info->name()) + "-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

SimulationOptions vehicle_only() {
  SimulationOptions o;
  o.scenario = "flat-lift";
  return o;
}

// steps with the same targets for `seconds`
void hold(Simulation& sim, const Targets& targets, double seconds) {
  const long steps = std::lround(seconds / sim.timestep());
  for (long k = 0; k < steps; ++k) sim.step(targets);
}

// the machine alone: a lift target raises the boom by its stroke speed times the time (the
// cylinders follow their targets within their force limits, vehicle/wheel_loader.hpp), a drive
// target moves the machine, and the clock counts the steps
TEST(Simulation, LiftAndDriveTargetsMoveTheMachine) {
  Simulation sim(vehicle_only());
  EXPECT_EQ(sim.level(), "vehicle");
  EXPECT_FALSE(sim.has_particles());
  EXPECT_DOUBLE_EQ(sim.time(), 0.0);
  const SensorReading start = sim.sensors();
  // 1 s of lift at 0.1 m/s, standing
  Targets lift;
  lift.lift = 0.1;
  hold(sim, lift, 1.0);
  EXPECT_NEAR(sim.time(), 1.0, 1e-12);
  const SensorReading lifted = sim.sensors();
  EXPECT_NEAR(lifted.d_lift - start.d_lift, 0.1, 0.02);
  EXPECT_GT(lifted.boom_deg, start.boom_deg + 2.0);
  EXPECT_GT(lifted.bucket_tip_z, start.bucket_tip_z);
  // then 1 s of drive at 1 m/s: the machine moves forward, the boom holds
  Targets drive;
  drive.drive = 1.0;
  hold(sim, drive, 1.0);
  const SensorReading driven = sim.sensors();
  EXPECT_GT(driven.x_vehicle - lifted.x_vehicle, 0.5);
  EXPECT_NEAR(driven.v_drive, 1.0, 0.1);
  EXPECT_NEAR(driven.d_lift, lifted.d_lift, 0.01);
  // the vehicle's bucket carries the scenario's payload
  EXPECT_DOUBLE_EQ(sim.loaded_mass(), 3500.0);
}

// step() follows the scenario's own inputs, which scenario_targets() reports: flat-lift stands
// still for its first 0.5 s, then accelerates to 1.5 m/s by 1.5 s (data/scenarios/flat-lift.json)
TEST(Simulation, StepWithoutTargetsReplaysTheScenario) {
  Simulation sim(vehicle_only());
  EXPECT_DOUBLE_EQ(sim.scenario_targets().drive, 0.0);
  while (sim.time() < 1.5 - 1e-9) sim.step();
  EXPECT_NEAR(sim.scenario_targets().drive, 1.5, 1e-9);
  EXPECT_GT(sim.sensors().v_drive, 1.0);
  EXPECT_FALSE(sim.done());
  EXPECT_DOUBLE_EQ(sim.duration(), 14.0);
}

// the channels are the run contract's (vehicle/sensor_channels.hpp), in its order, with its
// units; the map, the struct and the 100 Hz log say the same
TEST(Simulation, ChannelsAreTheContractsByNameStructAndLog) {
  ASSERT_EQ(Simulation::channel_names().size(), vehicle::kChannelCount);
  ASSERT_EQ(Simulation::channel_units().size(), vehicle::kChannelCount);
  for (std::size_t c = 0; c < vehicle::kChannelCount; ++c) {
    EXPECT_EQ(Simulation::channel_names()[c], vehicle::kSensorChannels[c].name);
    EXPECT_EQ(Simulation::channel_units()[c], vehicle::kSensorChannels[c].unit);
  }
  Simulation sim(vehicle_only());
  Targets targets;
  targets.drive = 1.0;
  targets.lift = 0.05;
  hold(sim, targets, 0.5);
  const std::map<std::string, double> values = sim.channels();
  ASSERT_EQ(values.size(), vehicle::kChannelCount);
  // the header's field of each name, spelled here a second time on purpose
  const std::pair<const char*, double SensorReading::*> fields[] = {
      {"t", &SensorReading::t},
      {"f_lift", &SensorReading::f_lift},
      {"f_tilt", &SensorReading::f_tilt},
      {"f_traction", &SensorReading::f_traction},
      {"v_drive", &SensorReading::v_drive},
      {"d_lift", &SensorReading::d_lift},
      {"d_tilt", &SensorReading::d_tilt},
      {"boom_deg", &SensorReading::boom_deg},
      {"bucket_deg", &SensorReading::bucket_deg},
      {"pitch_deg", &SensorReading::pitch_deg},
      {"x_vehicle", &SensorReading::x_vehicle},
      {"bucket_tip_x", &SensorReading::bucket_tip_x},
      {"bucket_tip_z", &SensorReading::bucket_tip_z},
      {"power", &SensorReading::power}};
  const SensorReading now = sim.sensors();
  for (const auto& [name, field] : fields) {
    ASSERT_EQ(values.count(name), 1u) << name;
    EXPECT_DOUBLE_EQ(values.at(name), now.*field) << name;
  }
  // the log: 100 Hz from t = 0, its last sample the reading now (0.5 s is a sampling instant)
  const std::vector<SensorReading> log = sim.sensor_log();
  ASSERT_EQ(log.size(), 51u);
  for (std::size_t k = 0; k < log.size(); ++k) EXPECT_NEAR(log[k].t, 0.01 * k, 1e-9);
  EXPECT_DOUBLE_EQ(log.back().d_lift, now.d_lift);
  EXPECT_DOUBLE_EQ(log.back().f_traction, now.f_traction);
}

// a moved simulation goes on where it was
TEST(Simulation, MovesWithItsState) {
  Simulation a(vehicle_only());
  Targets lift;
  lift.lift = 0.1;
  hold(a, lift, 0.2);
  const double d_lift = a.sensors().d_lift;
  Simulation b(std::move(a));
  EXPECT_NEAR(b.time(), 0.2, 1e-12);
  EXPECT_DOUBLE_EQ(b.sensors().d_lift, d_lift);
  b.step(lift);
  EXPECT_GT(b.sensors().d_lift, d_lift);
}

// HD27 at D400: the pile is built and settled, its particles come as flat arrays of the right
// sizes with the level's radii (D 0.4 m +- 10 %, terrain/pile.hpp), the timestep is the level's,
// and the caller's targets drive the machine into the pile and lift the boom
TEST(Simulation, PileScenarioGivesParticlesAndTakesTargets) {
  SimulationOptions o;
  o.scenario = "HD27";  // any case, as summaries spell it
  o.level = "D400";
  Simulation sim(o);
  EXPECT_TRUE(sim.has_particles());
  EXPECT_EQ(sim.scenario_name(), "HD27");
  EXPECT_EQ(sim.level(), "D400");
  EXPECT_DOUBLE_EQ(sim.timestep(), 0.02);  // paper Table 3
  EXPECT_FALSE(sim.device().empty());
  const std::size_t n = sim.particle_count();
  ASSERT_GT(n, 100u);
  const ParticleState p = sim.particles();
  ASSERT_EQ(p.size(), n);
  ASSERT_EQ(p.position.size(), 3 * n);
  ASSERT_EQ(p.velocity.size(), 3 * n);
  ASSERT_EQ(p.angular_velocity.size(), 3 * n);
  for (std::size_t i = 0; i < n; ++i) {
    EXPECT_GE(p.radius[i], 0.5 * 0.4 * 0.9 - 1e-9);
    EXPECT_LE(p.radius[i], 0.5 * 0.4 * 1.1 + 1e-9);
    // settled: above the ground, in front of the machine's front axle (x = 0)
    EXPECT_GT(p.position[3 * i + 2], 0.0);
    EXPECT_GT(p.position[3 * i], 0.0);
  }
  // the pile starts in front of the bucket, which holds nothing
  EXPECT_DOUBLE_EQ(sim.loaded_mass(), 0.0);
  // 0.4 s of the caller's lift and drive (20 steps): the boom rises, the machine moves
  const SensorReading start = sim.sensors();
  Targets targets;
  targets.drive = 1.0;
  targets.lift = 0.1;
  hold(sim, targets, 0.4);
  EXPECT_NEAR(sim.time(), 0.4, 1e-12);
  const SensorReading moved = sim.sensors();
  EXPECT_NEAR(moved.t, 0.4, 1e-12);
  EXPECT_GT(moved.d_lift - start.d_lift, 0.02);
  EXPECT_GT(moved.boom_deg, start.boom_deg);
  EXPECT_GT(moved.x_vehicle - start.x_vehicle, 0.1);
  // the log is at 100 Hz whatever the level's 20 ms step: 41 samples over 0.4 s
  EXPECT_EQ(sim.sensor_log().size(), 41u);
  EXPECT_EQ(sim.particles().size(), n);
}

// the soil's mass by where it is: at D400 the particles' alone, their masses' sum, unchanged by
// digging; at G400 the voxels, the pool and the zone's particles, whose sum a scenario's dig keeps
// to round-off while soil moves between them; the machine alone has none
TEST(Simulation, SoilMassIsThePilesAndDiggingKeepsIt) {
  SimulationOptions o;
  o.scenario = "hd27";
  o.level = "D400";
  Simulation d(o);
  const SoilMass d0 = d.soil_mass();
  EXPECT_EQ(d0.solid, 0.0);
  EXPECT_EQ(d0.pool, 0.0);
  // the particles' own masses: gravel spheres at its density; the device keeps radii and inverse
  // masses in single precision, so the two sums agree to about 1e-7 of a grain each
  double spheres = 0.0;
  for (double r : d.particles().radius) spheres += gravel().density * 4.0 / 3.0 * M_PI * r * r * r;
  EXPECT_NEAR(d0.particles, spheres, 1e-6 * spheres);
  while (d.time() < 3.0) d.step();
  EXPECT_NEAR(d.soil_mass().total(), d0.total(), 1e-9 * d0.total());

  o.level = "G400";
  Simulation g(o);
  const SoilMass g0 = g.soil_mass();
  ASSERT_GT(g0.solid, 1e4);  // the pile, as voxels
  double most_particles = 0.0;
  while (g.time() < 6.0) {
    g.step();
    const SoilMass m = g.soil_mass();
    most_particles = std::max(most_particles, m.particles);
    EXPECT_NEAR(m.total(), g0.total(), 1e-9 * g0.total()) << "t = " << g.time();
  }
  EXPECT_GT(most_particles, 100.0);  // soil did move into the zone's particles
  EXPECT_LT(g.soil_mass().solid, g0.solid);

  o.scenario = "load-carry";
  EXPECT_EQ(Simulation(o).soil_mass().total(), 0.0);
}

// a name that is neither a file nor a shipped scenario: one error naming the option, where it
// looked and what to give instead
TEST(Simulation, UnknownScenarioIsOneClearInputError) {
  SimulationOptions o;
  o.scenario = "no-such-scenario";
  try {
    Simulation sim(o);
    FAIL() << "no error";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("SimulationOptions::scenario 'no-such-scenario'"), std::string::npos)
        << what;
    EXPECT_NE(what.find("scenarios"), std::string::npos) << what;
    EXPECT_NE(what.find("hd27"), std::string::npos) << what;
    EXPECT_NE(what.find("path of a scenario file"), std::string::npos) << what;
  }
}

TEST(Simulation, UnknownLevelNamesTheOptionAndTheLevels) {
  SimulationOptions o = vehicle_only();
  o.level = "D300";
  try {
    Simulation sim(o);
    FAIL() << "no error";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("SimulationOptions::level"), std::string::npos) << what;
    EXPECT_NE(what.find("D300"), std::string::npos) << what;
    EXPECT_NE(what.find("D400"), std::string::npos) << what;
  }
}

// a scenario file's own mistakes are named by file and field (vehicle/scenario.hpp), and a
// payload the machine cannot hold is refused as talus run refuses it
TEST(Simulation, BadScenarioFileNamesFileAndField) {
  const fs::path dir = fresh_temp_dir();
  const fs::path heavy = dir / "heavy.json";
  std::ofstream(heavy) << R"({"name": "heavy", "machine": "wa320", "duration": 1, "timestep": 0.005,
    "payload": 1e12, "drive": [[0, 0]], "lift": [[0, 0]], "tilt": [[0, 0]]})";
  SimulationOptions o;
  o.scenario = heavy.string();
  try {
    Simulation sim(o);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(heavy.string() + ": field 'payload'"), std::string::npos)
        << e.what();
  }
  fs::remove_all(dir);
}

// SimulationOptions::data_dir is searched for the scenario and for the machine it names: a data
// folder of its own, with a scenario and a machine only it has
TEST(Simulation, DataDirIsSearchedForScenarioAndMachine) {
  const fs::path dir = fresh_temp_dir();
  fs::create_directories(dir / "scenarios");
  fs::create_directories(dir / "machines");
  fs::copy_file(fs::path(TALUS_SOURCE_DIR) / "data/machines/wa320.json",
                dir / "machines/embed-test-machine.json");
  std::ofstream(dir / "scenarios/embed-test.json")
      << R"({"name": "embed-test", "machine": "embed-test-machine", "duration": 0.5,
    "timestep": 0.005, "drive": [[0, 0]], "lift": [[0, 0.1]], "tilt": [[0, 0]]})";
  SimulationOptions o;
  o.scenario = "embed-test";
  o.data_dir = dir.string();
  {
    Simulation sim(o);
    EXPECT_EQ(sim.scenario_name(), "embed-test");
    const double d_lift = sim.sensors().d_lift;
    while (!sim.done()) sim.step();
    EXPECT_NEAR(sim.time(), 0.5, 1e-12);
    EXPECT_GT(sim.sensors().d_lift, d_lift + 0.03);
  }
  // without the folder the name is unknown, and the error says where it looked
  o.data_dir.clear();
  EXPECT_THROW(Simulation{o}, InputError);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace talus

namespace talus {
namespace {

// the loading cycle through the facade equals `talus sweep`'s cycle on the same pile (G400: a
// cycle in about a second), and its phases run in the paper's order
TEST(Simulation, LoadingCycleIsTheSweepsCycle) {
  SimulationOptions options;
  options.scenario = "fb35";
  options.level = "G400";
  options.loading_cycle = true;
  options.cycle_s = 0.7;
  Simulation sim(options);
  EXPECT_EQ(sim.cycle_phase(), "approach");
  EXPECT_DOUBLE_EQ(sim.duration(), options.cycle_max_time);
  std::vector<std::string> phases = {sim.cycle_phase()};
  while (!sim.done()) {
    sim.step();
    if (sim.cycle_phase() != phases.back()) phases.push_back(sim.cycle_phase());
  }
  EXPECT_EQ(phases, (std::vector<std::string>{"approach", "fill", "hold", "retreat", "done"}));
  const CycleSummary c = sim.cycle_summary();
  EXPECT_TRUE(c.completed);
  EXPECT_TRUE(c.broke_out);
  EXPECT_LT(c.fill_start, c.fill_end);
  EXPECT_EQ(c.work, sim.work());

  // the same cycle below the facade, on the pile the sweep builds
  const FidelityPreset& g400 = level_preset("G400");
  const DiggingOptions dig;
  const CyclePile pile =
      build_cycle_pile(test::shared_device(), vehicle::load_scenario("fb35"),
                       options.cycle_approach, options.cycle_max_time, g400, dig, nullptr);
  const CycleResult r = run_feedback_cycle(test::shared_device(), pile, g400, dig, 0.7);
  EXPECT_EQ(c.loaded_mass, r.loaded_mass_kg);
  EXPECT_EQ(c.cycle_time, r.cycle_time_s);
  EXPECT_EQ(c.work, r.work_J);
}

// the caller commands the fill only; a replay has no cycle; bad cycle options name the option
TEST(Simulation, LoadingCycleTakesTheCallersTargetsOnlyInTheFill) {
  SimulationOptions options;
  options.scenario = "fb35";
  options.level = "G400";
  options.loading_cycle = true;
  Simulation sim(options);
  EXPECT_THROW(sim.step(Targets{1.0, 0.0, 0.0}), Error);
  while (sim.cycle_phase() == "approach") sim.step();
  ASSERT_EQ(sim.cycle_phase(), "fill");
  const Targets top = sim.top_speeds();
  EXPECT_GT(top.drive, 0.0);
  EXPECT_GT(top.lift, 0.0);
  EXPECT_GT(top.tilt, 0.0);
  const double d_lift = sim.sensors().d_lift;
  for (int k = 0; k < 10; ++k) sim.step(Targets{0.5, top.lift, 0.0});
  EXPECT_GT(sim.sensors().d_lift, d_lift + 0.2 * top.lift * 10 * sim.timestep());

  SimulationOptions replay;
  replay.scenario = "flat-lift";
  EXPECT_THROW(Simulation(replay).cycle_summary(), Error);
  EXPECT_EQ(Simulation(replay).cycle_phase(), "");
  replay.loading_cycle = true;
  EXPECT_THROW(Simulation{replay}, InputError);
  options.cycle_s = -0.1;
  try {
    Simulation bad(options);
    ADD_FAILURE() << "cycle_s -0.1 was taken";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("SimulationOptions::cycle_s"), std::string::npos)
        << e.what();
  }
}

// model extensions through the facade (SimulationOptions::effects): a sensor bias shifts exactly
// its channel by its offset and nothing else; a lag on the cylinders slows the lift stroke
TEST(SimulationEffects, ABiasShiftsItsChannelOnlyAndALagSlowsTheLift) {
  SimulationOptions o = vehicle_only();
  Simulation plain(o);
  o.effects = {"sensor_bias:channel=f_lift,bias=1000"};
  Simulation biased(o);
  o.effects = {"hydraulic_lag:time_constant=0.3"};
  Simulation lagged(o);
  Targets lift;
  lift.lift = 0.1;
  for (Simulation* s : {&plain, &biased, &lagged}) hold(*s, lift, 1.0);
  const std::vector<SensorReading> a = plain.sensor_log(), b = biased.sensor_log();
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t k = 0; k < a.size(); ++k) {
    EXPECT_DOUBLE_EQ(b[k].f_lift - a[k].f_lift, 1000.0) << "sample " << k;
    EXPECT_EQ(b[k].d_lift, a[k].d_lift) << "sample " << k;
    EXPECT_EQ(b[k].f_tilt, a[k].f_tilt) << "sample " << k;
  }
  // a first-order lag of 0.3 s behind a step: after 1 s the stroke is short by about 0.3 s of
  // motion (0.03 m at 0.1 m/s; the unlagged cylinder also accelerates, so at least half of it)
  const double shortfall = plain.sensors().d_lift - lagged.sensors().d_lift;
  EXPECT_GT(shortfall, 0.015);
  EXPECT_LT(shortfall, 0.04);
}

// a dig with an effect through the facade is the dig below it with the same effect, bit for bit
TEST(SimulationEffects, ADigWithAnEffectIsTheDigBelowIt) {
  SimulationOptions o;
  o.scenario = "hd27";
  o.level = "D400";
  o.effects = {"engine_power_sharing"};
  Simulation sim(o);
  for (int k = 0; k < 150; ++k) sim.step();

  const vehicle::Scenario sc = vehicle::load_scenario("hd27");
  const FidelityPreset& preset = level_preset("D400");
  DiggingOptions dig;
  const PileBuild pile = build_scenario_pile(test::shared_device(), sc, scenario_pile_profile(sc),
                                             preset, dig, nullptr);
  vehicle::EffectSet effects;
  effects.add(vehicle::make_effect("engine_power_sharing"));
  DiggingSimulation below(test::shared_device(), sc, preset, pile, dig, &effects);
  for (int k = 0; k < 150; ++k) below.step();
  const std::vector<SensorReading> log = sim.sensor_log();
  const std::vector<vehicle::SensorSample>& expected = below.log().samples();
  ASSERT_EQ(log.size(), expected.size());
  for (std::size_t k = 0; k < log.size(); ++k) {
    EXPECT_EQ(log[k].f_lift, expected[k].f_lift) << "sample " << k;
    EXPECT_EQ(log[k].f_traction, expected[k].f_traction) << "sample " << k;
    EXPECT_EQ(log[k].x_vehicle, expected[k].x_vehicle) << "sample " << k;
  }
  EXPECT_EQ(sim.work(), below.log().work());
  // and the effect acts: the baseline machine drives differently over the same steps
  o.effects.clear();
  Simulation plain(o);
  for (int k = 0; k < 150; ++k) plain.step();
  EXPECT_NE(plain.sensors().f_traction, sim.sensors().f_traction);
  EXPECT_NE(plain.work(), sim.work());
}

// the loading cycle with an effect through the facade is LoadingCycle with the same effect, bit for
// bit over the whole cycle, and the effect acts: a biased boom-force sensor misleads the force-
// feedback controller, so the cycle ends differently from the baseline's
TEST(SimulationEffects, ALoadingCycleWithAnEffectIsTheCycleBelowIt) {
  SimulationOptions o;
  o.scenario = "fb35";
  o.level = "G400";
  o.loading_cycle = true;
  o.cycle_s = 0.7;
  o.effects = {"sensor_bias:channel=f_lift,bias=30000"};
  Simulation sim(o);
  while (!sim.done()) sim.step();
  const CycleSummary facade = sim.cycle_summary();

  const FidelityPreset& preset = level_preset("G400");
  const DiggingOptions dig;
  const CyclePile pile = build_cycle_pile(test::shared_device(), vehicle::load_scenario("fb35"),
                                          o.cycle_approach, o.cycle_max_time, preset, dig, nullptr);
  vehicle::EffectSet effects;
  effects.add(vehicle::make_effect("sensor_bias:channel=f_lift,bias=30000"));
  LoadingCycle below(test::shared_device(), pile, preset, dig, vehicle::gains_on_search_line(0.7),
                     &effects);
  while (!below.done()) below.step();
  const CycleResult expected = below.result(0.7);
  std::printf("[ measured ] FB35-G400 s = 0.7, f_lift biased +30 kN: %.0f kg in %.2f s, %.0f kJ\n",
              facade.loaded_mass, facade.cycle_time, 1e-3 * facade.work);
  EXPECT_EQ(facade.loaded_mass, expected.loaded_mass_kg);
  EXPECT_EQ(facade.cycle_time, expected.cycle_time_s);
  EXPECT_EQ(facade.work, expected.work_J);
  const std::vector<SensorReading> log = sim.sensor_log();
  const std::vector<vehicle::SensorSample>& samples = below.simulation().log().samples();
  ASSERT_EQ(log.size(), samples.size());
  for (std::size_t k = 0; k < log.size(); ++k)
    ASSERT_EQ(log[k].f_lift, samples[k].f_lift) << "sample " << k;

  // the baseline machine's cycle is another one
  o.effects.clear();
  Simulation plain(o);
  while (!plain.done()) plain.step();
  const CycleSummary baseline = plain.cycle_summary();
  std::printf("[ measured ] the same cycle unbiased: %.0f kg in %.2f s, %.0f kJ\n",
              baseline.loaded_mass, baseline.cycle_time, 1e-3 * baseline.work);
  EXPECT_NE(baseline.work, facade.work);
}

// bad effects are one InputError naming the option; a run with effects does not save its state
TEST(SimulationEffects, BadEffectsNameTheOption) {
  const auto refused = [](const SimulationOptions& o, const std::string& says) {
    try {
      Simulation sim(o);
      ADD_FAILURE() << "took effects " << o.effects.front();
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(says), std::string::npos) << e.what();
    }
  };
  SimulationOptions o = vehicle_only();
  o.effects = {"soil_cohesion:cohesion=1000"};
  refused(o, "SimulationOptions::effects soil_cohesion: acts on the soil's particles");
  o.effects = {"no_such_effect"};
  refused(o, "no_such_effect");

  // a plug-in's effect keeps its memory behind the C ABI: its run does not save its state yet
  o.effects = {"flow_relief"};
  o.effect_plugins = {std::string(TALUS_BINARY_DIR) + "/libtalus_example_effect.so"};
  Simulation relieved(o);
  try {
    (void)relieved.state();
    ADD_FAILURE() << "saved the state of a plug-in's effect";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("flow_relief"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace talus
