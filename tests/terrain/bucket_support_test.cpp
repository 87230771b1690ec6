// terrain/bucket_support: the terrain's support under the type-G bucket. Its four points lie on the
// bottom, behind the cutting edge and inside the width; each point's gap is its height over the
// voxel surface along the bottom's normal, and nothing holds a point off the grid, over the bare
// ground, pressed in deeper than the soil bears, or under a bottom that does not face down. A
// bucket set down on a level bed comes to rest on it carrying its weight, pressed in by far less
// than the pressed depth, and slides along it with the bucket-soil friction's deceleration.
#include "terrain/bucket_support.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>

#include "tests/terrain/voxel_test_util.hpp"
#include "vehicle/multibody.hpp"

namespace talus {
namespace {

constexpr double kDeg = M_PI / 180.0;

using test::level_bed;

TEST(BucketSupport, ItsPointsAreOnTheBottomBehindTheEdgeAndInsideTheWidth) {
  const vehicle::BucketGeometry g;
  const vehicle::BucketMesh mesh = vehicle::make_bucket_mesh(g);
  const std::vector<Vec3> points = support_points(mesh);
  ASSERT_EQ(points.size(), 4u);
  for (const Vec3& p : points) {
    EXPECT_EQ(p.z(), 0.0);
    // half the bottom or more behind the tip: at least the coarsest cell (G400, 0.4 m)
    EXPECT_LE(p.x(), -0.5 * g.bottom_length + 1e-12);
    EXPECT_GE(p.x(), -g.bottom_length - 1e-12);
    EXPECT_NEAR(std::abs(p.y()), 0.25 * mesh.inner_width, 1e-12);
  }
  EXPECT_NEAR(points[0].x(), -0.5 * g.bottom_length, 1e-12);
  EXPECT_NEAR(points[3].x(), -g.bottom_length, 1e-12);
}

// on a bed 1 m high (cells of 0.2 m) under a bottom tilted 10 deg: a point 5 cm above the
// surface has the gap 5 cm cos 10 deg, one pressed in by half the pressed depth a negative gap;
// one pressed in twice as deep, one off the grid and one over a bed thinner than the pressed depth
// have nothing under them; a bottom facing 70 deg from down rests on nothing
TEST(BucketSupport, APointsGapIsItsHeightOverTheSurfaceAlongTheBottomsNormal) {
  const VoxelTerrain bed = level_bed(0.2, 1.0);
  const Vec3 n(std::sin(10.0 * kDeg), 0.0, std::cos(10.0 * kDeg));
  const std::vector<Vec3> points = {{0.1, 0.3, 1.05},
                                    {-0.7, -0.2, 1.0 - 0.5 * kPressedDepth},
                                    {0.5, 0.5, 1.0 - 2.0 * kPressedDepth},
                                    {3.5, 0.0, 1.05}};
  const std::vector<double> gaps = support_gaps(bed, points, n);
  ASSERT_EQ(gaps.size(), 4u);
  EXPECT_NEAR(gaps[0], 0.05 * n.z(), 1e-12);
  EXPECT_NEAR(gaps[1], -0.5 * kPressedDepth * n.z(), 1e-12);
  EXPECT_EQ(gaps[2], std::numeric_limits<double>::infinity());
  EXPECT_EQ(gaps[3], std::numeric_limits<double>::infinity());
  const VoxelTerrain thin = level_bed(0.2, 0.5 * kPressedDepth);
  for (double g : support_gaps(thin, {{0.0, 0.0, 0.02}}, Vec3::UnitZ()))
    EXPECT_EQ(g, std::numeric_limits<double>::infinity());
  const Vec3 sideways(std::sin(70.0 * kDeg), 0.0, std::cos(70.0 * kDeg));
  for (double g : support_gaps(bed, points, sideways))
    EXPECT_EQ(g, std::numeric_limits<double>::infinity());
}

// a 2 t bucket body (its profile frame level, its centre of mass over the support's points) set
// down 2 cm over a level bed 0.5 m high with G200's step: after 1 s it rests, the support carries
// its weight and its bottom stands less than a millimetre in (far less than the pressed depth
// push_aside leaves); pushed along its bottom at 1 m/s it slows at mu g (mu = 0.2, the bucket-soil
// friction) and does not sink
TEST(BucketSupport, ABucketRestsOnTheBedAndSlidesAlongItWithTheSoilsFriction) {
  const double h = 0.02, bed_height = 0.5, mass = 2000.0, g = 9.81;
  const VoxelTerrain bed = level_bed(0.2, bed_height);
  const vehicle::BucketMesh mesh = vehicle::make_bucket_mesh(vehicle::BucketGeometry{});
  const BulkSoil soil;
  // the body's centre of mass in the profile frame: over the middle of the support's points
  const Vec3 centre_in_profile(-0.7, 0.0, 0.5);
  vehicle::MultibodySystem system;
  vehicle::RigidBody body;
  body.name = "bucket";
  body.mass = mass;
  body.inertia = Eigen::Matrix3d::Identity() * (mass * 0.5);
  body.position = Vec3(0.0, 0.0, bed_height + 0.02) + centre_in_profile;
  const int b = system.add_body(body);
  BucketSupport support(system, b, mesh, soil);
  // the profile frame where the body stands (its orientation the body's)
  const auto profile_frame = [&] {
    const vehicle::RigidBody& r = system.body(b);
    KinematicBucket k;
    k.orientation = r.orientation;
    k.position = r.position - r.orientation * centre_in_profile;
    k.velocity = r.point_velocity(k.position);
    k.omega = r.angular_velocity;
    return k;
  };
  for (int k = 0; k < 50; ++k) {
    support.update(bed, profile_frame());
    system.step(h);
  }
  const double bottom = profile_frame().position.z();
  std::printf("[ measured ] at rest: bottom %.5f m over the bed, support %.1f N (m g = %.1f N)\n",
              bottom - bed_height, support.force_on_bucket().z(), mass * g);
  EXPECT_NEAR(support.force_on_bucket().z(), mass * g, 1e-3 * mass * g);
  EXPECT_LT(std::abs(bottom - bed_height), 1e-3);
  EXPECT_LT(std::abs(system.body(b).velocity.z()), 1e-4);
  // pushed along its bottom
  system.body(b).velocity = Vec3(1.0, 0.0, 0.0);
  double v_start = 0.0;
  for (int k = 0; k < 20; ++k) {
    support.update(bed, profile_frame());
    system.step(h);
    if (k == 4) v_start = system.body(b).velocity.x();
  }
  const double deceleration = (v_start - system.body(b).velocity.x()) / (15 * h);
  std::printf("[ measured ] sliding: deceleration %.3f m/s^2 (mu g = %.3f), bottom %.5f m\n",
              deceleration, soil.tool_friction * g, profile_frame().position.z() - bed_height);
  EXPECT_NEAR(deceleration, soil.tool_friction * g, 0.02 * soil.tool_friction * g);
  EXPECT_LT(std::abs(profile_frame().position.z() - bed_height), 1e-3);
}

}  // namespace
}  // namespace talus
