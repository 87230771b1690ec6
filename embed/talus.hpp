/// \file talus.hpp
/// \brief the embedding API of talus (issue 16): a wheel loader digging in gravel, stepped by the
/// program that embeds it.
///
/// One header, plain types only (no OpenCL, Embree, CHOLMOD or Eigen in it): a Simulation is made
/// from a scenario and a particle level, builds and settles the scenario's pile (or runs the
/// machine alone on flat ground), and then steps one timestep at a time with the scenario's own
/// inputs or with target speeds the caller gives. After each step the caller reads the sensor
/// channels of the run contract (SPEC §2.4), the bucket's loaded mass and the particles.
///
/// Installed as `talus/talus.hpp`; CMake: `find_package(talus)` and `talus::talus`, pkg-config:
/// `talus`. docs/embedding.md tells how to install and link it and where the data is found.
#pragma once
#include <cstddef>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "host/error.hpp"

/// \brief the installed package's data folder, as a string literal.
///
/// talusConfig.cmake defines it on talus::talus from the prefix the package was found in, so a
/// program built with find_package(talus) finds the data wherever it runs; a pkg-config build can
/// define it from `pkg-config --variable=datadir talus`. Without it the data is searched as
/// SimulationOptions::data_dir says.
#ifndef TALUS_INSTALL_DATA_DIR
#define TALUS_INSTALL_DATA_DIR ""
#endif

