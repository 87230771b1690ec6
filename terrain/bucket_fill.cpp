#include "terrain/bucket_fill.hpp"

#include <algorithm>
#include <cmath>

namespace talus {

namespace {

// the 2:1 heap of SAE J742: its height grows by one for every two of distance from the edges
constexpr double kHeapSlope = 0.5;

// even-odd test of (x, z) against the profile polygon closed by the strike line
bool in_profile(const std::vector<Vec3>& profile, double x, double z) {
  bool inside = false;
  const size_t n = profile.size();
  for (size_t i = 0, j = n - 1; i < n; j = i++) {
    const Vec3& a = profile[i];
    const Vec3& b = profile[j];
    if ((a.z() > z) != (b.z() > z) && x < (b.x() - a.x()) * (z - a.z()) / (b.z() - a.z()) + a.x())
      inside = !inside;
  }
  return inside;
}

}  // namespace

bool in_struck_volume(const vehicle::BucketMesh& mesh, const Vec3& local) {
  return std::abs(local.y()) <= 0.5 * mesh.inner_width && mesh.profile.size() >= 3 &&
         in_profile(mesh.profile, local.x(), local.z());
}

bool in_heaped_volume(const vehicle::BucketMesh& mesh, const Vec3& local) {
  const double half_width = 0.5 * mesh.inner_width;
  if (std::abs(local.y()) > half_width || mesh.profile.size() < 3) return false;
  if (in_struck_volume(mesh, local)) return true;
  // the strike line from the tip (profile start) to the lip (profile end); the heap lies on the
  // side away from the profile's interior
  const Vec3& tip = mesh.profile.front();
  const Vec3& lip = mesh.profile.back();
  const Vec3 along = (lip - tip).normalized();
  Vec3 up(-along.z(), 0.0, along.x());  // the strike line's normal in the x-z plane
  // the interior lies where the profile's middle point is: the heap is on the other side
  const Vec3& middle = mesh.profile[mesh.profile.size() / 2];
  if ((middle - tip).dot(up) > 0.0) up = -up;
  const double s = (local - tip).dot(along);
  const double height = (local - tip).dot(up);
  const double length = (lip - tip).norm();
  if (height < 0.0 || s < 0.0 || s > length) return false;
  const double to_edge = std::min({s, length - s, half_width - std::abs(local.y())});
  return height <= kHeapSlope * to_edge;
}

std::vector<int> particles_in_bucket(const Particles& particles, const vehicle::BucketMesh& mesh,
                                     const BucketPose& pose) {
  std::vector<int> out;
  for (size_t i = 0; i < particles.size(); ++i)
    if (in_heaped_volume(mesh, pose.to_local(particles.position[i]))) out.push_back(static_cast<int>(i));
  return out;
}

double loaded_mass(const Particles& particles, const vehicle::BucketMesh& mesh, const BucketPose& pose) {
  double m = 0.0;
  for (int i : particles_in_bucket(particles, mesh, pose)) m += particles.mass(i);
  return m;
}

}  // namespace talus
