#include "terrain/particles.hpp"

#include <cmath>

namespace talus {

void Particles::add(const Vec3& x, double r, double density) {
  double mass = density * 4.0 / 3.0 * M_PI * r * r * r;
  position.push_back(x);
  velocity.push_back(Vec3::Zero());
  omega.push_back(Vec3::Zero());
  rotation.emplace_back(0.0, 0.0, 0.0, 1.0);
  radius.push_back(r);
  inv_mass.push_back(1.0 / mass);
  inv_inertia.push_back(1.0 / (0.4 * mass * r * r));
}

StaticGeom StaticGeom::plane(const Vec3& point, const Vec3& normal) {
  StaticGeom g;
  g.type = Type::Plane;
  g.centre = point;
  Vec3 n = normal.normalized();
  // any orthonormal completion; only column 0 matters for a plane
  Vec3 t = std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  Vec3 u = n.cross(t).normalized();
  g.axes.col(0) = n;
  g.axes.col(1) = u;
  g.axes.col(2) = n.cross(u);
  return g;
}

StaticGeom StaticGeom::box(const Vec3& centre, const Vec3& half, const Eigen::Matrix3d& axes) {
  StaticGeom g;
  g.type = Type::Box;
  g.centre = centre;
  g.axes = axes;
  g.half = half;
  return g;
}

}  // namespace talus
