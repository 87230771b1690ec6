// The multiscale terrain's soil side (type G, issue 14; paper §4.4, Servin, Berglund & Nystedt
// 2021): the solid voxel terrain, the active zone in front of the bucket, and the dynamic soil as
// particles co-simulated by the OpenCL DEM with the bucket as a kinematic body. What the machine
// feels of the soil (the aggregate body solved with the machine in the direct solver) is built on
// top of this and is not part of it.
//
// One step, with the bucket's pose and twist given (the machine moved it):
//   1. the active zone is predicted from the bucket's cutting edge, top edge and velocity
//      (terrain/active_zone) on the soil's surface (the voxels raised to the tops of the particles
//      heaped on them: once the soil in front of a blade is particles, the voxels there stand on
//      the last failure plane), and, while the bucket cuts, its solid soil leaves the voxels as
//      dynamic mass into a pool;
//   2. the pool becomes particles of the level's size (D ± 10 %, the gravel's grain density): first
//      the particles still growing take its mass, oldest first, each its diameter up by at most
//      `growth_speed` times the step; then seeds (`seed_diameter` of their own full diameter) are
//      made over the columns the soil left, layer by layer from each one's new floor (or a taller
//      neighbour's, so no particle starts inside the voxel surface) up (2 m at most: the
//      soil a bucket pushes heaps up in front of it), wherever a seed fits without touching
//      another particle or the bucket; what does not fit yet waits in the pool;
//   3. the particles take one DEM step with the bucket as a kinematic tool (solvers/tool_world),
//      on the voxel surface near them (one static box per column) inside the pile's container;
//   4. particles that have come to rest on the surface outside the zone and away from the bucket
//      merge back into the column under them as loose soil (compaction 1 / swell);
//   5. the surface avalanches to the repose angle (terrain/avalanche).
// Mass is kept by bookkeeping: every kilogram is in the voxels, the pool or one particle's entry
// of a double-precision ledger (the device's float masses are not used for it), and each transfer
// hands the same double on. `mass_balance()` adds the three.
//
// Choices where the paper says nothing (docs/multiscale.md): how small a seed starts and how fast
// it grows (the paper: particles "grow and shrink"); a particle merges whole once it rests, slower
// than the zone's
// activation speed (0.1 m/s: soil slower than the tool that mobilises it counts as at rest),
// touching the surface, outside the zone and more than 0.5 m from the bucket's bounding box (the
// reference engine's default margin).
#pragma once
#include <memory>
#include <optional>
#include <random>
#include <vector>

#include "host/device.hpp"
#include "solvers/bucket_contacts.hpp"
#include "solvers/bucket_rows.hpp"
#include "solvers/dem_world.hpp"
#include "solvers/embree.hpp"
#include "terrain/active_zone.hpp"
#include "terrain/avalanche.hpp"
#include "terrain/pile.hpp"
#include "terrain/voxel_terrain.hpp"
#include "vehicle/bucket_mesh.hpp"

