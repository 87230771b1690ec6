// The bucket as a triangle mesh from parametric geometry (SPEC §2.4: flat bottom, 2.685 m wide,
// 3.0 m³, bolt-on cutting edge). The side profile, in the bucket's profile frame (x forward along the
// bottom plate, z up, origin at the cutting-edge tip, y across), runs
//   tip -> flat bottom -> circular corner -> back plate -> top lip (spill guard),
// and the bucket is that profile swept over the inner width, closed by two side plates.
// Vertices and triangles are exposed for an Embree scene; volumes follow SAE J742: struck volume
// (profile area under the strike line from tip to lip, times the inner width) plus the heap above the
// strike plane at 2:1 (a² b / 8 - a³ / 24 for strike length a and inner width b).
#pragma once
#include <array>
#include <vector>

#include "vehicle/rigid_body.hpp"

namespace talus::vehicle {

struct BucketGeometry {
  double width = 2.685;          // m, outer
  double side_plate = 0.03;      // m, side plate thickness
  double bottom_length = 0.95;   // m, tip to the start of the corner
  double corner_radius = 0.45;   // m
  double back_height = 1.0;      // m, top of the back plate above the bottom
  Vec3 lip = Vec3(-1.2, 0.0, 1.2);  // m, top lip in the profile frame (y ignored)
  double edge_length = 0.1;      // m, bolt-on cutting edge along the bottom at the tip
  int corner_segments = 8;
};

struct BucketMesh {
  std::vector<Vec3> vertices;                 // profile frame
  std::vector<std::array<int, 3>> triangles;  // outward-facing where it matters: inner surface
  std::vector<Vec3> profile;                  // x-z polyline from the tip to the lip (y = 0)
  double inner_width = 0.0;                   // m
  double struck_volume = 0.0;                 // m³
  double heaped_volume = 0.0;                 // m³ (SAE J742)
  double mesh_volume = 0.0;                   // m³, divergence theorem over the mesh closed at the strike plane
  Vec3 volume_centroid = Vec3::Zero();        // of the struck volume, profile frame
};

// the bottom's four corners in the profile frame: both ends of the cutting edge and of the heel
// (the last profile point on the flat bottom, where the corner arc starts), across the inner
// width; where the bucket meets the ground (vehicle/wheel_loader) and the type-G terrain's surface
// (terrain/bucket_support)
std::vector<Vec3> bottom_corners(const BucketMesh& mesh);

// throws talus::Error for impossible geometry (non-positive sizes, lip not above and behind the tip)
BucketMesh make_bucket_mesh(const BucketGeometry& g);

}  // namespace talus::vehicle
