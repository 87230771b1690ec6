#include "terrain/bucket_fill.hpp"

#include <algorithm>
#include <cmath>

namespace talus {

namespace {

// the 2:1 heap of SAE J742: its height grows by one for every two of distance from the edges
constexpr double kHeapSlope = 0.5;
// [m] how far outside the heaped volume's box a point is still given the exact test: far above
// the rounding of a bucket's metre-sized coordinates (1e-16 m), far below a grain
constexpr double kBoundsSlack = 1e-9;

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

// the radical inverse of i in `base` (a coordinate of the Halton sequence)
double radical_inverse(int i, int base) {
  double f = 1.0, r = 0.0;
  for (; i > 0; i /= base) {
    f /= base;
    r += f * static_cast<double>(i % base);
  }
  return r;
}

// kBallPoints points evenly spread through the unit ball: the Halton points (bases 2, 3, 5) of the
// cube [-1, 1]^3 that fall inside it. Quasi-random rather than a lattice, so that no plane of the
// bucket lines up with a layer of points
const std::vector<Vec3>& unit_ball_points() {
  static const std::vector<Vec3> points = [] {
    std::vector<Vec3> out;
    for (int i = 1; static_cast<int>(out.size()) < kBallPoints; ++i) {
      const Vec3 u(2.0 * radical_inverse(i, 2) - 1.0, 2.0 * radical_inverse(i, 3) - 1.0,
                   2.0 * radical_inverse(i, 5) - 1.0);
      if (u.squaredNorm() <= 1.0) out.push_back(u);
    }
    return out;
  }();
  return points;
}

// a box in the profile frame that holds the whole heaped volume: the profile, and the strike
// rectangle raised by the heap's highest point (half the distance to its nearest edge, at most)
Aabb heaped_bounds(const vehicle::BucketMesh& mesh) {
  Aabb box{Vec3::Constant(1e300), Vec3::Constant(-1e300)};
  const double half_width = 0.5 * mesh.inner_width;
  const double length = (mesh.profile.back() - mesh.profile.front()).norm();
  const double apex = kHeapSlope * std::min(0.5 * length, half_width);
  for (const Vec3& p : mesh.profile) {
    box.lo = box.lo.cwiseMin(p);
    box.hi = box.hi.cwiseMax(p);
  }
  // the heap rises along the strike line's normal, a unit vector in the x-z plane
  box.lo -= Vec3(apex, 0.0, apex);
  box.hi += Vec3(apex, 0.0, apex);
  box.lo.y() = -half_width;
  box.hi.y() = half_width;
  return box;
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
  if (mesh.profile.size() < 3) return out;
  // a centre outside the box that holds the heaped volume is not in it: the box first (a type-G
  // step asks for every particle of the zone, most of them ahead of the bucket: issue 14), grown
  // by kBoundsSlack so that the exact test's rounding at the box's faces (the heap's ridge) decides
  const Aabb bounds = heaped_bounds(mesh);
  for (size_t i = 0; i < particles.size(); ++i) {
    const Vec3 local = pose.to_local(particles.position[i]);
    if (!bounds.contains(local, kBoundsSlack)) continue;
    if (in_heaped_volume(mesh, local)) out.push_back(static_cast<int>(i));
  }
  return out;
}

double heaped_fraction(const vehicle::BucketMesh& mesh, const Vec3& local_centre, double radius) {
  int inside = 0;
  for (const Vec3& u : unit_ball_points())
    if (in_heaped_volume(mesh, local_centre + radius * u)) ++inside;
  return static_cast<double>(inside) / static_cast<double>(kBallPoints);
}

double loaded_mass(const Particles& particles, const vehicle::BucketMesh& mesh, const BucketPose& pose) {
  if (mesh.profile.size() < 3) return 0.0;
  const Aabb bounds = heaped_bounds(mesh);
  double m = 0.0;
  for (size_t i = 0; i < particles.size(); ++i) {
    if (particles.inv_mass[i] <= 0.0) continue;
    const Vec3 local = pose.to_local(particles.position[i]);
    const double r = particles.radius[i];
    // a ball wholly outside the heaped volume's box holds nothing in it
    if (!bounds.contains(local, r)) continue;
    m += particles.mass(i) * heaped_fraction(mesh, local, r);
  }
  return m;
}

}  // namespace talus