namespace talus {

class ToolWorld;

// the seeds' diameter as a fraction of their full one: 1, particles appear at full size and do not
// grow. Growth from smaller seeds is built and measured (docs/multiscale.md "Growth"): it loads
// more soil the smaller the seed (G400 kinematic dig: 1397 kg carried at 1, 1830 at 0.5, 2538 at
// 0.3), at every level, without bringing the levels' coupled digs closer together, so it is a
// study option, not the default
inline constexpr double kSeedDiameter = 1.0;
// the smallest seed accepted: a tenth of its diameter, a thousandth of its mass (far smaller seeds
// hold too little mass for the DEM's float state: 1e-9 made non-finite velocities)
inline constexpr double kMinSeedDiameter = 0.1;
// [m/s] how fast a seed's diameter may grow: about the bucket's cutting speed (the soil a bucket
// mobilises moves with it), a judgement, not a source's value
inline constexpr double kGrowthSpeed = 1.0;
// [m/s] a particle slower than this may merge back into the voxels: the zone's activation speed
// (soil slower than the tool that mobilises it counts as at rest; SPEC §2.5, the reference
// engine's 0.1 m/s). The reference engine's own merge threshold is about 4 m/s at a rate of about
// 9 per second (SPEC §2.5); a study option (MultiscaleOptions::merge_speed, `--merge-speed`)
// measures what the faster merge does (docs/multiscale.md "How many particles")
inline constexpr double kMergeSpeed = BulkSoil{}.activation_speed;
// the bucket's resting load (MultiscaleOptions::rest_in_bucket): [m/s] a held particle
// slower than this relative to the bucket is at rest in it: the zone's activation speed, as for
// the merge's default (soil slower than the tool that mobilises it counts as at rest), whatever
// merge speed a study sets
inline constexpr double kRestSpeed = kMergeSpeed;
// [s] how long it must stay so before it rides with the bucket: ten G200 steps (a judgement: long
// enough that a grain bouncing in does not count as at rest)
inline constexpr double kRestTime = 0.2;
// how much the gravity a riding particle feels in the bucket's frame (the gravity less its point's
// acceleration) may change, as a fraction of |g|, before it is released to the DEM again: 0.1,
// about a 6 degree turn of the bucket or a tenth of g of acceleration, a judgement (a heap at
// rest holds a small turn; a larger one, or a jolt, lets it settle as its particles would)
inline constexpr double kRestRelease = 0.1;

struct MultiscaleOptions {
  BulkSoil soil;
  AvalancheOptions avalanche;
  Material particle_material = gravel();  // the zone's particles are the type-D gravel
  BucketMaterial bucket_material;         // particle-bucket contacts (friction 0.2, paper §4.4)
  // [m/s] a particle slower than this may merge (see above); positive
  double merge_speed = kMergeSpeed;
  double no_merge_margin = 0.5;           // [m] around the bucket's bounding box: no merging there
  double front_margin = 2.0;              // voxels ahead of the toe [m] (VoxelTerrainOptions)
  // [m] how far the bucket may press into the voxels before push_aside moves the soil: 0 without
  // the terrain's support under the bucket (a kinematic bucket), kPressedDepth with it
  // (terrain/bucket_support, the digs'); in [0, a cell)
  double pressed_depth = 0.0;
  double max_particle_speed = 4.0;        // [m/s] DemSettings::max_speed of the zone's particles
  int one_group_rows = kPgsOneGroupRows;  // DemSettings::one_group_rows of the zone's sweeps
  int serial_lanes = kSerialLanes;        // DemSettings::serial_lanes of the zone's sweeps
  int sweep_parts = 0;                    // DemSettings::sweep_parts of the zone's sweeps
  bool pair_reach = true;                 // DemSettings::pair_reach of the zone's particles (digs')
  double relaxation = 1.0;                // DemSettings::relaxation of the zone's sweeps
  // a particle appears as a seed of this fraction of its full diameter and grows as the pool
  // feeds it, in [kMinSeedDiameter, 1]; 1 (the default): at full size, no growth
  // (docs/multiscale.md "Growth")
  double seed_diameter = kSeedDiameter;
  // [m/s] the most a growing particle's diameter rises per second of the step
  double growth_speed = kGrowthSpeed;
  // [m] a study: the zone's soil turns dynamic only within this distance ahead of the cutting
  // edge (terrain/active_zone within_reach); 0, the default: the whole wedge up to where its
  // failure plane leaves the surface (docs/multiscale.md "Excavation reach": measured, not the
  // default). The zone the aggregate reads is the whole wedge either way
  double excavation_reach = 0.0;
  // the zone's particles stand on its failure plane, not on the staircase its excavated columns
  // make (terrain/active_zone failure_plane_column; the default since 2026-11-30:
  // docs/multiscale.md "The zone's floor is its failure plane", measured); false: the columns'
  // boxes alone (a study)
  bool failure_plane_floor = true;
  // the default since 2026-12-02 (docs/multiscale.md "The bucket's resting load": the same errors
  // against D100, 1.1-1.4 times faster where the load is carried long): while the bucket digs
  // nothing (no zone), a particle held in it (inside its heaped volume) that has moved slower than
  // kRestSpeed relative to the bucket for kRestTime rides with the bucket as a fixed particle
  // (zero inverse mass, the bucket's motion): no rows with the bucket, its neighbours at rest or
  // the ground, while the particles that still move meet it as a moving wall. It is released,
  // where the bucket carries it, with its own mass and the bucket's motion, when the gravity it
  // feels in the bucket's frame changes by more than kRestRelease |g| or a zone appears. The
  // machine sees the same load either way (the held particles' body, digging/digging); the
  // particles' own wrench on the bucket (MultiscaleStep::bucket_wrench, recorded, not applied)
  // leaves the riding ones out. false, a study: every particle in the DEM
  bool rest_in_bucket = true;
  unsigned seed = 1;                      // of the particles' sizes
};

// the bucket as the particles see it: its mesh frame (the bucket's profile frame: origin at the
// cutting edge's middle, x forward along the bottom, z up) in the world, and the frame's twist
struct KinematicBucket {
  Vec3 position = Vec3::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  Vec3 velocity = Vec3::Zero();  // of the frame's origin [m/s]
  Vec3 omega = Vec3::Zero();     // [1/s]
};

// where the soil is [kg]: solid in the voxels, dynamic in the pool and in the particles
struct MassBalance {
  double solid = 0.0;
  double pool = 0.0;
  double particles = 0.0;
  double total() const { return solid + pool + particles; }
};

// what one step did (before the first step: the zone where the bucket starts, nothing done)
struct MultiscaleStep {
  ActiveZone zone;
  double excavated = 0.0;   // soil turned dynamic [kg]
  int spawned = 0;          // particles made from the pool (seeds)
  int grown = 0;            // particles that grew from the pool
  int merged = 0;           // particles merged back into the voxels
  int resting = 0;          // particles riding with the bucket at rest (rest_in_bucket)
  int released = 0;         // riding particles given back to the DEM (rest_in_bucket)
  double avalanched = 0.0;  // soil that slid [kg]
  Vec6 bucket_wrench =
      Vec6::Zero();  // the particles' mean wrench on the bucket about its frame's origin
};

class MultiscaleTerrain {
 public:
  // the terrain of a pile profile (placed where the pile stands) at a type-G level, with the
  // bucket's mesh (its profile frame) where `start` puts it. Throws InputError for a level that
  // is not type G and for options outside their ranges (seed_diameter, growth_speed,
  // pressed_depth, excavation_reach, merge_speed, the avalanche's repose angle and rate)
  MultiscaleTerrain(Device& dev, const PileProfile& profile, const FidelityPreset& level,
                    const vehicle::BucketMesh& bucket, const KinematicBucket& start,
                    const MultiscaleOptions& options = {},
                    const embree::Device& embree = embree::Device());
  ~MultiscaleTerrain();

