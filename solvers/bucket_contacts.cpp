#include "solvers/bucket_contacts.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "host/error.hpp"

namespace talus {

namespace {

// below this centre-to-surface distance the direction to the closest point is noise [m]
constexpr double kOnSurface = 1e-12;
// a point lies on a triangle when it is this close to it [m] (shared edges and vertices)
constexpr double kTouch = 1e-9;

// one triangle within range of one particle, in the frame the query ran in
struct Candidate {
  int tri = -1;
  double dist = 0.0;
  ClosestPoint cp;
};

// closest point on segment [a, b]
ClosestPoint closest_on_segment(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return {a + t * ab, (t == 0.0 || t == 1.0) ? TriangleFeature::Vertex : TriangleFeature::Edge};
}

// strict order of candidates: nearer first, then lower triangle index
bool better(const Candidate& x, const Candidate& y) {
  return x.dist < y.dist || (x.dist == y.dist && x.tri < y.tri);
}

// whether p lies outside triangle t's bounds grown by twice kTouch: then it is farther than
// kTouch from the triangle with room for the exact test's rounding, a cheaper test than its
// closest point that decides the same
bool beyond_touch(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Aabb bounds{a.cwiseMin(b).cwiseMin(c), a.cwiseMax(b).cwiseMax(c)};
  return !bounds.contains(p, 2.0 * kTouch);
}

// keeps the local minima of the distance over the surface: a candidate whose closest point lies
// on a better candidate's triangle (a shared edge or vertex with a nearer neighbour, or the same
// point found twice) is not one. `cands` sorted by triangle index; vertices in the query's frame.
std::vector<Candidate> local_minima(const std::vector<Candidate>& cands, const std::vector<Vec3>& v,
                                    const std::vector<std::array<int, 3>>& tris) {
  std::vector<Candidate> kept;
  for (size_t i = 0; i < cands.size(); ++i) {
    bool drop = false;
    for (size_t j = 0; j < cands.size() && !drop; ++j) {
      if (j == i || !better(cands[j], cands[i])) continue;
      const auto& t = tris[cands[j].tri];
      // most better candidates are far triangles of a large bucket's range (issue 14: a type-G
      // step spent a tenth of its host time on their closest points)
      if (beyond_touch(cands[i].cp.point, v[t[0]], v[t[1]], v[t[2]])) continue;
      // (candidates come from triangles with area alone: the scene and the brute force skip
      // the others)
      const Vec3 q =
          closest_point_on_proper_triangle(cands[i].cp.point, v[t[0]], v[t[1]], v[t[2]]).point;
      drop = (q - cands[i].cp.point).norm() <= kTouch;
    }
    if (!drop) kept.push_back(cands[i]);
  }
  return kept;
}

// the contact of a kept candidate; centre, closest point and triangle are in the query's frame,
// which `rotation` (directions) and `to_world` (points) take to the world
template <class ToWorld>
BucketContact make_contact(int particle, double radius, const Vec3& centre, const Candidate& c,
                           const std::vector<Vec3>& v, const std::vector<std::array<int, 3>>& tris,
                           const Eigen::Quaterniond& rotation, const ToWorld& to_world,
                           const Vec3& bucket_origin) {
  Vec3 n = c.cp.point - centre;
  if (c.dist > kOnSurface) {
    n /= c.dist;
  } else {
    // centre on the surface: the winding normal (no side is preferred by the geometry)
    const auto& t = tris[c.tri];
    n = (v[t[1]] - v[t[0]]).cross(v[t[2]] - v[t[0]]).normalized();
  }
  BucketContact k;
  k.particle = particle;
  k.triangle = c.tri;
  k.feature = c.cp.feature;
  k.normal = rotation * n;
  k.gap = c.dist - radius;
  const Vec3 centre_w = to_world(centre);
  k.surface_point = to_world(c.cp.point);
  k.point = centre_w + k.normal * (radius + 0.5 * k.gap);
  k.arm_particle = k.point - centre_w;
  k.arm_bucket = k.point - bucket_origin;
  return k;
}

// what the embree point-query callback needs for one particle
struct QueryData {
  const std::vector<Vec3>* vertices;
  const std::vector<std::array<int, 3>>* triangles;
  const std::vector<int>* used;
  Vec3 centre;    // bucket frame, double
  double range;   // radius × (1 + margin_rel)
  std::vector<Candidate>* out;
};

// embree calls this for every triangle whose bounds meet the query sphere; the exact test is ours
bool closest_point_callback(RTCPointQueryFunctionArguments* args) {
  auto* q = static_cast<QueryData*>(args->userPtr);
  const int tri = (*q->used)[args->primID];
  const auto& t = (*q->triangles)[tri];
  const auto& v = *q->vertices;
  // (the scene holds no degenerate triangle: BucketScene keeps only the others in used_)
  const ClosestPoint cp = closest_point_on_proper_triangle(q->centre, v[t[0]], v[t[1]], v[t[2]]);
  const double d = (cp.point - q->centre).norm();
  if (d < q->range) q->out->push_back({tri, d, cp});
  return false;  // the query radius is left as it is: we want every triangle in range
}

}  // namespace

ClosestPoint closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  if (is_degenerate_triangle(a, b, c)) {
    ClosestPoint best = closest_on_segment(p, a, b);
    for (const ClosestPoint& s : {closest_on_segment(p, b, c), closest_on_segment(p, c, a)})
      if ((s.point - p).squaredNorm() < (best.point - p).squaredNorm()) best = s;
    return best;
  }
  return closest_point_on_proper_triangle(p, a, b, c);
}

