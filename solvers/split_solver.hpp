// The type-D step: the particle world (DemWorld, iterative, on the device) and the wheel loader
// (MultibodySystem, direct, on the host) coupled strongly through the bucket contacts
// (SPEC §1 steps 1-7, the paper's "time-implicit integration").
//
// One step:
//   1. the vehicle assembles its rows; the particles find their own contacts and rows;
//   2. particles near the bucket are selected on the device (DeviceBoxSelection), their state
//      gathered, and Embree finds their contacts with the bucket mesh on the host;
//   3. last step's bucket impulses are matched to the new contacts (warm start) and their wrench
//      goes into a first direct vehicle solve, which yields the bucket's twist and its
//      articulated mobility W (Schur complement, with the active set under that load);
//   4. PGS or Jacobi sweeps over the particle rows, each followed by one sweep over the bucket
//      rows in which the bucket moves by W times every impulse change (serially, or colour by
//      colour: CouplingSettings::bucket_sweep);
//   5. the bucket rows' total wrench goes back into the direct solve. If the bucket twist it
//      yields differs from the one the sweeps ended with (the vehicle's active set changed: a
//      cylinder reached its force limit, a tyre started to slip), the sweeps go on from the new
//      twist and mobility: an outer pass. Passes stop when the difference, as the largest
//      velocity of a bucket point, is below the tolerance, or after max_passes;
//   6. both sides integrate positions.
// How many passes: with an unchanged active set the first pass already agrees to float
// rounding, because the sweeps used the same linear response W the direct solve has; only a
// change of active set needs more. docs/validation.md reports how often that happens.
#pragma once
#include <memory>
#include <vector>

#include "solvers/bucket_rows.hpp"
#include "solvers/dem_world.hpp"
#include "solvers/bucket_contacts.hpp"
#include "solvers/bucket_selection.hpp"
#include "vehicle/wheel_loader.hpp"

namespace talus {

struct CouplingSettings {
  BucketMaterial material;
  int max_passes = 4;              // outer passes of steps 4-5 (the first included)
  double tolerance = 1.0e-3;       // [m/s] bucket point-velocity disagreement that ends the passes
  // sweeps in each pass after the first, as a fraction of the step's iterations (at least one)
  double pass_sweep_fraction = 0.2;
  // how the bucket rows are swept (BucketSweep): the serial chain (true Gauss-Seidel for the
  // bucket), or colour by colour with the bucket split among a colour's rows, a work-item a row,
  // for devices where the chain's latency is what a sweep waits for (docs/digging.md)
  BucketSweep bucket_sweep = BucketSweep::Serial;
  // measure the particle rows' RMS residual at the end of every step (CouplingStats::
  // particle_residual): one more kernel and a download per step, for convergence studies
  bool record_residual = false;
};

// the particles' mean force on the bucket over a step [N, world], split by the face of the bucket
// each contact presses on, read from the contact's normal in the bucket's frame (x its cutting
// direction along the bottom, z the bottom's normal into the bucket): within 45 deg of +z the
// soil under the bottom bears it up; within 45 deg of -z the soil on the bottom's inside presses
// on it (the held load); within 45 deg of +-x the soil meets a face across the cutting direction
// (-x: the cutting edge's face, the back wall's inside; +x, rare in a dig: the heel's outside
// dragged back through soil). The rest (the side plates, the corner arc) is the whole force less
// these three. A type-G run's terrain support, held load and interface A with the cutting edge's
// brake are the same three parts (docs/validation.md "RD21's overfill has the same cause,
// measured")
struct BucketFaceForces {
  Vec3 below = Vec3::Zero();
  Vec3 inside = Vec3::Zero();
  Vec3 across = Vec3::Zero();
};

// the split of `rows`' impulses over a step of `h` [s], with the bucket at `orientation`
BucketFaceForces bucket_face_forces(const std::vector<ContactRow>& rows,
                                    const Eigen::Quaterniond& orientation, double h);

// what one coupled step did
struct CouplingStats {
  int candidates = 0;          // particles in the bucket's box
  int bucket_contacts = 0;     // rows between particles and the bucket
  int passes = 0;              // outer passes run
  int sweeps = 0;              // particle sweeps over all passes (fewer than N_it per pass when
                               // DemSettings::tolerance stopped them)
  double residual = 0.0;       // final bucket point-velocity disagreement [m/s]
  double max_overlap_rel = 0.0;  // deepest particle-bucket overlap at the step's start / radius
  Vec6 wrench = Vec6::Zero();  // mean wrench of the particles on the bucket over the step [N, N m]
  // wrench's force by the face of the bucket the soil meets (bucket_face_forces)
  BucketFaceForces faces;
  Vec6 impulse = Vec6::Zero(); // the same as an impulse over the step [N s, N m s]
  double embree_seconds = 0.0; // wall time of the Embree queries
  double particle_residual = -1.0;  // RMS particle-row residual after the sweeps [m/s]; -1 unless recorded
};

class SplitSolver {
 public:
  // `dem` and `loader` must outlive the solver; their timesteps become dem.settings().dt
  SplitSolver(Device& dev, DemWorld& dem, vehicle::WheelLoader& loader, const CouplingSettings& settings,
              const embree::Device& embree = embree::Device());

  // one coupled step with the controls already set on the loader
  void step();

  const CouplingStats& stats() const { return stats_; }
  const CouplingSettings& settings() const { return settings_; }
  const BucketScene& bucket_scene() const { return scene_; }
  // the bucket contacts' solved impulses of the last step (particle indices of the whole system)
  const std::vector<BucketImpulse>& bucket_impulses() const { return previous_; }
  // the state between two steps, for a saved state (digging/saved_state): the bucket contacts'
  // impulses, which the next step warm starts from (the particles and the machine save their own)
  void save_state(ByteWriter& w) const;
  void restore_state(ByteReader& r);

 private:
  // the particles near the bucket at the step's start: their indices in the whole system, their
  // state, and their contacts with the bucket mesh (indices into `near`)
  struct NearBucket {
    std::vector<int> candidates;
    Particles near;
    std::vector<BucketContact> contacts;
  };

  // the stages of step(), in order
  // 2. device box selection, the candidates' state, Embree contacts within the speculative reach
  NearBucket find_near_bucket(double h, const Vec3& com, const Vec6& twist_before);
  // 3. the bucket rows warm started from last step's impulses, a first vehicle solve under their
  // wrench, the rows' effective masses from its mobility; rows and bucket go to the device.
  // Returns the rows (particle indices into near.near) and their warm-start impulse on the bucket
  std::vector<ContactRow> start_bucket_rows(const NearBucket& n, const StepParams& params,
                                            const Vec3& com, const Vec6& twist_before,
                                            Vec6* warm_impulse);
  // 4-5. gravity, warm start, sweeps with the bucket rows, and outer passes with the direct
  // vehicle solve until the two sides agree on the bucket's twist; returns the rows' impulse
  Vec6 solve_coupled(std::vector<ContactRow>& rows, const Vec6& warm_impulse, const Vec3& com);
  // the largest speed difference over the bucket's points between two twists [m/s]
  double point_speed_difference(const Vec6& a, const Vec6& b, const Vec3& com) const;

  Device& dev_;
  DemWorld& dem_;
  vehicle::WheelLoader& loader_;
  CouplingSettings settings_;
  BucketScene scene_;
  DeviceBoxSelection selection_;
  BucketRowBlock block_;
  std::vector<BucketImpulse> previous_;
  CouplingStats stats_;
  double bucket_reach_ = 0.0;  // largest distance of a mesh vertex from the mesh origin [m]
};

}  // namespace talus
