#include "vehicle/rigid_body.hpp"

#include "host/error.hpp"

namespace talus::vehicle {

Mat3 RigidBody::inverse_inertia_world() const {
  const Mat3 R = rotation();
  return R * inertia.inverse() * R.transpose();
}

Vec6 RigidBody::twist() const {
  Vec6 t;
  t << velocity, angular_velocity;
  return t;
}

void RigidBody::integrate(double h) {
  if (fixed) return;
  position += h * velocity;
  // rotate by the angle |ω| h about ω, exactly
  const double angle = angular_velocity.norm() * h;
  if (angle > 0.0) {
    const Eigen::Quaterniond dq(Eigen::AngleAxisd(angle, angular_velocity.normalized()));
    orientation = dq * orientation;
  }
  orientation.normalize();
}

void add_point_mass(RigidBody& body, double mass, const Vec3& world_point) {
  if (!(mass >= 0.0)) throw Error("add_point_mass: mass must be >= 0");
  if (mass == 0.0) return;
  // combined centre of mass, then both inertias moved there (parallel axis, world frame)
  const double total = body.mass + mass;
  const Vec3 com = (body.mass * body.position + mass * world_point) / total;
  const Mat3 R = body.rotation();
  auto shift = [](double m, const Vec3& d) { return m * (d.squaredNorm() * Mat3::Identity() - d * d.transpose()); };
  const Mat3 world_inertia = R * body.inertia * R.transpose() + shift(body.mass, body.position - com) +
                             shift(mass, world_point - com);
  body.inertia = R.transpose() * world_inertia * R;
  body.mass = total;
  body.position = com;
}

}  // namespace talus::vehicle
