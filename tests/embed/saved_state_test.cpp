// Saved states through the facade (Simulation::save_state, restore_state, state, set_state; issue
// 16): a run restored from a state continues bit for bit as the run that never stopped (a second
// simulation, and the same one rewound), for a dig at D400, the loading cycle and the machine
// alone; a file that is not such a state, is cut short, corrupt or from another simulation is one
// clear InputError and changes nothing.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "digging/saved_state.hpp"
#include "embed/talus.hpp"

namespace talus {
namespace {

namespace fs = std::filesystem;

// everything a caller can read of a run, to compare two runs bit for bit
struct Observed {
  double time = 0.0, work = 0.0, loaded_mass = 0.0;
  std::vector<SensorReading> log;
  SensorReading now;
  ParticleState particles;
  std::string phase;
};

Observed observe(const Simulation& sim) {
  Observed o;
  o.time = sim.time();
  o.work = sim.work();
  o.loaded_mass = sim.loaded_mass();
  o.log = sim.sensor_log();
  o.now = sim.sensors();
  o.particles = sim.particles();
  o.phase = sim.cycle_phase();
  return o;
}

// every channel of two readings, bit for bit (EXPECT_EQ on doubles is exact), in the order of
// Simulation::channel_names()
void expect_same_reading(const SensorReading& a, const SensorReading& b, const std::string& what) {
  constexpr double SensorReading::*kFields[] = {&SensorReading::t,
                                                &SensorReading::f_lift,
                                                &SensorReading::f_tilt,
                                                &SensorReading::f_traction,
                                                &SensorReading::v_drive,
                                                &SensorReading::d_lift,
                                                &SensorReading::d_tilt,
                                                &SensorReading::boom_deg,
                                                &SensorReading::bucket_deg,
                                                &SensorReading::pitch_deg,
                                                &SensorReading::x_vehicle,
                                                &SensorReading::bucket_tip_x,
                                                &SensorReading::bucket_tip_z,
                                                &SensorReading::power};
  const std::vector<std::string>& names = Simulation::channel_names();
  ASSERT_EQ(std::size(kFields), names.size());
  for (std::size_t c = 0; c < names.size(); ++c)
    EXPECT_EQ(a.*kFields[c], b.*kFields[c]) << what << ": channel " << names[c];
}

void expect_same(const Observed& a, const Observed& b) {
  EXPECT_EQ(a.time, b.time);
  EXPECT_EQ(a.work, b.work);
  EXPECT_EQ(a.loaded_mass, b.loaded_mass);
  EXPECT_EQ(a.phase, b.phase);
  expect_same_reading(a.now, b.now, "sensors now");
  ASSERT_EQ(a.log.size(), b.log.size());
  for (std::size_t k = 0; k < a.log.size(); ++k)
    expect_same_reading(a.log[k], b.log[k], "log sample " + std::to_string(k));
  EXPECT_EQ(a.particles.position, b.particles.position);
  EXPECT_EQ(a.particles.velocity, b.particles.velocity);
  EXPECT_EQ(a.particles.angular_velocity, b.particles.angular_velocity);
  EXPECT_EQ(a.particles.radius, b.particles.radius);
}

void steps(Simulation& sim, int n) {
  for (int k = 0; k < n; ++k) sim.step();
}

// a fresh folder per test (ctest runs them in separate processes, maybe in parallel)
fs::path fresh_temp_dir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  fs::path dir = fs::temp_directory_path() /
                 ("talus-state-" + std::string(info->name()) + "-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// the save, the continuation, and two restores of it: a second simulation made with the same
// options, and the first one rewound. `before` and `after` are step counts
void expect_bit_identical_continuation(const SimulationOptions& options, int before, int after) {
  Simulation first(options);
  steps(first, before);
  const std::string saved = first.state();
  const double saved_time = first.time();
  steps(first, after);
  const Observed reference = observe(first);

  Simulation second(options);
  second.set_state(saved);
  EXPECT_EQ(second.time(), saved_time) << "the clock comes back with the state";
  steps(second, after);
  {
    SCOPED_TRACE("a second simulation restored from the state");
    expect_same(observe(second), reference);
  }

  // rewinding the first: the state replaces whatever it has now (other contacts, other buffers)
  first.set_state(saved);
  steps(first, after);
  {
    SCOPED_TRACE("the first simulation rewound to the state");
    expect_same(observe(first), reference);
  }
}

// HD27 at D400 (765 particles, 20 ms steps): 2.4 s to the pile, 2.6 s of digging into it; the
// bucket holds soil by the end, so the bucket contacts' warm starts were carried over
TEST(SavedState, DigContinuesBitIdentically) {
  SimulationOptions o;
  o.scenario = "hd27";
  o.level = "D400";
  Simulation probe(o);
  // the state is saved in the middle of the dig: find when the bucket first holds soil
  int touched = -1;
  for (int k = 0; k < 400 && touched < 0; ++k) {
    probe.step();
    if (probe.loaded_mass() > 0.0) touched = k;
  }
  ASSERT_GT(touched, 0) << "the bucket never reached the pile in 8 s";
  expect_bit_identical_continuation(o, touched + 20, 60);
  // and the loaded mass is a real dig's: something in the bucket after the save
  Simulation check(o);
  steps(check, touched + 80);
  EXPECT_GT(check.loaded_mass(), 0.0);
}

// the machine alone (flat-lift, 5 ms steps): the direct solver's warm start and the joints' state
TEST(SavedState, MachineAloneContinuesBitIdentically) {
  SimulationOptions o;
  o.scenario = "flat-lift";
  expect_bit_identical_continuation(o, 150, 250);
}

// effects with a memory (a lag, a delay line, a learned correction's delay line and force lag,
// the traction correction's too) are saved with the run: the machine alone and a dig continue bit
// for bit with them
TEST(SavedState, EffectsMemoriesContinueBitIdentically) {
  SimulationOptions o;
  o.scenario = "load-carry";
  o.effects = {"hydraulic_lag:time_constant=0.3", "sensor_delay:channel=f_lift,delay=0.2",
               "learned_actuator_correction:actuator=lift,delay_02=0.5,force=-1e-8",
               "learned_traction_correction:delay_01=-2e4,abs_force_sign_speed=0.01"};
  expect_bit_identical_continuation(o, 300, 300);
  // a dig: the learned correction's phase features read the scenario's digging phase (1.1 s on)
  // in the continued run as in the whole one
  SimulationOptions dig;
  dig.scenario = "hd27";
  dig.level = "D400";
  dig.effects = {"engine_power_sharing", "hydraulic_lag",
                 "learned_actuator_correction:actuator=drive,digging_times=-0.2"};
  expect_bit_identical_continuation(dig, 100, 40);
  // a state saved without the effects is another simulation's
  SimulationOptions plain = o;
  plain.effects.clear();
  Simulation with(o);
  try {
    with.set_state(Simulation(plain).state());
    ADD_FAILURE() << "restored a state without effects into a run with them";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("effect=hydraulic_lag"), std::string::npos) << e.what();
  }
}

// the loading cycle at D400: saved in the approach, continued through the change to the fill
TEST(SavedState, LoadingCycleContinuesBitIdentically) {
  SimulationOptions o;
  o.scenario = "fb35";
  o.level = "D400";
  o.loading_cycle = true;
  Simulation probe(o);
  int fill = -1;
  for (int k = 0; k < 600 && fill < 0; ++k) {
    probe.step();
    if (probe.cycle_phase() == "fill") fill = k;
  }
  ASSERT_GT(fill, 20) << "the cycle never began its fill";
  expect_bit_identical_continuation(o, fill - 20, 60);
}

// a file: written atomically, restored by path into another simulation
TEST(SavedState, FileRoundTrip) {
  const fs::path dir = fresh_temp_dir();
  SimulationOptions o;
  o.scenario = "flat-lift";
  Simulation first(o);
  steps(first, 100);
  const std::string path = (dir / "lift.state").string();
  first.save_state(path);
  ASSERT_TRUE(fs::exists(path));
  // nothing else left beside it (no temporary file)
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);
  steps(first, 50);
  Simulation second(o);
  second.restore_state(path);
  steps(second, 50);
  expect_same(observe(second), observe(first));
  fs::remove_all(dir);
}

// what a bad state does: one InputError naming the file and what is wrong, and the simulation
// goes on as if nothing had been given
TEST(SavedState, BadStatesAreOneClearErrorAndChangeNothing) {
  const fs::path dir = fresh_temp_dir();
  SimulationOptions o;
  o.scenario = "flat-lift";
  Simulation sim(o);
  steps(sim, 40);
  const std::string good = sim.state();
  steps(sim, 10);
  const std::string later = sim.state();

  const auto expect_refused = [&](const std::string& bytes, const std::string& says) {
    const std::string path = (dir / "bad.state").string();
    std::ofstream(path, std::ios::binary) << bytes;
    try {
      sim.restore_state(path);
      ADD_FAILURE() << "restored a bad state; expected: " << says;
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(path), std::string::npos) << what;
      EXPECT_NE(what.find(says), std::string::npos) << what;
    }
    // unchanged: the same state as before the attempt
    EXPECT_EQ(sim.state(), later);
  };
  expect_refused("not a state", "not a talus state file");
  expect_refused(good.substr(0, good.size() / 2), "checksum");
  std::string flipped = good;
  flipped[flipped.size() / 2] ^= 0x10;
  expect_refused(flipped, "checksum");
  std::string version = good;
  version[8] = 99;
  expect_refused(version, "state format version 99");

