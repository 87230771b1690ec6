// The loaded mass (SPEC §2.4 "mass of soil in the bucket after the cycle"): which particles the
// bucket holds, by the rated-capacity rule of SAE J742 / ISO 7546 that the bucket's volumes
// already follow (vehicle/bucket_mesh.hpp).
//
// Rule: a particle is in the bucket when its centre lies in the bucket's heaped volume, in the
// bucket's own frame:
//   - struck part: inside the side profile closed by the strike line (tip to lip) and between
//     the side plates (|y| <= inner width / 2);
//   - heap: above the strike plane (outside the profile, on the strike line's open side), no
//     higher than half the distance to the nearest edge of the strike rectangle (the 2:1 heap
//     of SAE J742, whose volume is the mesh's a^2 b / 8 - a^3 / 24).
// Counting centres rather than clipping sphere volumes is unbiased for a layer of particles
// crossing the boundary and exact in the limit of small particles; at D400 one particle is
// 1% of the bucket's capacity, which bounds the rule's granularity there.
#pragma once
#include <vector>

#include "terrain/bucket_contacts.hpp"
#include "terrain/particles.hpp"
#include "vehicle/bucket_mesh.hpp"

namespace talus {

// is a point, given in the bucket's profile frame, inside the struck volume? the heaped one?
bool in_struck_volume(const vehicle::BucketMesh& mesh, const Vec3& local);
bool in_heaped_volume(const vehicle::BucketMesh& mesh, const Vec3& local);

// indices of the particles whose centres lie in the heaped volume at the bucket's pose
std::vector<int> particles_in_bucket(const Particles& particles, const vehicle::BucketMesh& mesh,
                                     const BucketPose& pose);

// their mass [kg] (fixed particles count nothing)
double loaded_mass(const Particles& particles, const vehicle::BucketMesh& mesh, const BucketPose& pose);

}  // namespace talus