ClosestPoint closest_point_on_proper_triangle(const Vec3& p, const Vec3& a, const Vec3& b,
                                              const Vec3& c) {
  // voronoi regions of the vertices, edges and face in turn
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return {a, TriangleFeature::Vertex};
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return {b, TriangleFeature::Vertex};
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return {a + (d1 / (d1 - d3)) * ab, TriangleFeature::Edge};
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return {c, TriangleFeature::Vertex};
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return {a + (d2 / (d2 - d6)) * ac, TriangleFeature::Edge};
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return {b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b), TriangleFeature::Edge};
  const double denom = 1.0 / (va + vb + vc);
  return {a + ab * (vb * denom) + ac * (vc * denom), TriangleFeature::Face};
}

bool is_degenerate_triangle(const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a;
  const double scale = ab.squaredNorm() + ac.squaredNorm() + (c - b).squaredNorm();
  return !(ab.cross(ac).norm() > 1e-12 * scale);
}

BucketPose bucket_pose(const vehicle::WheelLoader& loader) {
  BucketPose pose;
  pose.position = loader.bucket_tip_world();
  pose.orientation = loader.bodies().at(loader.bucket_body()).orientation;
  return pose;
}

BucketScene::BucketScene(const vehicle::BucketMesh& mesh, const embree::Device& device)
    : vertices_(mesh.vertices), triangles_(mesh.triangles), scene_(device, RTC_SCENE_FLAG_ROBUST) {
  const int nv = static_cast<int>(vertices_.size());
  for (int i = 0; i < static_cast<int>(triangles_.size()); ++i) {
    const auto& t = triangles_[i];
    for (int k : t)
      if (k < 0 || k >= nv) throw Error("bucket mesh: triangle " + std::to_string(i) + " names vertex " +
                                        std::to_string(k) + " of " + std::to_string(nv));
    if (!is_degenerate_triangle(vertices_[t[0]], vertices_[t[1]], vertices_[t[2]])) used_.push_back(i);
  }
  if (used_.empty()) throw Error("bucket mesh: no triangle with an area; nothing to collide with");
  // float copies for embree: they only steer the traversal, distances are computed in double
  std::vector<float> xyz;
  xyz.reserve(3 * vertices_.size());
  local_bounds_.lo = Vec3::Constant(std::numeric_limits<double>::infinity());
  local_bounds_.hi = -local_bounds_.lo;
  for (const Vec3& p : vertices_) {
    for (int k = 0; k < 3; ++k) xyz.push_back(static_cast<float>(p[k]));
    local_bounds_.lo = local_bounds_.lo.cwiseMin(p);
    local_bounds_.hi = local_bounds_.hi.cwiseMax(p);
  }
  std::vector<unsigned> idx;
  idx.reserve(3 * used_.size());
  for (int i : used_)
    for (int k : triangles_[i]) idx.push_back(static_cast<unsigned>(k));
  embree::attach_triangles(scene_, xyz.data(), vertices_.size(), idx.data(), used_.size());
  scene_.commit();
}

Aabb candidate_box(const Aabb& bucket_bounds, double r_max, double margin_rel) {
  Aabb box = bucket_bounds;
  const Vec3 grow = Vec3::Constant(r_max * (1.0 + margin_rel));
  box.lo -= grow;
  box.hi += grow;
  return box;
}

