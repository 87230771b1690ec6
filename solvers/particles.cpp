#include "solvers/particles.hpp"

#include <algorithm>
#include <cmath>
#include <tuple>

#include "host/error.hpp"

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

void Particles::resize(size_t i, double r, double density) {
  double mass = density * 4.0 / 3.0 * M_PI * r * r * r;
  radius.at(i) = r;
  inv_mass.at(i) = 1.0 / mass;
  inv_inertia.at(i) = 1.0 / (0.4 * mass * r * r);
}

Particles Particles::permuted(const std::vector<size_t>& order) const {
  Particles out;
  for (size_t i : order) {
    out.position.push_back(position[i]);
    out.velocity.push_back(velocity[i]);
    out.omega.push_back(omega[i]);
    out.rotation.push_back(rotation[i]);
    out.radius.push_back(radius[i]);
    out.inv_mass.push_back(inv_mass[i]);
    out.inv_inertia.push_back(inv_inertia[i]);
  }
  return out;
}

Bounds centres_box(const Particles& particles) {
  if (particles.size() == 0) throw Error("centres_box: no particles");
  Bounds box{particles.position[0], particles.position[0]};
  for (const Vec3& x : particles.position) {
    box.lo = box.lo.cwiseMin(x);
    box.hi = box.hi.cwiseMax(x);
  }
  return box;
}

std::vector<size_t> spatial_order(const Particles& particles, double cell) {
  std::vector<size_t> order(particles.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  auto key = [&](size_t i) {
    const Vec3& x = particles.position[i];
    return std::make_tuple(std::floor(x.x() / cell), std::floor(x.y() / cell), x.z());
  };
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return key(a) < key(b); });
  return order;
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
