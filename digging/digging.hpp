// The digging simulator: a scenario's pile at a fidelity level in front of the wheel loader, and
// the scenario's feedforward inputs replayed with the soil and the machine coupled.
//   type D (issue 4): the pile built and settled as particles, coupled to the machine through the
//     bucket's contacts (solvers/split_solver.hpp);
//   type G (issue 14): the pile as the voxel terrain of its profile; each step the aggregate of the
//     active zone's particles is solved with the machine (terrain/aggregate), the soil in the
//     bucket weighs on the bucket, then the terrain steps with the bucket as the machine moved it
//     (terrain/multiscale_terrain); the cutting edge's penetration resistance holds it back
//     (terrain/penetration). docs/multiscale.md
//
// Frames: the machine's reference pose has its front axle at x = 0 (data/machines/*.json); the
// pile's profile (data/piles/*.json) is shifted so its toe lies at the scenario's pile_toe_x.
// One timestep for both sides, the level's (paper Table 3), so the coupling stays implicit; the
// sensors are logged at 100 Hz (interpolated within steps longer than 10 ms, vehicle/sensors.hpp).
#pragma once
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "host/progress.hpp"
#include "solvers/split_solver.hpp"
#include "terrain/aggregate.hpp"
#include "terrain/bucket_support.hpp"
#include "terrain/multiscale_terrain.hpp"
#include "terrain/pile.hpp"
#include "terrain/pile_cache.hpp"
#include "vehicle/effect.hpp"
#include "vehicle/scenario.hpp"
#include "vehicle/sensors.hpp"

