// solvers/bucket_selection: the device selection of particles near the bucket against the
// host's double-precision box test, on fresh random particles (seed printed on failure).
#include <gtest/gtest.h>

#include <cstdio>
#include <random>

#include "solvers/dem_world.hpp"
#include "solvers/bucket_selection.hpp"
#include "vehicle/bucket_mesh.hpp"

namespace talus {
namespace {

TEST(BucketSelection, DeviceSelectsWhatTheHostSelectsAndOnlyBoundaryExtras) {
  const unsigned seed = std::random_device{}();
  SCOPED_TRACE("seed " + std::to_string(seed));
  std::mt19937_64 rng(seed);
  Device dev;
  DeviceBoxSelection selection(dev);
  const BucketScene scene(vehicle::make_bucket_mesh(vehicle::BucketGeometry{}));
  std::uniform_real_distribution<double> u(0.0, 1.0), pos(-3.0, 3.0), rad(0.02, 0.1);
  for (int trial = 0; trial < 5; ++trial) {
    // a random bucket pose, its candidate box, particles around it and exactly on its faces
    BucketPose pose;
    pose.orientation = Eigen::Quaterniond(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5).normalized();
    pose.position = Vec3(pos(rng), pos(rng), pos(rng));
    Particles p;
    const Aabb bounds = scene.world_bounds(pose);
    for (int i = 0; i < 5000; ++i) {
      Vec3 x;
      for (int k = 0; k < 3; ++k) x[k] = bounds.lo[k] + (bounds.hi[k] - bounds.lo[k]) * (1.6 * u(rng) - 0.3);
      p.add(x, rad(rng), 2590.0);
    }
    double r_max = 0.0;
    for (double r : p.radius) r_max = std::max(r_max, r);
    const Aabb box = candidate_box(bounds, r_max, 0.05);
    for (int i = 0; i < 200; ++i) {
      Vec3 x = box.lo + (box.hi - box.lo).cwiseProduct(Vec3(u(rng), u(rng), u(rng)));
      int k = i % 3;
      x[k] = (i % 2) ? box.lo[k] : box.hi[k];
      p.add(x, 0.05, 2590.0);
    }
    // the device sees the particles as float, like the DEM buffers hold them
    std::vector<cl_float4> x(p.size());
    for (size_t i = 0; i < p.size(); ++i) x[i] = to_float4(p.position[i], p.radius[i]);
    Buffer<cl_float4> position(dev, x.size());
    position.upload(x);
    std::vector<int> device = selection.select(position, p.size(), box);
    std::vector<int> host = scene.select_candidates(p, pose, 0.05);
    // every host candidate is selected; an extra lies within float rounding of the box
    std::vector<char> on_device(p.size(), 0);
    for (int i : device) on_device[i] = 1;
    for (int i : host) ASSERT_TRUE(on_device[i]) << "particle " << i << " missed";
    ASSERT_TRUE(std::is_sorted(device.begin(), device.end()));
    size_t extras = 0;
    for (int i : device) {
      if (box.contains(p.position[i])) continue;
      ++extras;
      Vec3 outside = (box.lo - p.position[i]).cwiseMax(p.position[i] - box.hi).cwiseMax(0.0);
      EXPECT_LT(outside.maxCoeff(), 1e-4) << "particle " << i;
    }
    std::printf("trial %d: %zu host candidates, %zu device (%zu boundary extras)\n", trial, host.size(),
                device.size(), extras);
  }
}

}  // namespace
}  // namespace talus
