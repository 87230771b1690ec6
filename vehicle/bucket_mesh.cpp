#include "vehicle/bucket_mesh.hpp"

#include <algorithm>
#include <cmath>

#include "host/error.hpp"

namespace talus::vehicle {

namespace {

// signed volume of the tetrahedron (0, a, b, c) times 6
double tet6(const Vec3& a, const Vec3& b, const Vec3& c) { return a.dot(b.cross(c)); }

}  // namespace

BucketMesh make_bucket_mesh(const BucketGeometry& g) {
  if (!(g.width > 2 * g.side_plate) || !(g.side_plate >= 0) || !(g.bottom_length > 0) || !(g.corner_radius > 0) ||
      !(g.back_height > g.corner_radius) || !(g.edge_length > 0) || !(g.edge_length < g.bottom_length) || g.corner_segments < 1 || !(g.lip.z() > 0) || !(g.lip.x() < 0)) {
    throw Error("bucket geometry: sizes must be positive, the back higher than the corner radius, "
                "and the lip above and behind the cutting edge");
  }
  BucketMesh m;
  m.inner_width = g.width - 2 * g.side_plate;
  // side profile: tip, bottom, corner arc, back plate, lip
  const double r = g.corner_radius;
  const Vec3 corner_centre(-g.bottom_length, 0.0, r);
  m.profile.push_back(Vec3::Zero());
  m.profile.push_back(Vec3(-g.edge_length, 0.0, 0.0));  // the bolt-on cutting edge
  m.profile.push_back(Vec3(-g.bottom_length, 0.0, 0.0));
  for (int k = 1; k <= g.corner_segments; ++k) {
    const double a = -M_PI / 2 - k * (M_PI / 2) / g.corner_segments;
    m.profile.push_back(corner_centre + r * Vec3(std::cos(a), 0.0, std::sin(a)));
  }
  m.profile.push_back(Vec3(-g.bottom_length - r, 0.0, g.back_height));
  m.profile.push_back(Vec3(g.lip.x(), 0.0, g.lip.z()));
  // profile area (shoelace over the polygon closed by the strike line) and its centroid
  const int np = static_cast<int>(m.profile.size());
  double area2 = 0.0;
  Vec3 c = Vec3::Zero();
  for (int i = 0; i < np; ++i) {
    const Vec3& p = m.profile[i];
    const Vec3& q = m.profile[(i + 1) % np];
    const double cross = p.x() * q.z() - q.x() * p.z();
    area2 += cross;
    c += cross * (p + q);
  }
  const double area = std::abs(area2) / 2;
  m.volume_centroid = c / (3.0 * area2);
  m.struck_volume = area * m.inner_width;
  const double a = g.lip.norm();
  m.heaped_volume = m.struck_volume + a * a * m.inner_width / 8 - a * a * a / 24;
  // vertices: each profile point at y = -b/2 and y = +b/2
  const double y = m.inner_width / 2;
  for (const Vec3& p : m.profile) {
    m.vertices.push_back(Vec3(p.x(), -y, p.z()));
    m.vertices.push_back(Vec3(p.x(), y, p.z()));
  }
  // swept plates: a quad per profile segment
  for (int i = 0; i + 1 < np; ++i) {
    const int a0 = 2 * i, a1 = 2 * i + 1, b0 = 2 * (i + 1), b1 = 2 * (i + 1) + 1;
    m.triangles.push_back({a0, b0, b1});
    m.triangles.push_back({a0, b1, a1});
  }
  // side plates: fans from the tip over the convex profile
  for (int i = 1; i + 1 < np; ++i) {
    m.triangles.push_back({0, 2 * (i + 1), 2 * i});
    m.triangles.push_back({1, 2 * i + 1, 2 * (i + 1) + 1});
  }
  // mesh volume: the swept plates and sides plus the strike-plane quad close the struck volume
  std::vector<std::array<int, 3>> closed = m.triangles;
  const int l0 = 2 * (np - 1), l1 = 2 * (np - 1) + 1;
  closed.push_back({l0, 0, 1});
  closed.push_back({l0, 1, l1});
  double v6 = 0.0;
  for (const auto& t : closed) v6 += tet6(m.vertices[t[0]], m.vertices[t[1]], m.vertices[t[2]]);
  m.mesh_volume = std::abs(v6) / 6.0;
  return m;
}

std::vector<Vec3> bottom_corners(const BucketMesh& mesh) {
  // the heel: the last profile point still on the bottom (z = 0) behind the tip
  double heel = 0.0;
  for (const Vec3& p : mesh.profile) {
    if (p.z() != 0.0) break;
    heel = std::min(heel, p.x());
  }
  if (!(heel < 0.0)) throw Error("bucket mesh: the profile has no flat bottom behind the tip");
  const double half = 0.5 * mesh.inner_width;
  std::vector<Vec3> corners;
  for (double x : {0.0, heel})
    for (double y : {-half, half}) corners.emplace_back(x, y, 0.0);
  return corners;
}

}  // namespace talus::vehicle
