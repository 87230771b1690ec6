// The bucket mesh: rated volume, a consistent closed mesh, and the paper's width.
#include "vehicle/bucket_mesh.hpp"

#include <gtest/gtest.h>

#include <iostream>

#include "host/error.hpp"
#include "vehicle/data_file.hpp"
#include "vehicle/wheel_loader.hpp"

namespace talus::vehicle {
namespace {

TEST(WheelLoaderBucketMeshTest, VolumeWithinTenPercentOfRated) {
  WheelLoader w(find_data_file("wa320", "machines"));
  const BucketMesh& m = w.bucket_mesh();
  std::cout << "[ measured ] struck " << m.struck_volume << " m3, heaped (SAE J742) " << m.heaped_volume << " m3\n";
  EXPECT_NEAR(m.heaped_volume, w.rated_bucket_volume(), 0.10 * w.rated_bucket_volume());
  // the divergence-theorem volume of the triangles agrees with the profile area times width
  EXPECT_NEAR(m.mesh_volume, m.struck_volume, 1e-9 * m.struck_volume);
}

TEST(WheelLoaderBucketMeshTest, TrianglesIndexVerticesAndSpanTheWidth) {
  const BucketMesh m = make_bucket_mesh(BucketGeometry{});
  ASSERT_FALSE(m.triangles.empty());
  double ymin = 0, ymax = 0;
  for (const auto& t : m.triangles) {
    for (int i : t) {
      ASSERT_GE(i, 0);
      ASSERT_LT(i, static_cast<int>(m.vertices.size()));
    }
  }
  for (const auto& v : m.vertices) {
    ymin = std::min(ymin, v.y());
    ymax = std::max(ymax, v.y());
  }
  EXPECT_NEAR(ymax - ymin, 2.685 - 2 * 0.03, 1e-12);  // inner width
  // flat bottom: the cutting edge and the bottom plate lie at z = 0
  EXPECT_DOUBLE_EQ(m.profile[0].z(), 0.0);
  EXPECT_DOUBLE_EQ(m.profile[2].z(), 0.0);
}

TEST(WheelLoaderBucketMeshTest, RejectsImpossibleGeometry) {
  BucketGeometry g;
  g.corner_radius = -0.1;
  EXPECT_THROW(make_bucket_mesh(g), Error);
}

// the mesh moves with the bucket: the tip vertex sits where the data file puts the cutting edge
TEST(WheelLoaderBucketMeshTest, MeshFollowsBucketPose) {
  WheelLoader w(find_data_file("wa320", "machines"), 2000.0);
  EXPECT_LT((w.bucket_mesh_vertex_world(0) - (w.bucket_tip_world() + Vec3(0, -w.bucket_mesh().inner_width / 2, 0))).norm(),
            1e-12);
  EXPECT_LT((w.bucket_tip_world() - Vec3(2.70, 0.0, 0.05)).norm(), 1e-12);
}

}  // namespace
}  // namespace talus::vehicle