namespace talus {

// the residual a type-D dig's sweeps stop at [m/s]: 0.1 % of the velocity gravity adds in a D200
// step (g h = 0.098 m/s), ten times what D200's 500 sweeps reach (1.1e-5, median). Measured
// (docs/dem.md, "Sweeps stopped by a tolerance", issue 13): at D200 FB35's fill and work move by
// +0.9 % and +1.3 %, HD27's five-pile means by -0.6 % and -0.6 %, with 62-79 sweeps a step
// instead of 500 (3.8-4.6 times the speed); D400's 15 sweeps rarely reach it
inline constexpr double kDigSweepTolerance = 1.0e-4;
// the largest factor DiggingOptions::edge_resistance takes: a study's range, up to ten times the
// law (at 0.5 m of depth the law gives 38 kN; ten times it is four times the machine's traction,
// about 100 kN, so larger factors only stall the bucket)
inline constexpr double kMaxEdgeResistance = 10.0;
// the range `talus run --repose-angle` takes for the type-G surface [deg]: dry granular soils
// stand at 25-45 deg; 5 lets a study flatten a face, 60 steepen one
inline constexpr double kMinReposeAngle = 5.0;
inline constexpr double kMaxReposeAngle = 60.0;
// the largest rate `talus run --avalanche-rate` takes [1/s]: at every level's step the fraction a
// step moves, 1 - exp(-k dt), reaches its cap of 0.25 (terrain/avalanche.hpp) below it (G50's 5 ms:
// k = 58 /s), so faster rates change nothing
inline constexpr double kMaxAvalancheRate = 1000.0;

// the bucket sweep at a level: the coloured one only at a type-D level (a type-G bucket meets the
// soil through its aggregate, with no chain of particle-bucket rows); InputError naming `field`
void check_bucket_sweep(BucketSweep sweep, const FidelityPreset& level, const std::string& field);
// the residual tolerance a dig's particle sweeps stop at [m/s]: `tolerance` at a type-D level; 0
// (none) at a type-G level, whose zone runs its level's N_it sweeps in one launch (the paper's
// fixed iterations)
double applied_sweep_tolerance(double tolerance, const FidelityPreset& level);
// a sweep tolerance at a level: at a type-G level only the default (which it does not apply) or 0;
// InputError naming `field`
void check_sweep_tolerance(double tolerance, const FidelityPreset& level, const std::string& field);

struct DiggingOptions {
  PileBuildOptions pile;         // settling of the pile before the machine starts
  CouplingSettings coupling;     // bucket contacts and outer passes
  SweepKind sweep = SweepKind::Pgs;
  // PGS sweeps a system of at most this many rows in one work-group (DemSettings::one_group_rows;
  // type D and the type-G zone alike): a device-dependent speed (and order, see serial_lanes)
  int one_group_rows = kPgsOneGroupRows;
  // blocks of contacts a serially walked system's rows interleave (DemSettings::serial_lanes;
  // type D and the type-G zone alike); 0 colours them
  int serial_lanes = kSerialLanes;
  // parts a larger system's rows are walked in on a CPU device (DemSettings::sweep_parts; type D
  // and the type-G zone alike); 0: one per compute unit
  int sweep_parts = 0;
  // each particle pair's own speculative reach instead of the fastest particle's (DemSettings::
  // pair_reach; type D and the type-G zone alike). The default since 2026-11-29: the same sweeps
  // and fills within the piles' scatter with 30-45 % fewer rows (docs/dem.md "Speculative reach")
  bool pair_reach = true;
  // the relaxation omega of the particle rows' PGS sweeps (DemSettings::relaxation; type D and the
  // type-G zone alike; the pile is settled with its own settings)
  double relaxation = 1.0;
  // type G: the fraction of its full diameter a zone particle appears at and grows from
  // (MultiscaleOptions::seed_diameter; 1, the default: at full size; docs/multiscale.md "Growth")
  double seed_diameter = kSeedDiameter;
  // type G: the soil the bucket holds as a body welded to it, its weight and inertia in the
  // machine's solve (terrain/aggregate BucketPayload; the default since 2026-11-29: the carry's
  // lift force then fluctuates per kg as a type-D dig's does, docs/validation.md "Type G against
  // type D"); off, its weight alone (a type-G study; refused at a type-D level, whose particles
  // are the content itself)
  bool content_inertia = true;
  // type G, a study: a factor on the cutting edge's penetration resistance (constraint C,
  // terrain/penetration), in [0, kMaxEdgeResistance]; 1 the law as it stands, 0 none. The law is
  // talus's own (the paper gives none) and moves a type-G dig more than anything else measured
  // (docs/validation.md "Type G against type D"); refused at a type-D level unless 1
  double edge_resistance = 1.0;
  // type G, a study: the zone's soil turns dynamic only within this distance ahead of the
  // cutting edge [m] (MultiscaleOptions::excavation_reach); 0, the default: the whole wedge. It
  // moves the type-G loads toward D100's and RD21's work away from it (docs/validation.md "The
  // zone's excavation reach"); refused at a type-D level unless 0
  double excavation_reach = 0.0;
  // type G, a study: a zone particle slower than this may merge back into the voxels [m/s]
  // (MultiscaleOptions::merge_speed; kMergeSpeed, the default, the zone's activation speed; the
  // reference engine merges below about 4 m/s: docs/multiscale.md "How many particles"); refused at
  // a type-D level unless the default, which has no voxels to merge into
  double merge_speed = kMergeSpeed;
  // type G: while the bucket digs nothing, its resting load rides with it as fixed particles, out
  // of the DEM's rows until the gravity it feels changes or the bucket digs again
  // (MultiscaleOptions::rest_in_bucket; the default since 2026-12-02: the same errors against
  // D100, 1.1-1.4 times faster, docs/multiscale.md "The bucket's resting load"); off: every
  // particle in the DEM (a study; refused at a type-D level, whose bucket's load is its
  // particles' own)
  bool rest_in_bucket = true;
  // type G: the zone's particles stand on its failure plane, not on its excavated columns'
  // staircase (MultiscaleOptions::failure_plane_floor; the default since 2026-11-30: it brings
  // the type-G loads and work toward D100's, docs/validation.md "The zone's floor is its failure
  // plane"); off: the columns alone (a study; refused at a type-D level, which has no voxels)
  bool failure_plane_floor = true;
  // type G, a study: the voxel surface's avalanche (MultiscaleOptions::avalanche,
  // terrain/avalanche): its angle of repose (32 deg, the gravel's internal friction, paper §4.4)
  // and decay rate (6.3 /s, the reference engine's). A lower angle and a faster rate let the pile's
  // face slide into the cut as the type-D spheres' face creeps (docs/validation.md "D100's face
  // creeps from t = 0"); refused at a type-D level unless the defaults, whose particles are the
  // surface
  AvalancheOptions avalanche;
  // type G, a study: the SPOOK damping time of the aggregate's interfaces A and B [s] in
  // [kMinDampingTime, kMaxDampingTime] (solvers/dem_settings); 0, the default: two of the level's
  // steps (AggregateParameters::
  // damping_time). At G200 it sets HD27's breakout force where the step does not, and moves
  // FB35's fill (docs/validation.md "HD27's breakout follows the interfaces' damping time");
  // refused at a type-D level unless 0
  double interface_damping_time = 0.0;
  // type G: the resting soil holds the bucket's bottom up (terrain/bucket_support: four points
  // on its bottom against the voxel surface, solved with the machine; push_aside then leaves the
  // soil the bottom presses in by less than kPressedDepth); off, the soil under the bucket gives
  // way to any force as before 2026-11-29 (a study; refused at a type-D level, whose particles hold
  // the bucket up themselves)
  bool bucket_support = true;
  // a type-D dig's sweeps end early once the particle rows' RMS residual is below this [m/s]
  // (DemSettings::tolerance; the level's N_it is the cap). 0: always N_it, as the paper's presets
  double sweep_tolerance = kDigSweepTolerance;
  // the fastest particle to expect [m/s] (speculative contacts, DemSettings::max_speed): gravel
  // thrown by the bucket moves at about the bucket's speed, 1-2 m/s in these scenarios
  double max_particle_speed = 2.0;
  // the soil's contact material (the pile is built and dug with it): the paper's gravel unless a
  // study changes it (talus run --rolling); the soil_cohesion effect adds its cohesion on top
  Material soil = gravel();
  // settled piles saved and read back by their parameters (terrain/pile_cache.hpp): off here,
  // on in talus run, sweep, bench dig and the facade unless disabled (--no-pile-cache)
  PileCacheOptions pile_cache;
};

// the scenario's pile profile (data/piles/NAME.json or a path; InputError naming the scenario's
// field), moved along x so that its toe lies at the scenario's pile_toe_x
PileProfile scenario_pile_profile(const vehicle::Scenario& scenario);

// the bucket as the type-G terrain sees it: its profile frame (tip) and that point's twist
KinematicBucket kinematic_bucket(const vehicle::WheelLoader& loader);

// the upright walls among a pile's static planes (terrain/pile's container: side and rear walls;
// not the ground), as rigid planes for the machine's bucket
std::vector<vehicle::RigidPlane> container_walls(const std::vector<StaticGeom>& geoms);

// the scenario's pile at the level, built and settled on `placed` (scenario_pile_profile):
// particles, container (ground, sides, rear wall) and the broad-phase bounds, which also cover
// where the machine carries gravel (back to 6 m in front of the toe, up to 5 m high). Through the
// pile cache when options.pile_cache.enabled (PileBuild::from_cache says whether it was read back).
// At a type-G level: the container and bounds only, no particles (the run builds its voxels)
PileBuild build_scenario_pile(Device& dev, const vehicle::Scenario& scenario, const PileProfile& placed,
                              const FidelityPreset& preset, const DiggingOptions& options, Progress* progress);

// the type-G aggregate after one step: what the machine felt of the active zone
struct AggregateSample {
  double t = 0.0;                       // end of the step [s]
  int particles = 0;                    // in the zone
  double mass = 0.0;                    // [kg]
  Vec3 centre = Vec3::Zero();           // [m]
  Vec3 velocity = Vec3::Zero();         // as solved with the machine [m/s]
  // the zone's particles' mean velocity (their momentum over their mass) when the step began
  // [m/s]: what the aggregate stands for, beside the motion it keeps from the machine's solve
  Vec3 zone_velocity = Vec3::Zero();
  Vec3 force_on_bucket = Vec3::Zero();  // interface A's on the bucket [N]
  double terrain_normal_force = 0.0;    // interface B's normal force [N]
  // interface B's whole force on the aggregate [N]: its normal force and its friction along the
  // failure plane (with interface A's, -force_on_bucket, and the aggregate's weight, in a run
  // without effects, it is the aggregate's mass times the change of its velocity over the step)
  Vec3 terrain_force = Vec3::Zero();
  double edge_force = 0.0;              // the penetration resistance's [N]
  Vec3 support_force = Vec3::Zero();    // the terrain's support's on the bucket [N] (0 without)
  double held_mass = 0.0;  // the soil the bucket holds outside the zone, this step's [kg]
  // the soil's whole force on the bucket [N]: interface A, the cutting edge's brake, the support
  // and the held load's weight (not its inertia); a type-D run's SoilForceSample::force
  Vec3 soil_force = Vec3::Zero();
  // the zone's and the bucket's particles' own force on the kinematic bucket in the terrain's DEM
  // step [N] (MultiscaleStep::bucket_wrench: recorded, not applied; the aggregate and the held
  // load stand for it in the machine's solve)
  Vec3 particle_force = Vec3::Zero();
  double depth_a = 0.0, depth_b = 0.0;  // the interfaces' depths [m]
  // its principal axes of inertia (a rotation from the world, terrain/aggregate principal_axes)
  // and the moments about them [kg m^2]: the orientation of its pose
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  Vec3 principal_moments = Vec3::Zero();
};

// one type-D step's soil force on the bucket: the mean wrench of its particle contacts over the
// step (the split solver's, solvers/split_solver CouplingStats::wrench), the load in the bucket
// included, so it is what a type-G bucket feels of the soil through interface A, the cutting
// edge's brake, the terrain's support and its held load's weight together
struct SoilForceSample {
  double t = 0.0;              // end of the step [s]
  Vec3 force = Vec3::Zero();   // [N], world
  Vec3 torque = Vec3::Zero();  // about the bucket's centre of mass at the step's start [N m]
  // `force` by the bucket's face the soil meets (solvers/split_solver BucketFaceForces): under the
  // bottom (type G: the terrain's support), on the bottom's inside (the held load), across the
  // cutting direction (interface A and the cutting edge's brake) [N], world
  BucketFaceForces faces;
};

// the laser scan of a scenario's pile before loading, as the field tests measured it: the settled
// particles' surface (type D) or the voxels' of the placed profile (type G)
PileScan scan_scenario_pile(const PileBuild& pile, const PileProfile& placed,
                            const FidelityPreset& preset);

class DiggingSimulation {
 public:
  // the scenario must have a pile; `pile` from build_scenario_pile (or a saved one). With
  // `effects` (model extensions, vehicle/effect.hpp; not owned, must outlive the simulation) the
  // set is reset when the machine has settled, and every step's commands, limits and forces and
  // the logged sensors go through it: log() records what the sensors report. Without, the run
  // steps through an empty set of its own, the identity
  DiggingSimulation(Device& dev, const vehicle::Scenario& scenario, const FidelityPreset& preset,
                    const PileBuild& pile, const DiggingOptions& options, vehicle::EffectSet* effects = nullptr);
  // it points into itself (the empty effect set), so it stays where it was built
  DiggingSimulation(const DiggingSimulation&) = delete;
  DiggingSimulation& operator=(const DiggingSimulation&) = delete;

