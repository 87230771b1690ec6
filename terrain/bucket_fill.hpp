// The loaded mass (SPEC §2.4 "mass of soil in the bucket after the cycle"): which particles the
// bucket holds, by the rated-capacity rule of SAE J742 / ISO 7546 that the bucket's volumes
// already follow (vehicle/bucket_mesh.hpp).
//
// Rule: the soil in the bucket is the solid volume of the particles inside the bucket's heaped
// volume, in the bucket's own frame, a grain cut by the boundary counting in part:
//   - struck part: inside the side profile closed by the strike line (tip to lip) and between
//     the side plates (|y| <= inner width / 2);
//   - heap: above the strike plane (outside the profile, on the strike line's open side), no
//     higher than half the distance to the nearest edge of the strike rectangle (the 2:1 heap
//     of SAE J742, whose volume is the mesh's a^2 b / 8 - a^3 / 24).
// Why partial grains: counting whole grains by their centres is unbiased on average, but at D400
// one grain is 87 kg (3 % of a field load), so a grain rolling over the lip made the mass jump by
// that much (issue 11). Each sphere's share inside is measured with a fixed set of quadrature
// points spread evenly through the ball (kBallPoints), so the mass changes smoothly as a grain
// crosses the boundary; the share of a plane-cut ball is exact to about 1 % of the grain.
#pragma once
#include <vector>

#include "solvers/particles.hpp"
#include "solvers/bucket_contacts.hpp"
#include "vehicle/bucket_mesh.hpp"

namespace talus {

// is a point, given in the bucket's profile frame, inside the struck volume? the heaped one?
bool in_struck_volume(const vehicle::BucketMesh& mesh, const Vec3& local);
bool in_heaped_volume(const vehicle::BucketMesh& mesh, const Vec3& local);

// the share of a sphere (centre and radius in the profile frame) that lies in the heaped volume,
// from kBallPoints quadrature points: 0 or 1 away from the boundary, in between across it
double heaped_fraction(const vehicle::BucketMesh& mesh, const Vec3& local_centre, double radius);
inline constexpr int kBallPoints = 512;

// indices of the particles whose centres lie in the heaped volume at the bucket's pose
std::vector<int> particles_in_bucket(const Particles& particles, const vehicle::BucketMesh& mesh,
                                     const BucketPose& pose);

// the mass of soil in the heaped volume [kg]: each particle's mass times its heaped_fraction
// (fixed particles count nothing)
double loaded_mass(const Particles& particles, const vehicle::BucketMesh& mesh, const BucketPose& pose);

}  // namespace talus