namespace talus {

/// \brief what to simulate: a scenario and, for a scenario with a pile, its particle level.
struct SimulationOptions {
  /// a shipped scenario's name (data/scenarios/NAME.json in any case: "hd27", "fb35", "rd21" dig in
  /// a pile; "flat-lift", "load-carry" run the machine alone) or the path of a scenario file
  /// (docs/spec.md §3)
  std::string scenario = "hd27";
  /// the particle level of a pile, paper Table 3: "D400" (HD27: 765 particles, a second to build),
  /// "D200", "D100", "D50" (the finer, the slower); checked for vehicle-only scenarios too
  std::string level = "D400";
  /// the random seed of the pile's particle sizes and jitter
  unsigned seed = 1;
  /// progress lines on stderr while the pile is built and settled
  bool progress = false;
  /// the folder holding talus's data (machines/, scenarios/, piles/). Shipped names are looked up
  /// in $TALUS_DATA_DIR, then here, then in ./data, then beside the running program (a build tree's
  /// data/, an installed prefix's share/talus/data); empty: not searched. Defaults to
  /// TALUS_INSTALL_DATA_DIR
  std::string data_dir = TALUS_INSTALL_DATA_DIR;
  /// read the settled pile from the pile cache when it holds one built from the same profile,
  /// level, material, seed, device and talus commit, and save a pile it builds there:
  /// $TALUS_CACHE_DIR, else $XDG_CACHE_HOME/talus, else ~/.cache/talus (docs/embedding.md, "Saved
  /// states: settled piles"). A build with uncommitted changes ("-dirty") never uses it; a folder
  /// that cannot be written is a line on stderr, and the pile is built all the same
  bool pile_cache = true;
  /// run the paper's loading cycle (§7, docs/sweep.md) on the scenario's pile instead of replaying
  /// the scenario's inputs: the machine starts cycle_approach metres in front of the pile, drives
  /// up to it at 8 km/h with the bucket flat, fills (by the force-feedback controller at cycle_s,
  /// or by the caller's targets), holds 0.5 s once the bucket breaks out, and reverses to its
  /// start while lifting and tilting. The scenario must have a pile; its pile position, start and
  /// duration are the cycle's
  bool loading_cycle = false;
  /// the loading cycle's distance from the bucket's tip to the pile at the start [m] (paper: 5 m)
  double cycle_approach = 5.0;
  /// the loading cycle's time limit [s]: duration() of a cycle
  double cycle_max_time = 40.0;
  /// the force-feedback controller's point on the paper's search line, s in [0, 1]: what fills
  /// the bucket when a cycle is stepped with step() (paper §7.1; the sweep of `talus sweep`)
  double cycle_s = 0.5;
  /// model extensions (docs/effects.md), each as `talus run --effect` takes it: "NAME" or
  /// "NAME:key=value,..." (for example "engine_power_sharing", "hydraulic_lag:time_constant=0.2",
  /// "sensor_bias:channel=f_lift,bias=2e4"), applied in this order to every step's commands,
  /// limits and forces and to what the sensors report; in a loading cycle the controller reads the
  /// sensors as the effects report them
  std::vector<std::string> effects;
  /// shared libraries with more effects (docs/effects.md, "Plug-ins"), as `talus run
  /// --effect-plugin` loads them; their effects are named in `effects` like built-in ones
  std::vector<std::string> effect_plugins;
};

/// \brief the operator's commands for one step: target speeds, clipped to the machine's maxima.
struct Targets {
  double drive = 0.0;  ///< driving speed [m/s], positive forward
  double lift = 0.0;   ///< lift cylinders' stroke speed [m/s], positive raises the boom
  double tilt = 0.0;   ///< tilt cylinder's stroke speed [m/s], positive curls the bucket
};

/// \brief one reading of the sensor channels: the run contract's columns (SPEC §2.4, the columns
/// of `talus run`'s timeseries.csv, in the order of Simulation::channel_names()).
///
/// Angles are measured in the front frame's x-z plane; strokes are pin-to-pin length minus the
/// closed length.
struct SensorReading {
  double t = 0.0;           ///< time [s]
  double f_lift = 0.0;      ///< both lift cylinders' force, summed [N], positive pushes them longer
  double f_tilt = 0.0;      ///< tilt cylinder's force [N], positive pushes it longer
  double f_traction = 0.0;  ///< traction on the machine [N], positive forward
  double v_drive = 0.0;     ///< driving speed [m/s]
  double d_lift = 0.0;      ///< lift stroke, the mean of the two cylinders [m]
  double d_tilt = 0.0;      ///< tilt stroke [m]
  double boom_deg = 0.0;    ///< boom angle [deg], positive up
  double bucket_deg = 0.0;  ///< bucket angle [deg], positive curled
  double pitch_deg = 0.0;   ///< machine pitch [deg], positive nose-up
  double x_vehicle = 0.0;   ///< machine position along its driving line [m]
  double bucket_tip_x = 0.0;  ///< bucket tip, world x [m] (the front axle starts at x = 0)
  double bucket_tip_z = 0.0;  ///< bucket tip height above the ground [m]
  double power = 0.0;  ///< f_traction v_drive + f_lift (d/dt) d_lift + f_tilt (d/dt) d_tilt [W]
};

/// \brief the paper's measures of a loading cycle (§7): what `talus sweep` reports per sample.
struct CycleSummary {
  double loaded_mass = 0.0;  ///< M: the soil in the bucket now [kg]
  /// T: from the start to the machine's return to its starting point [s]; the time so far while
  /// the cycle has not returned
  double cycle_time = 0.0;
  double work = 0.0;  ///< W: the work of the cycle so far [J] (the sensor log's power, integrated)
  bool completed = false;  ///< whether the machine is back at its start
  bool broke_out =
      false;  ///< whether the fill ended by the bucket breaking out (not its time limit)
  double fill_start = -1.0;  ///< when the bucket reached the pile and the fill began [s]; -1 before
  double fill_end = -1.0;    ///< when the fill ended (breakout or its 15 s limit) [s]; -1 before
};

/// \brief the particles as flat arrays: particle i's vector at [3i, 3i + 3), its radius at [i].
struct ParticleState {
  std::vector<double> position;          ///< x, y, z of each particle's centre [m]
  std::vector<double> velocity;          ///< [m/s]
  std::vector<double> angular_velocity;  ///< [rad/s]
  std::vector<double> radius;            ///< [m]
  /// the number of particles
  std::size_t size() const { return radius.size(); }
};

/// \brief the soil's mass by where it is now [kg]. Its total stays constant over a run to
/// round-off: type-D particles are never made or removed; at a type-G level excavation, spawning
/// and merging move mass between the three parts and lose none (docs/multiscale.md).
struct SoilMass {
  double solid = 0.0;      ///< type G: the voxels' solid soil (0 at a type-D level)
  double pool = 0.0;       ///< type G: soil excavated and not yet made particles (0 at type D)
  /// the particles': the pile's (type D: from the device's masses) or the active zone's (type G:
  /// the terrain's double-precision ledger of the masses it gave its particles)
  double particles = 0.0;
  /// solid + pool + particles
  double total() const { return solid + pool + particles; }
};

/// \brief a scenario's run, stepped by the caller.
///
/// Construction loads the scenario and, when it has a pile, builds and settles the pile at the
/// level (digging/digging.hpp: about a second at D400 on two CPU cores, longer at finer levels) and
/// lets the machine settle on its tyres; time() is then 0. Errors: talus::InputError (a
/// talus::Error) for bad options or data files, naming the option or the file and field and how to
/// fix it; talus::Error for a failure of the simulation (an OpenCL error, a non-finite state).
///
/// With SimulationOptions::loading_cycle the run is the paper's loading cycle (§7) instead of
/// the scenario's replay: cycle_phase() says where it is, step() drives every phase itself (the
/// force-feedback controller fills), and step(targets) commands the fill, as a learning agent or
/// a controller of one's own does (the Python package's Gymnasium environment, docs/python.md).
///
/// The whole state between two steps can be saved and restored (save_state, restore_state; in
/// memory: state, set_state): a restored run continues bit-identically to one that never stopped,
/// on the same build and device (docs/embedding.md, "Saved states").
///
/// Model extensions (SimulationOptions::effects) change the machine and its sensors as `talus run
/// --effect` does. Not in this version: saving a run with a plug-in's effect
/// (docs/embedding.md, "Not yet").
class Simulation {
 public:
  /// loads the scenario and builds what it needs (see the class)
  explicit Simulation(const SimulationOptions& options = {});
  ~Simulation();
  /// a moved-from Simulation may only be destroyed or assigned to
  Simulation(Simulation&& other) noexcept;
  /// a moved-from Simulation may only be destroyed or assigned to
  Simulation& operator=(Simulation&& other) noexcept;
  Simulation(const Simulation&) = delete;
  Simulation& operator=(const Simulation&) = delete;