  // a payload that passes the envelope and the key but fails inside (a file of a build whose
  // layout changed under the same format version): the parts read into the run until the cut,
  // then everything is put back from the copy taken first
  std::string payload;
  SavedStateHeader header = open_state(good, "good", &payload);
  expect_refused(seal_state(header, payload.substr(0, payload.size() / 2)), "ends inside");
  std::string renamed = payload;
  const std::size_t tyre = renamed.find("tyre");
  ASSERT_NE(tyre, std::string::npos) << "the constraints' names are in the payload";
  renamed[tyre] = 'T';
  expect_refused(seal_state(header, renamed), "expected the section");

  // a state of another simulation names what differs
  SimulationOptions other = o;
  other.scenario = "load-carry";
  const std::string foreign = Simulation(other).state();
  expect_refused(foreign, "scenario=");

  // a file that is not there
  try {
    sim.restore_state((dir / "none.state").string());
    ADD_FAILURE() << "restored a missing file";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("none.state"), std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}

// another level or seed of the same scenario is another pile: refused, naming the key's line
TEST(SavedState, AnotherPileIsRefusedNamingWhatDiffers) {
  SimulationOptions o;
  o.scenario = "hd27";
  o.level = "D400";
  const std::string saved = Simulation(o).state();
  o.seed = 2;
  Simulation other_seed(o);
  try {
    other_seed.set_state(saved);
    ADD_FAILURE() << "restored a state of seed 1 into seed 2";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("seed=1 (saved) against seed=2 (this simulation)"), std::string::npos)
        << what;
  }
}

