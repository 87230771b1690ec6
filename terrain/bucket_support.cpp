#include "terrain/bucket_support.hpp"

#include <limits>
#include <memory>
#include <optional>

namespace talus {

std::vector<Vec3> support_points(const vehicle::BucketMesh& mesh) {
  // the heel from the bottom's corners (the tip's two ends, then the heel's)
  const double heel = vehicle::bottom_corners(mesh)[2].x();
  const double quarter = 0.25 * mesh.inner_width;
  std::vector<Vec3> points;
  for (double x : {0.5 * heel, heel})
    for (double y : {-quarter, quarter}) points.emplace_back(x, y, 0.0);
  return points;
}

std::vector<double> support_gaps(const VoxelTerrain& voxels, const std::vector<Vec3>& points,
                                 const Vec3& normal) {
  constexpr double kNothing = std::numeric_limits<double>::infinity();
  std::vector<double> gaps(points.size(), kNothing);
  // a bottom that does not face down rests on nothing
  if (!(normal.z() >= kSupportMinNormalZ)) return gaps;
  for (size_t k = 0; k < points.size(); ++k) {
    const Vec3& c = points[k];
    const std::optional<double> surface = voxels.surface_at(c.x(), c.y());
    // off the grid, or over the bare ground (the machine's ground contact's)
    if (!surface || *surface - voxels.z0() < kPressedDepth) continue;
    // along the normal to the plane through the surface point parallel to the bottom
    const double gap = normal.z() * (c.z() - *surface);
    // pressed in deeper than the soil bears: it gives way there (push_aside)
    if (gap < -kPressedDepth) continue;
    gaps[k] = gap;
  }
  return gaps;
}

BucketSupport::BucketSupport(vehicle::MultibodySystem& system, int bucket,
                             const vehicle::BucketMesh& mesh, const BulkSoil& soil,
                             const BucketSupportParameters& parameters)
    : points_(support_points(mesh)) {
  vehicle::PlaneContactParameters p;
  p.stiffness = parameters.stiffness;
  p.damping_time = parameters.damping_time;
  p.friction = soil.tool_friction;
  contact_ = &system.add_constraint(std::make_unique<vehicle::PlaneContact>(
      vehicle::kWorld, bucket, static_cast<int>(points_.size()), p));
  contact_->name = "terrain support (bucket bottom)";
}

void BucketSupport::update(const VoxelTerrain& voxels, const KinematicBucket& bucket) {
  // the points in the world, and the bottom's normal from the soil into the bucket
  vehicle::PlaneContactGeometry g;
  g.active = true;
  for (const Vec3& c : points_) g.points.push_back(bucket.orientation * c + bucket.position);
  g.normal = bucket.orientation * Vec3::UnitZ();
  g.gaps = support_gaps(voxels, g.points, g.normal);
  contact_->set_geometry(g);
}

}  // namespace talus