Aabb BucketScene::world_bounds(const BucketPose& pose) const {
  Aabb box;
  box.lo = Vec3::Constant(std::numeric_limits<double>::infinity());
  box.hi = -box.lo;
  for (const Vec3& p : vertices_) {
    const Vec3 w = pose.to_world(p);
    box.lo = box.lo.cwiseMin(w);
    box.hi = box.hi.cwiseMax(w);
  }
  return box;
}

std::vector<int> BucketScene::select_candidates(const Particles& particles, const BucketPose& pose,
                                                double margin_rel) const {
  std::vector<int> out;
  if (particles.size() == 0) return out;
  const double r_max = *std::max_element(particles.radius.begin(), particles.radius.end());
  const Aabb box = candidate_box(world_bounds(pose), r_max, margin_rel);
  for (size_t i = 0; i < particles.size(); ++i)
    if (box.contains(particles.position[i])) out.push_back(static_cast<int>(i));
  return out;
}

std::vector<BucketContact> BucketScene::find_bucket_contacts(const Particles& particles,
                                                             const std::vector<int>& candidates,
                                                             const BucketPose& pose,
                                                             double margin_rel) const {
  std::vector<BucketContact> contacts;
  std::vector<Candidate> found;
  QueryData data{&vertices_, &triangles_, &used_, Vec3::Zero(), 0.0, &found};
  RTCPointQueryContext context;
  rtcInitPointQueryContext(&context);
  const auto to_world = [&](const Vec3& x) { return pose.to_world(x); };
  for (int i : candidates) {
    if (i < 0 || static_cast<size_t>(i) >= particles.size())
      throw Error("find_bucket_contacts: candidate " + std::to_string(i) + " is not a particle index");
    const double r = particles.radius[i];
    found.clear();
    data.centre = pose.to_local(particles.position[i]);
    data.range = r * (1.0 + margin_rel);
    // the float query sphere is inflated so rounding of the centre and of embree's float bounds
    // can only add triangles (the callback rejects them in double), never lose one
    RTCPointQuery q;
    q.x = static_cast<float>(data.centre.x());
    q.y = static_cast<float>(data.centre.y());
    q.z = static_cast<float>(data.centre.z());
    q.time = 0.0f;
    q.radius = static_cast<float>(data.range * (1.0 + 1e-5) + 1e-6 * (1.0 + data.centre.lpNorm<Eigen::Infinity>()));
    rtcPointQuery(scene_.get(), &q, &context, closest_point_callback, &data);
    if (found.empty()) continue;
    std::sort(found.begin(), found.end(), [](const Candidate& a, const Candidate& b) { return a.tri < b.tri; });
    for (const Candidate& c : local_minima(found, vertices_, triangles_))
      contacts.push_back(make_contact(i, r, data.centre, c, vertices_, triangles_, pose.orientation,
                                      to_world, pose.position));
  }
  scene_.device().check("rtcPointQuery");
  return contacts;
}

std::vector<BucketContact> find_bucket_contacts_brute_force(const vehicle::BucketMesh& mesh,
                                                            const Particles& particles,
                                                            const std::vector<int>& candidates,
                                                            const BucketPose& pose, double margin_rel) {
  // the whole mesh in the world, every triangle against every candidate
  std::vector<Vec3> w(mesh.vertices.size());
  for (size_t k = 0; k < w.size(); ++k) w[k] = pose.to_world(mesh.vertices[k]);
  std::vector<BucketContact> contacts;
  const Eigen::Quaterniond identity = Eigen::Quaterniond::Identity();
  const auto same = [](const Vec3& x) { return x; };
  for (int i : candidates) {
    const Vec3& x = particles.position.at(i);
    const double r = particles.radius[i];
    std::vector<Candidate> found;
    for (int t = 0; t < static_cast<int>(mesh.triangles.size()); ++t) {
      const auto& tri = mesh.triangles[t];
      if (is_degenerate_triangle(w[tri[0]], w[tri[1]], w[tri[2]])) continue;
      const ClosestPoint cp = closest_point_on_proper_triangle(x, w[tri[0]], w[tri[1]], w[tri[2]]);
      const double d = (cp.point - x).norm();
      if (d < r * (1.0 + margin_rel)) found.push_back({t, d, cp});
    }
    for (const Candidate& c : local_minima(found, w, mesh.triangles))
      contacts.push_back(make_contact(i, r, x, c, w, mesh.triangles, identity, same, pose.position));
  }
  return contacts;
}

}  // namespace talus