  // one step with the scenario's controls at the current time
  void step();
  // one step with the given target speeds [m/s] (a controller instead of the scenario's inputs);
  // with effects, these are the operator's targets before on_commands
  void step(double drive, double lift, double tilt);
  // the run loop: steps with the scenario's controls to the end, calling after_step(k) after the
  // run's step k (counted from its start, steps taken by hand included; snapshots, progress: not
  // timed); returns the wall time of the steps alone [s]
  double run(const std::function<void(int)>& after_step = {});
  double time() const { return time_; }
  int steps_total() const { return steps_total_; }
  bool done() const { return steps_done_ >= steps_total_; }

  const vehicle::WheelLoader& loader() const { return *loader_; }
  // the type-D particle world and split solver (talus::Error at a type-G level), the type-G
  // terrain (talus::Error at a type-D level)
  const DemWorld& dem() const;
  const SplitSolver& split() const;
  const MultiscaleTerrain& terrain() const;
  // the type-G aggregate, its interfaces and the cutting edge's resistance (talus::Error at a
  // type-D level)
  const AggregateCoupling& aggregate() const;
  bool multiscale() const { return terrain_ != nullptr; }
  // type G: the aggregate after every step so far (empty at a type-D level)
  const std::vector<AggregateSample>& aggregate_log() const { return aggregate_log_; }
  // type D: the soil's force on the bucket step by step (empty at type G: aggregate_log)
  const std::vector<SoilForceSample>& soil_log() const { return soil_log_; }
  const vehicle::SensorLog& log() const { return log_; }
  // what the sensors report now, after the last step (at time()) and through the effects: what a
  // controller reads; the log holds only the 100 Hz instants, which a step under 10 ms may miss
  const vehicle::SensorSample& sensors() const { return sensors_; }
  // particles now (downloaded from the device): the pile's, or the type-G zone's
  Particles particles() const;
  size_t particle_count() const;
  // soil in the bucket now, by terrain/bucket_fill's rule [kg]
  double loaded_mass() const;