  // one step of the level's timestep with the bucket at `bucket` (pose at the step's start, and
  // the twist it moves with through the step)
  void step(const KinematicBucket& bucket);

  const VoxelTerrain& voxels() const { return voxels_; }
  // the particles as the last step left them on the device (downloaded once per step; those riding
  // with the bucket, rest_in_bucket, where it carried them and with their own masses, though the
  // device holds them fixed), and each one's mass from the ledger [kg]
  const Particles& particles() const { return state_; }
  const std::vector<double>& particle_masses() const { return ledger_; }
  MassBalance mass_balance() const;
  // whether particle k rides with the bucket at rest (rest_in_bucket), fixed on the device
  bool rides(size_t k) const { return k < rest_.size() && rest_[k].resting; }
  const MultiscaleStep& last_step() const { return last_; }
  // the zone's particle world (its last step's statistics: contacts, sweeps)
  const DemWorld& dem() const { return *dem_; }
  double time() const { return time_; }
  const FidelityPreset& level() const { return level_; }

  // the state a step carries to the next, for a saved state (digging/saved_state): the voxels'
  // soil, the pool, the zone's particles with their contacts, masses (the ledger) and full
  // diameters, the bucket's contact impulses, where the pool's soil came from, the size generator,
  // the clock and what the last step did (its zone is what the aggregate reads next), and with
  // rest_in_bucket each particle's rest and the bucket's last motion. restore_state reads it into
  // a terrain made with the same profile, level, bucket and options; the terrain then steps on
  // bit-identically to the saved one on the same device. InputError (naming the reader's place)
  // for a state of another grid, a ledger that does not match the particles or another
  // rest_in_bucket;
  // the checks run as the parts are read, so a failed restore may leave the terrain half
  // restored: the caller keeps a copy to undo it (embed/talus.cpp does)
  void save_state(ByteWriter& w) const;
  void restore_state(ByteReader& r);

