// Bucket–particle contacts with Embree (SPEC §1 step 3, issue 4 "type-D digging"): the bucket mesh
// (vehicle/bucket_mesh) as an Embree triangle scene, closest-point queries for the particles near
// it, and a host-side candidate selection by the bucket's expanded world bounding box.
//
// Frames. The Embree scene is built once, in the mesh's own (profile) frame, and never rebuilt:
// each step the bucket pose (position + quaternion of that frame in the world) is given, and
// the particle centres are transformed into the bucket frame for the queries, while normals,
// points and lever arms are rotated back into the world. Distances are invariant under the rigid
// transform, so nothing is lost; the alternative, an Embree instance whose transform is updated
// and committed every step, would put the transform in float and add a commit per step for
// nothing. The closest points themselves are computed in double from our own vertex array: Embree
// (float bounds, float query) only decides which triangles to visit, with a search radius that is
// inflated so float rounding can never hide a triangle, and every distance is exact in double.
//
// Contacts. A particle touches the thin-plate shell wherever the distance from its centre to the
// surface has a local minimum below radius × (1 + margin_rel): a face interior, or an edge or
// vertex no neighbouring triangle is closer than. One particle may therefore have several
// contacts (the inner corner between bottom and side plate gives two), while a particle over the
// shared edge of two plates gets one. Because the shell has no thickness, the closest point also
// handles both sides of a plate: the normal points from the particle centre to its closest point,
// so the contact pushes a particle back out to the side it came from. Only if the centre lies on
// the surface itself (distance below 1e-12 m) is the triangle's winding normal used instead.
//
// Conventions follow kernels/dem_types.h TlContact with the particle as body a and the bucket as
// body b: normal from a towards b, gap negative for overlap, contact point in the middle of the
// overlap (centre + normal (r + gap/2)), lever arms from the particle centre and from the bucket
// frame origin (pose.position). The bucket's rigid body has its centre of mass elsewhere: add
// (pose.position - body.position) to arm_bucket for the arm about the centre of mass.
#pragma once
#include <Eigen/Geometry>
#include <array>
#include <vector>

#include "solvers/particles.hpp"
#include "solvers/embree.hpp"
#include "vehicle/bucket_mesh.hpp"
#include "vehicle/wheel_loader.hpp"

namespace talus {

// where the bucket mesh is: world = orientation * local + position
struct BucketPose {
  Vec3 position = Vec3::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();

  Vec3 to_world(const Vec3& local) const { return orientation * local + position; }
  Vec3 to_local(const Vec3& world) const { return orientation.conjugate() * (world - position); }
};

// the pose of a wheel loader's bucket mesh: its profile frame sits at the cutting-edge tip and is
// turned with the bucket body (WheelLoader places it by a pure translation, profile_to_body)
BucketPose bucket_pose(const vehicle::WheelLoader& loader);

// an axis-aligned box [lo, hi]
struct Aabb {
  Vec3 lo = Vec3::Zero();
  Vec3 hi = Vec3::Zero();
  // x lies in the box grown by `grow` [m] on every side (0: the box itself)
  bool contains(const Vec3& x, double grow = 0.0) const {
    return (x.array() >= lo.array() - grow).all() && (x.array() <= hi.array() + grow).all();
  }
};

// the box where particles can touch the bucket: its world bounds grown by r_max (1 + margin_rel);
// BucketScene::select_candidates and DeviceBoxSelection (solvers/bucket_selection.hpp) search it
Aabb candidate_box(const Aabb& bucket_bounds, double r_max, double margin_rel);

// which part of the triangle the closest point lies on
enum class TriangleFeature { Face, Edge, Vertex };

struct ClosestPoint {
  Vec3 point = Vec3::Zero();
  TriangleFeature feature = TriangleFeature::Face;
};

// the point of triangle (a, b, c) closest to p, in double (Voronoi regions, Ericson 2005 §5.1.5);
// degenerate triangles fall back to the closest of their edges
ClosestPoint closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);
// the same for a triangle known to have area (is_degenerate_triangle false), without testing it
// again: the scene's queries call it for every triangle near every candidate
ClosestPoint closest_point_on_proper_triangle(const Vec3& p, const Vec3& a, const Vec3& b,
                                              const Vec3& c);

// true when the triangle has (numerically) no area; such triangles are left out of the scene
// and of the brute-force reference alike (the bucket's side fans have two: they add no surface)
bool is_degenerate_triangle(const Vec3& a, const Vec3& b, const Vec3& c);

struct BucketContact {
  int particle = -1;   // index into Particles
  int triangle = -1;   // mesh triangle holding the closest point
  TriangleFeature feature = TriangleFeature::Face;
  Vec3 normal = Vec3::Zero();         // world, unit, from the particle centre towards the bucket
  double gap = 0.0;                   // distance - radius [m], negative = overlap
  Vec3 point = Vec3::Zero();          // world contact point, middle of the overlap
  Vec3 surface_point = Vec3::Zero();  // world, closest point on the bucket surface
  Vec3 arm_particle = Vec3::Zero();   // point - particle centre
  Vec3 arm_bucket = Vec3::Zero();     // point - pose.position (bucket frame origin)
};

class BucketScene {
 public:
  // builds the Embree scene of the mesh (in its profile frame) once; throws talus::Error on
  // Embree errors and for a mesh with no usable triangle
  explicit BucketScene(const vehicle::BucketMesh& mesh, const embree::Device& device = embree::Device());

  // the mesh's bounding box in its own frame, and the tight world box of its vertices at a pose
  const Aabb& local_bounds() const { return local_bounds_; }
  Aabb world_bounds(const BucketPose& pose) const;

  // particles whose centre lies in world_bounds(pose) expanded by max radius × (1 + margin_rel),
  // in index order: a superset of every particle that find_bucket_contacts can report.
  // Host loop for now; on the device this is one kernel over the positions buffer plus a
  // compaction (docs/embree.md).
  std::vector<int> select_candidates(const Particles& particles, const BucketPose& pose,
                                     double margin_rel) const;

  // contacts of the candidate particles with gap < margin_rel × radius, grouped by candidate in
  // the given order and by triangle index within a particle (deterministic)
  std::vector<BucketContact> find_bucket_contacts(const Particles& particles,
                                                  const std::vector<int>& candidates,
                                                  const BucketPose& pose, double margin_rel) const;

  size_t triangle_count() const { return used_.size(); }  // non-degenerate triangles in the scene
  const std::vector<Vec3>& vertices() const { return vertices_; }
  const std::vector<std::array<int, 3>>& triangles() const { return triangles_; }

 private:
  std::vector<Vec3> vertices_;                  // profile frame, double
  std::vector<std::array<int, 3>> triangles_;   // all mesh triangles
  std::vector<int> used_;                       // Embree primitive id -> mesh triangle index
  Aabb local_bounds_;
  embree::Scene scene_;
};

// the reference: every (non-degenerate) triangle transformed into the world and tested in double,
// no acceleration structure; same contact rules as BucketScene::find_bucket_contacts
std::vector<BucketContact> find_bucket_contacts_brute_force(const vehicle::BucketMesh& mesh,
                                                            const Particles& particles,
                                                            const std::vector<int>& candidates,
                                                            const BucketPose& pose, double margin_rel);

}  // namespace talus