  // the state between two steps (issue 16, docs/embedding.md "Saved states"): the machine (bodies,
  // warm start, constraints), the particles with last step's contacts and impulses, the bucket
  // contacts' impulses, the clock, the sensor log, what the sensors read, the coupling counters
  // and the effects' memories (vehicle::EffectSet::save_state); at a type-G level the terrain
  // (MultiscaleTerrain::save_state), the aggregate's memory and its log instead of the particle
  // pile and the bucket impulses. restore_state reads it into a
  // simulation made with the same scenario, level, pile and options, which then steps on
  // bit-identically to the one saved (same device and work-group size). What the constructor sets
  // (scenario, level, material, settings) is not saved; the caller checks that it is the same
  // (embed/talus.cpp keys the file by it). talus::Error ("not yet") with a plug-in's effect: its
  // state is not saved yet
  void save_state(ByteWriter& w) const;
  void restore_state(ByteReader& r);

  // coupling over the run so far: steps with bucket contacts, the largest outer-pass count and
  // coupling residual, and the mean number of passes over steps with contacts
  int contact_steps() const { return contact_steps_; }
  int max_passes() const { return max_passes_; }
  double max_residual() const { return max_residual_; }
  double mean_passes() const { return contact_steps_ > 0 ? double(pass_sum_) / contact_steps_ : 0.0; }
  double max_bucket_overlap_rel() const { return max_overlap_rel_; }
  // steps whose outer passes stopped at the limit with the residual still above the tolerance
  int steps_at_pass_limit() const { return capped_steps_; }
  // particle sweeps per type-D step, mean over the steps run (all passes; the level's N_it or
  // more without a tolerance, fewer when DiggingOptions::sweep_tolerance stopped them)
  double mean_sweeps() const { return steps_done_ > 0 ? double(sweep_sum_) / steps_done_ : 0.0; }
  // the particle rows' RMS residual at the end of each step with particle contacts [m/s], when
  // options.coupling.record_residual is set (empty otherwise)
  const std::vector<double>& step_residuals() const { return residuals_; }

