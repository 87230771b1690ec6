// The loaded-mass rule (terrain/bucket_fill): the regions it counts have the volumes the bucket
// mesh states (struck by the shoelace area, heaped by SAE J742's formula), at any pose.
#include "terrain/bucket_fill.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "vehicle/bucket_mesh.hpp"

namespace talus {
namespace {

// the radical inverse of i in `base` (the Halton sequence's coordinate)
double radical_inverse(long i, int base) {
  double f = 1.0, r = 0.0;
  for (; i > 0; i /= base) {
    f /= base;
    r += f * static_cast<double>(i % base);
  }
  return r;
}

// the volume of a region from n Halton points in the box [-2, 1] x [-1.5, 1.5] x [-0.5, 2] m that
// holds the bucket and its heap. A regular lattice would not do: the bucket's bottom and back are
// aligned with it, and which row of points falls inside shifts the count by a whole layer
template <class Inside>
double halton_volume(const vehicle::BucketMesh& mesh, long n, Inside inside) {
  const Vec3 lo(-2.0, -1.5, -0.5), size(3.0, 3.0, 2.5);
  long count = 0;
  for (long i = 1; i <= n; ++i) {
    const Vec3 u(radical_inverse(i, 2), radical_inverse(i, 3), radical_inverse(i, 5));
    if (inside(mesh, lo + size.cwiseProduct(u))) ++count;
  }
  return size.prod() * static_cast<double>(count) / static_cast<double>(n);
}

TEST(BucketFill, StruckAndHeapedRegionsHaveTheMeshVolumes) {
  const auto mesh = vehicle::make_bucket_mesh(vehicle::BucketGeometry{});
  // a million quasi-random points: the estimate's error is well under 0.1% of these volumes
  const long n = 1000000;
  const double struck = halton_volume(mesh, n, in_struck_volume);
  const double heaped = halton_volume(mesh, n, in_heaped_volume);
  std::printf("[ measured ] struck %.4f m^3 (mesh %.4f), heaped %.4f m^3 (SAE J742 %.4f)\n", struck,
              mesh.struck_volume, heaped, mesh.heaped_volume);
  EXPECT_NEAR(struck, mesh.struck_volume, 0.002 * mesh.struck_volume);
  EXPECT_NEAR(heaped, mesh.heaped_volume, 0.002 * mesh.heaped_volume);
  EXPECT_GT(heaped, struck);
}

TEST(BucketFill, LoadedMassIsTheSameAtAnyPose) {
  // particles on a lattice in the profile frame, then carried with a turned and moved bucket
  const auto mesh = vehicle::make_bucket_mesh(vehicle::BucketGeometry{});
  BucketPose pose;
  pose.position = Vec3(4.0, -0.3, 1.7);
  pose.orientation = Eigen::AngleAxisd(0.7, Vec3(0.2, 1.0, 0.1).normalized());
  Particles p;
  long inside = 0;
  for (double x = -1.6; x < 0.3; x += 0.1)
    for (double y = -1.4; y < 1.4; y += 0.1)
      for (double z = -0.2; z < 1.8; z += 0.1) {
        const Vec3 local(x + 0.013, y + 0.007, z + 0.011);
        p.add(pose.to_world(local), 0.04, 2590.0);
        if (in_heaped_volume(mesh, local)) ++inside;
      }
  // one fixed particle inside weighs nothing
  p.add(pose.to_world(Vec3(-0.5, 0.0, 0.3)), 0.04, 2590.0);
  p.inv_mass.back() = 0.0;
  const double m = loaded_mass(p, mesh, pose);
  // the same particles at the bucket's own frame hold the same mass (the quadrature points are
  // taken in the bucket's frame, so only rounding differs)
  Particles at_rest = p;
  for (size_t i = 0; i < p.size(); ++i) at_rest.position[i] = pose.to_local(p.position[i]);
  EXPECT_NEAR(loaded_mass(at_rest, mesh, BucketPose()), m, 1e-9 * m);
  // grains cut by the boundary count in part; this lattice is aligned with the bottom plate, so
  // the layer whose centres lie just above it counts only half and the shares fall below the
  // count of centres by a few percent
  EXPECT_GT(inside, 1000);
  EXPECT_LT(m, inside * p.mass(0));
  EXPECT_GT(m, 0.9 * inside * p.mass(0));
  EXPECT_EQ(particles_in_bucket(p, mesh, pose).size(), static_cast<size_t>(inside + 1));
}

TEST(BucketFill, ABallCutInHalfByTheBottomPlateCountsHalf) {
  // a ball centred on the bottom plate, far from every other boundary: half of it is inside
  const auto mesh = vehicle::make_bucket_mesh(vehicle::BucketGeometry{});
  const double f = heaped_fraction(mesh, Vec3(-0.5, 0.0, 0.0), 0.2);
  std::printf("[ measured ] share of a ball cut by the bottom plate: %.4f (exact 0.5)\n", f);
  EXPECT_NEAR(f, 0.5, 0.01);
  EXPECT_DOUBLE_EQ(heaped_fraction(mesh, Vec3(-0.5, 0.0, 0.4), 0.2), 1.0);
  EXPECT_DOUBLE_EQ(heaped_fraction(mesh, Vec3(-0.5, 0.0, -0.4), 0.2), 0.0);
}

TEST(BucketFill, AD400GrainCrossingTheSidePlateChangesTheMassSmoothly) {
  // one 0.4 m grain (87 kg), under the strike plane, carried in 5 mm steps out through the side
  // plate's plane: with
  // centres counted the mass jumped by the whole grain at once; now no step moves it by more than
  // the share of a 5 mm slice of the ball (at most 3 % of it at the equator), and it runs from
  // the full grain to nothing
  const auto mesh = vehicle::make_bucket_mesh(vehicle::BucketGeometry{});
  BucketPose pose;
  Particles p;
  const double r = 0.2;
  p.add(Vec3(-0.5, 0.0, 0.25), r, 2590.0);
  const double grain = p.mass(0);
  const double y0 = 0.5 * mesh.inner_width - 1.5 * r;
  double previous = -1.0, largest_jump = 0.0, first = 0.0, last = 0.0;
  for (int k = 0; k <= 120; ++k) {
    p.position[0] = Vec3(-0.5, y0 + 0.005 * k, 0.25);
    const double m = loaded_mass(p, mesh, pose);
    if (k == 0) first = m;
    if (previous >= 0.0) largest_jump = std::max(largest_jump, std::abs(m - previous));
    previous = last = m;
  }
  std::printf("[ measured ] grain %.1f kg: from %.1f kg to %.1f kg, largest step %.2f kg\n", grain, first,
              last, largest_jump);
  EXPECT_NEAR(first, grain, 1e-9 * grain);
  EXPECT_NEAR(last, 0.0, 1e-9 * grain);
  EXPECT_LT(largest_jump, 0.03 * grain);
}

TEST(BucketFill, PointsOutsideTheBucketAreNotCounted) {
  const auto mesh = vehicle::make_bucket_mesh(vehicle::BucketGeometry{});
  EXPECT_TRUE(in_struck_volume(mesh, Vec3(-0.5, 0.0, 0.2)));
  EXPECT_FALSE(in_heaped_volume(mesh, Vec3(-0.5, 0.0, -0.1)));                 // under the bottom
  EXPECT_FALSE(in_heaped_volume(mesh, Vec3(-0.5, 0.6 * mesh.inner_width, 0.2)));  // beside the sides
  EXPECT_FALSE(in_heaped_volume(mesh, Vec3(0.2, 0.0, 0.05)));                  // in front of the tip
  // above the strike line's middle: inside up to half the distance to the nearest edge
  const Vec3 mid = 0.5 * (mesh.profile.front() + mesh.profile.back());
  const Vec3 up = Vec3(1.0, 0.0, 1.0).normalized();
  const double half_length = 0.5 * mesh.profile.back().norm();
  EXPECT_TRUE(in_heaped_volume(mesh, mid + up * (0.49 * half_length)));
  EXPECT_FALSE(in_heaped_volume(mesh, mid + up * (0.51 * half_length)));
}

}  // namespace
}  // namespace talus