 private:
  // step 2: the growing particles fed from the pool; returns how many grew
  int grow(Particles& particles);
  // step 2: seeds from the pool in the excavated cells; returns how many
  int spawn(Particles& particles, const std::vector<ExcavatedColumn>& columns,
            const BucketPose& pose);
  // step 4: resting particles back into the voxels; returns how many, and each old particle's
  // new index (-1 merged) in `new_index_of_old` (the survivors keep their order, as
  // DemWorld::renumber_particles needs; spawn then appends)
  int merge(Particles& particles, const KinematicBucket& bucket,
            std::vector<int>* new_index_of_old);
  // rest_in_bucket: the held particles at rest in the bucket made fixed and moved with it, those
  // a change of their felt gravity or a zone releases given back their masses; true if any
  // particle's state changed (always, while any rides: the bucket moves them)
  bool ride_with_bucket(Particles& particles, const KinematicBucket& bucket);
  // step 1's zone: predicted from the bucket's edges on the soil's surface under `particles`
  ActiveZone zone_for(const KinematicBucket& bucket, const Particles& particles) const;
  // the host copy of the device's particles that every reader uses (empty without particles)
  void download_particles();
  // the soil's surface: the voxels' columns raised to the tops of the particles heaped on them,
  // leaving out the particles marked `held` (those in the bucket)
  std::vector<double> soil_surface(const Particles& particles, const std::vector<char>& held) const;
  // step 3's static geometry: the container and a box per voxel column near the particles
  std::vector<StaticGeom> geometry(const Particles& particles) const;

  FidelityPreset level_;
  MultiscaleOptions options_;
  PileProfile profile_;
  VoxelTerrain voxels_;
  vehicle::BucketMesh bucket_mesh_;
  BucketScene bucket_scene_;
  std::unique_ptr<DemWorld> dem_;
  std::unique_ptr<ToolWorld> tools_;
  std::vector<double> ledger_;  // mass of each particle on the device, in its order [kg]
  std::vector<double> full_;    // the diameter each particle grows to, in the same order [m]
  // rest_in_bucket, in the particles' order: how long each has been slow relative to the bucket
  // [s], and for a riding one where it sits in the bucket's frame, the gravity it felt there when
  // it came to rest [m/s^2], and its own inverse mass and inertia; and the bucket's motion at the
  // last step (its acceleration)
  struct Rest {
    double still = 0.0;
    bool resting = false;
    Vec3 local = Vec3::Zero();
    Vec3 gravity = Vec3::Zero();
    double inv_mass = 0.0, inv_inertia = 0.0;
  };
  std::vector<Rest> rest_;
  std::optional<KinematicBucket> last_bucket_;
  Particles state_;             // the device's particles after the last step (host copy)
  double pool_ = 0.0;           // dynamic soil not yet made into particles [kg]
  std::vector<ExcavatedColumn>
      sites_;              // where the pool's soil came from: the last excavation's columns
  std::mt19937_64 sizes_;  // the particles' diameters, one draw per particle made
  double time_ = 0.0;
  MultiscaleStep last_;
};

// the bucket's cutting edge and top edge in the world, from its mesh (the profile frame's tip and
// lip across the inner width) and pose, with the cutting edge's velocity
ToolEdges bucket_edges(const vehicle::BucketMesh& mesh, const KinematicBucket& bucket);

}  // namespace talus