// a type-G level (HD27 at G400, 50 ms steps): saved while the zone holds particles and the bucket
// cuts, continued through excavation, spawning and merging. The voxels, the pool, the particles
// with their ledger and contacts, the size generator, the bucket's impulses, the aggregate's
// memory and the machine all come back: the continuation is bit for bit
TEST(SavedState, TypeGDigContinuesBitIdentically) {
  SimulationOptions o;
  o.scenario = "hd27";
  o.level = "G400";
  Simulation probe(o);
  int cutting = -1;
  for (int k = 0; k < 400 && cutting < 0; ++k) {
    probe.step();
    if (probe.particles().radius.size() > 20 && probe.loaded_mass() > 0.0) cutting = k;
  }
  ASSERT_GT(cutting, 0) << "the zone never held particles with soil in the bucket";
  expect_bit_identical_continuation(o, cutting + 5, 60);
}

// the loading cycle at G400 (s = 0.35, the cycle that drives its bucket to the rear wall at about
// 15 s): saved in the fill 10 s after it began, continued 5 s through the wall contact
TEST(SavedState, TypeGLoadingCycleContinuesBitIdentically) {
  SimulationOptions o;
  o.scenario = "fb35";
  o.level = "G400";
  o.loading_cycle = true;
  o.cycle_s = 0.35;
  Simulation probe(o);
  int fill = -1;
  for (int k = 0; k < 800 && fill < 0; ++k) {
    probe.step();
    if (probe.cycle_phase() == "fill") fill = k;
  }
  ASSERT_GT(fill, 0) << "the cycle never began its fill";
  expect_bit_identical_continuation(o, fill + 200, 100);
}

}  // namespace
}  // namespace talus
