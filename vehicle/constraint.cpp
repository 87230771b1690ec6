#include "vehicle/constraint.hpp"

#include <cmath>
#include <string>

#include "host/error.hpp"

namespace talus::vehicle {

void Constraint::store_forces(const double* impulse, int count, double h) {
  forces_.assign(count, 0.0);
  for (int i = 0; i < count; ++i) forces_[i] = impulse[i] / h;
}

void Constraint::save_state(ByteWriter& w) const {
  w.u64(forces_.size());
  w.f64s(forces_.data(), forces_.size());
}

void Constraint::restore_state(ByteReader& r) {
  const std::uint64_t n = r.u64("constraint forces");
  r.need_elements(n, 8, "constraint forces");
  forces_.assign(n, 0.0);
  r.f64s(forces_.data(), forces_.size(), "constraint forces");
}

BodyFrame BodyFrame::from_world(const std::vector<RigidBody>& bodies, int body, const Vec3& world_anchor,
                                const Mat3& world_axes) {
  BodyFrame f;
  f.body = body;
  if (body == kWorld) {
    f.anchor = world_anchor;
    f.axes = world_axes;
  } else {
    const RigidBody& b = bodies.at(body);
    f.anchor = b.point_to_local(world_anchor);
    f.axes = b.rotation().transpose() * world_axes;
  }
  return f;
}

Vec3 BodyFrame::world_anchor(const std::vector<RigidBody>& bodies) const {
  return body == kWorld ? anchor : bodies[body].point_to_world(anchor);
}

Mat3 BodyFrame::world_axes(const std::vector<RigidBody>& bodies) const {
  return body == kWorld ? axes : Mat3(bodies[body].rotation() * axes);
}

Vec3 BodyFrame::lever(const std::vector<RigidBody>& bodies, const Vec3& world_point) const {
  return body == kWorld ? Vec3::Zero() : Vec3(world_point - bodies[body].position);
}

Mat3 frame_from_axis(const Vec3& axis) {
  const Vec3 z = axis.normalized();
  // any vector not parallel to z gives x; prefer world x, then world y
  const Vec3 seed = std::abs(z.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  const Vec3 y = z.cross(seed).normalized();
  const Vec3 x = y.cross(z);
  Mat3 m;
  m << x, y, z;
  return m;
}

void check_stiffness(double stiffness, const std::string& what) {
  if (!(stiffness > 0.0 && std::isfinite(stiffness)))
    throw Error(what + ": stiffness " + std::to_string(stiffness) +
                " N/m is not a positive finite number");
}

double point_rows_normal_force(const std::vector<double>& forces) {
  double f = 0.0;
  for (size_t k = 0; k < forces.size(); k += 3) f += forces[k];
  return f;
}

Vec3 point_rows_force(const std::vector<double>& forces, const Mat3& frame) {
  Vec3 f = Vec3::Zero();
  for (size_t k = 0; k + 2 < forces.size(); k += 3)
    f += forces[k] * frame.col(2) + forces[k + 1] * frame.col(0) + forces[k + 2] * frame.col(1);
  return f;
}

ConstraintRow point_row(const std::vector<RigidBody>& bodies, const BodyFrame& a, const BodyFrame& b,
                        const Vec3& point_a, const Vec3& point_b, const Vec3& n) {
  ConstraintRow r;
  // d/dt n·(p_b - p_a) with n held: n·(v_b + ω_b × r_b - v_a - ω_a × r_a)
  if (a.body != kWorld) {
    JacobianBlock ja;
    ja.body = a.body;
    ja.jacobian << -n, -a.lever(bodies, point_a).cross(n);
    r.blocks.push_back(ja);
  }
  if (b.body != kWorld) {
    JacobianBlock jb;
    jb.body = b.body;
    jb.jacobian << n, b.lever(bodies, point_b).cross(n);
    r.blocks.push_back(jb);
  }
  return r;
}

ConstraintRow angular_row(const BodyFrame& a, const BodyFrame& b, const Vec3& n) {
  ConstraintRow r;
  if (a.body != kWorld) r.blocks.push_back({a.body, (Vec6() << Vec3::Zero(), -n).finished()});
  if (b.body != kWorld) r.blocks.push_back({b.body, (Vec6() << Vec3::Zero(), n).finished()});
  return r;
}

ConstraintRow dot_row(const BodyFrame& a, const BodyFrame& b, const Vec3& u, const Vec3& w) {
  return angular_row(a, b, w.cross(u));
}

}  // namespace talus::vehicle