 private:
  Device& dev_;
  vehicle::Scenario scenario_;
  FidelityPreset preset_;
  std::unique_ptr<vehicle::WheelLoader> loader_;
  std::unique_ptr<DemWorld> dem_;
  std::unique_ptr<SplitSolver> split_;
  std::unique_ptr<MultiscaleTerrain> terrain_;
  std::unique_ptr<AggregateCoupling> aggregate_;
  std::unique_ptr<BucketPayload> payload_;  // type G with DiggingOptions::content_inertia
  std::unique_ptr<BucketSupport> support_;  // type G with DiggingOptions::bucket_support
  // the type-G coupled step (see the top of this file)
  void multiscale_step();
  std::vector<AggregateSample> aggregate_log_;
  std::vector<SoilForceSample> soil_log_;
  vehicle::SensorLog log_;
  vehicle::SensorSample sensors_;
  vehicle::EffectSet no_effects_;
  vehicle::EffectSet& effects_;  // the caller's, or no_effects_
  double time_ = 0.0;
  int steps_done_ = 0, steps_total_ = 0;
  int contact_steps_ = 0, max_passes_ = 0, capped_steps_ = 0;
  long pass_sum_ = 0, sweep_sum_ = 0;
  double max_residual_ = 0.0, max_overlap_rel_ = 0.0;
  std::vector<double> residuals_;
};

}  // namespace talus
