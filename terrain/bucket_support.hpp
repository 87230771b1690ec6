// The terrain's support under the bucket (type G, issue 14): the resting soil holds the bucket's
// bottom up as a type-D pile's particles do. The paper's multiscale terrain is a surface the
// machine meets ("When a bucket comes in contact with the terrain surface, the zone of active soil
// movement is predicted", §4.4); only the zone ahead of the cutting edge turns to particles and
// reaches the machine through the aggregate (terrain/aggregate). Without this support the soil
// under the bucket gave way to any force (push_aside moved whatever the bucket's body overlapped),
// so nothing but the aggregate's interfaces and the cutting edge's brake held the bucket: a loaded
// RD21 bucket nosed the machine down to -1.8 deg where type D's pile held it 0.6 to 1.5 deg nose
// up (docs/validation.md "Type G against type D").
//
// The contact: four points on the bottom, at half its length and at its heel (where the corner arc
// starts), a quarter of the inner width either side of the middle, against the voxel surface, one
// frictional plane contact (vehicle/plane_contact) with the bucket-soil friction (0.2, paper
// §4.4). Not the cutting edge: the soil ahead of it is the face the edge cuts (constraint C's
// resistance, the zone's excavation), and a support there lifted the bucket over RD21's face like
// a sled (nothing loaded, the machine pitched 4.6 deg nose up); half the bottom's length (0.475 m)
// is at least the coarsest cell (G400: 0.4 m) behind the edge, so the surface under a point
// interpolates only columns the edge has already cut. Not the side edges either: the columns
// beside the zone's width are uncut pile. Its normal is the bottom's (from the soil into the
// bucket), not the surface's: the floor under a bucket is the trench its own cutting edge cut,
// parallel to the bottom while the bucket moves along it, so sliding along the bottom is free and
// only pressing the bottom into the floor is held; the voxels' staircase slopes would tilt a
// surface normal by the cell's steps. Each point's gap is its height over the
// piecewise-linear surface through the columns' tops (VoxelTerrain::surface_at), times the
// normal's vertical component (the distance to the plane through that surface point parallel to
// the bottom). A point has nothing under it (gap +infinity) off the grid, over soil thinner than
// kPressedDepth (the bare ground: the machine's ground contact holds it there), or pressed in
// deeper than kPressedDepth (the soil gives way there and push_aside moves it, terrain/
// active_zone: a bucket set down on the pile from above, a heel dragged back). The whole contact
// holds nothing while the bottom faces more than 60 deg from down (a bucket curled back or tipped
// to dump). Its rows are stiff, as the ground's (1e8 N/m a point), so the machine presses them in
// by far less than the pressed depth that push_aside leaves in place.
#pragma once
#include <vector>

#include "terrain/multiscale_terrain.hpp"
#include "terrain/voxel_terrain.hpp"
#include "vehicle/bucket_mesh.hpp"
#include "vehicle/ground_contact.hpp"
#include "vehicle/multibody.hpp"
#include "vehicle/plane_contact.hpp"

namespace talus {

struct BucketSupportParameters {
  // [N/m] of the whole patch: its four points each as stiff as the bucket's ground contact
  // (vehicle/ground_contact GroundContactParameters: 1e8 N/m)
  double stiffness = 4.0 * vehicle::GroundContactParameters{}.stiffness;
  double damping_time = vehicle::GroundContactParameters{}.damping_time;  // [s], the ground's
};

// the support's points in the bucket's profile frame (see the header)
std::vector<Vec3> support_points(const vehicle::BucketMesh& mesh);

// the smallest vertical component of the bottom's normal for which the terrain holds the bucket
// up: 0.5, the bottom within 60 deg of facing straight down (see the header)
inline constexpr double kSupportMinNormalZ = 0.5;

// each of `points` (world) over the voxel surface along `normal` (the bottom's, world, unit):
// its gap, or +infinity where nothing holds it (see the header)
std::vector<double> support_gaps(const VoxelTerrain& voxels, const std::vector<Vec3>& points,
                                 const Vec3& normal);

class BucketSupport {
 public:
  // adds the contact between the world's terrain and `system`'s body `bucket`, whose profile frame
  // is `mesh`'s, with the soil's bucket friction
  BucketSupport(vehicle::MultibodySystem& system, int bucket, const vehicle::BucketMesh& mesh,
                const BulkSoil& soil, const BucketSupportParameters& parameters = {});

  // before the machine's step: the points where the bucket stands (`bucket`, its profile frame)
  // over the voxels as the terrain's last step left them
  void update(const VoxelTerrain& voxels, const KinematicBucket& bucket);

  // after the machine's step: the terrain's force on the bucket [N]
  Vec3 force_on_bucket() const { return contact_->force_on_b(); }
  const vehicle::PlaneContact& contact() const { return *contact_; }

 private:
  std::vector<Vec3> points_;  // profile frame
  vehicle::PlaneContact* contact_ = nullptr;
};

}  // namespace talus