  /// one timestep with the scenario's own target speeds at time(); in a loading cycle, the
  /// cycle's own (the force-feedback controller's in the fill)
  void step();
  /// one timestep with the caller's target speeds instead of the scenario's; in a loading cycle
  /// only in its fill phase (talus::Error in the others: step() drives them)
  void step(const Targets& targets);
  /// the target speeds step() uses now: the scenario's at time(), or the loading cycle's
  Targets scenario_targets() const;
  /// the machine's top speeds, the largest targets it follows: drive [m/s] and the lift and tilt
  /// cylinders' stroke speeds [m/s] (data/machines)
  Targets top_speeds() const;

  /// simulated time since the start [s]: steps taken times timestep()
  double time() const;
  /// the timestep [s]: the level's for a pile (paper Table 3), the scenario file's otherwise
  double timestep() const;
  /// the scenario's duration [s]; stepping may go on past it, the inputs holding their last value
  double duration() const;
  /// whether time() has reached duration(); a loading cycle also ends when the machine is back
  /// at its start
  bool done() const;

  /// the loading cycle's phase: "approach", "fill", "hold", "retreat" or "done"; empty when the
  /// run replays a scenario
  std::string cycle_phase() const;
  /// the loading cycle's measures so far (talus::Error when the run replays a scenario)
  CycleSummary cycle_summary() const;
  /// the work since the start [J]: the logged power integrated over every step so far
  double work() const;

  /// what the sensors read now, after the last step
  SensorReading sensors() const;
  /// the same as name -> value, the names of channel_names()
  std::map<std::string, double> channels() const;
  /// the readings at 100 Hz since the start (t = 0, 0.01 s, ...), as `talus run` logs them;
  /// instants inside a step longer than 10 ms are interpolated
  std::vector<SensorReading> sensor_log() const;
  /// the contract's channel names, in its column order: "t", "f_lift", ..., "power"
  static const std::vector<std::string>& channel_names();
  /// the channels' SI units, in the order of channel_names(): "s", "N", ...
  static const std::vector<std::string>& channel_units();

  /// the soil in the bucket now [kg] (terrain/bucket_fill's rule); a vehicle-only scenario's
  /// payload, which its bucket carries from the start
  double loaded_mass() const;
  /// whether the pile was read back from the pile cache rather than built (false without a pile)
  bool pile_from_cache() const;

  /// whether the scenario has particles (a pile)
  bool has_particles() const;
  /// the number of particles (0 without a pile)
  std::size_t particle_count() const;
  /// the particles now, downloaded from the device (empty arrays without a pile)
  ParticleState particles() const;
  /// the soil's mass by where it is now (all zero without a pile; type D downloads the particles)
  SoilMass soil_mass() const;

  /// saves the whole state between two steps to `path`, written atomically: the machine (bodies,
  /// the direct solver's warm start, joints and contacts), the particles with last step's
  /// contacts and their impulses (the next warm start), the bucket contacts' impulses, the clock,
  /// the 100 Hz sensor log, what the sensors read now, the effects' memories (lags, delay lines)
  /// and a loading cycle's phase; at a type-G level the voxels, the zone's particles with their
  /// masses and contacts and the aggregate instead of the particle pile. The file is
  /// keyed by what made this simulation (scenario and machine files by content, level, seed,
  /// loading-cycle options, particle count) and closed by a checksum. talus::Error naming the
  /// path when it cannot be written, and ("not yet") with a plug-in's effect
  void save_state(const std::string& path) const;
  /// restores a state save_state wrote into this simulation, which must have been made with the
  /// same options (scenario, level, seed, loading cycle): stepping then continues exactly as the
  /// saved run did, bit for bit on the same build and device. talus::InputError naming the file
  /// when it cannot be read, is not a state file, is truncated or corrupt, is of another format
  /// version, or was saved from another simulation (naming what differs); such a file leaves
  /// this simulation unchanged (a payload that fails inside is undone from a copy taken first)
  void restore_state(const std::string& path);
  /// the same bytes as save_state's file, in memory (a rewind point, a copy to send elsewhere)
  std::string state() const;
  /// restores bytes from state() (or a file's), as restore_state does
  void set_state(const std::string& bytes);

  /// the scenario's name as its file gives it ("HD27")
  std::string scenario_name() const;
  /// the particle level ("D400"), or "vehicle" for a scenario without a pile
  std::string level() const;
  /// the OpenCL device the particles run on, "platform / device (...)"; empty without a pile
  std::string device() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace talus
