// terrain/multiscale_terrain: a bucket moved kinematically into the default pile at G400 and lifted
// out with a curl. The soil's mass (voxels + pool + particles) is kept to 1e-9 at every step, the
// zone's soil becomes particles that the bucket carries, resting ones merge back, and two runs are
// bit-identical.
#include "terrain/multiscale_terrain.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>

#include "host/error.hpp"

namespace talus {
namespace {

struct DigRecord {
  double worst_drift = 0.0;  // largest |total - start| / start over the steps
  int most_particles = 0;
  int merged = 0;
  double excavated = 0.0;
  double carried = 0.0;  // particle mass in the bucket's box at the end [kg]
  double peak_force = 0.0;
  std::vector<float> state;  // final positions, for the bit-for-bit comparison
  Vec6 wrench = Vec6::Zero();
};

// 1.5 s forward at 1 m/s with the bucket level 0.1 m above the ground, then 2 s lifting at
// 0.5 m/s while curling back at 0.4 rad/s, then 2 s standing still
DigRecord kinematic_dig(Device& dev, const std::string& level) {
  const vehicle::BucketMesh mesh = vehicle::make_bucket_mesh(vehicle::BucketGeometry{});
  KinematicBucket b;
  b.position = Vec3(-0.3, 0.0, 0.1);
  MultiscaleTerrain terrain(dev, default_pile_profile(), *find_multiscale_preset(level), mesh, b);
  const double dt = terrain.level().dt;
  const double start = terrain.mass_balance().total();
  DigRecord rec;
  const int steps = static_cast<int>(std::lround(5.5 / dt));
  for (int k = 0; k < steps; ++k) {
    const double t = k * dt;
    b.velocity = t < 1.5 ? Vec3(1.0, 0, 0) : t < 3.5 ? Vec3(0, 0, 0.5) : Vec3::Zero();
    b.omega = t >= 1.5 && t < 3.5 ? Vec3(0, -0.4, 0) : Vec3::Zero();
    terrain.step(b);
    b.position += dt * b.velocity;
    if (b.omega.norm() > 0.0)
      b.orientation = (Eigen::AngleAxisd(dt * b.omega.norm(), b.omega.normalized()) * b.orientation)
                          .normalized();
    const MassBalance m = terrain.mass_balance();
    rec.worst_drift = std::max(rec.worst_drift, std::abs(m.total() - start) / start);
    rec.most_particles =
        std::max(rec.most_particles, static_cast<int>(terrain.particle_masses().size()));
    rec.merged += terrain.last_step().merged;
    rec.excavated += terrain.last_step().excavated;
    rec.peak_force = std::max(rec.peak_force, terrain.last_step().bucket_wrench.head<3>().norm());
  }
  const Particles p = terrain.particles();
  BucketPose pose;
  pose.position = b.position;
  pose.orientation = b.orientation;
  const Aabb box = BucketScene(mesh).world_bounds(pose);
  for (size_t k = 0; k < p.size(); ++k) {
    if (box.contains(p.position[k])) rec.carried += terrain.particle_masses()[k];
    for (int c = 0; c < 3; ++c) rec.state.push_back(static_cast<float>(p.position[k](c)));
  }
  rec.wrench = terrain.last_step().bucket_wrench;
  const MassBalance m = terrain.mass_balance();
  std::printf(
      "[ measured ] %s: %.0f kg excavated, at most %d particles, %d merged, %.0f kg carried in the "
      "bucket, "
      "peak force on the bucket %.1f kN; at the end %.1f kg solid, %.1f kg pool, %.1f kg "
      "particles; "
      "worst mass drift %.2e\n",
      level.c_str(), rec.excavated, rec.most_particles, rec.merged, rec.carried,
      1e-3 * rec.peak_force, m.solid, m.pool, m.particles, rec.worst_drift);
  return rec;
}

TEST(MultiscaleTerrain, AKinematicDigKeepsTheMassAndCarriesTheSoil) {
  Device dev;
  const DigRecord a = kinematic_dig(dev, "G400");
  EXPECT_LT(a.worst_drift, 1e-9);
  EXPECT_GT(a.excavated, 500.0);
  EXPECT_GT(a.most_particles, 5);
  EXPECT_GT(a.carried, 300.0);
  EXPECT_GT(a.peak_force, 0.0);
  // the same inputs, the same bits
  const DigRecord b = kinematic_dig(dev, "G400");
  ASSERT_EQ(a.state.size(), b.state.size());
  EXPECT_EQ(std::memcmp(a.state.data(), b.state.data(), a.state.size() * sizeof(float)), 0);
  EXPECT_EQ(a.wrench, b.wrench);
}

TEST(MultiscaleTerrain, ATypeDLevelIsRefused) {
  Device dev;
  const vehicle::BucketMesh mesh = vehicle::make_bucket_mesh(vehicle::BucketGeometry{});
  EXPECT_THROW(MultiscaleTerrain(dev, default_pile_profile(), fidelity_preset("D400"), mesh,
                                 KinematicBucket{}),
               InputError);
}

}  // namespace
}  // namespace talus
