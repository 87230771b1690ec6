// A rigid body in maximal coordinates: centre-of-mass position, orientation quaternion, linear and
// angular velocity in the world frame (SPEC §2.1, paper §4.1). The velocity of a body is the 6-vector
// [v; ω] (world frame, v of the centre of mass); a wrench is [force at the centre of mass; torque].
#pragma once
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>

namespace talus::vehicle {

using Vec3 = Eigen::Vector3d;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat3 = Eigen::Matrix3d;
using Mat6 = Eigen::Matrix<double, 6, 6>;

struct RigidBody {
  std::string name;
  double mass = 1.0;                 // kg
  Mat3 inertia = Mat3::Identity();   // kg m², body frame, about the centre of mass
  Vec3 position = Vec3::Zero();      // centre of mass, world, m
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  Vec3 velocity = Vec3::Zero();          // m/s
  Vec3 angular_velocity = Vec3::Zero();  // rad/s, world frame
  bool fixed = false;                // static body: infinite mass, never moves

  Mat3 rotation() const { return orientation.toRotationMatrix(); }
  Mat3 inverse_inertia_world() const;
  Vec3 point_to_world(const Vec3& local) const { return position + orientation * local; }
  Vec3 point_to_local(const Vec3& world) const { return orientation.conjugate() * (world - position); }
  Vec3 vector_to_world(const Vec3& local) const { return orientation * local; }
  Vec3 vector_to_local(const Vec3& world) const { return orientation.conjugate() * world; }
  Vec3 point_velocity(const Vec3& world_point) const {
    return velocity + angular_velocity.cross(world_point - position);
  }
  Vec6 twist() const;

  // q⁺ = exp(h ω / 2) q (exact rotation over the step, then renormalised), x⁺ = x + h v
  void integrate(double h);
};

// merge a point mass (a payload) into a body: new centre of mass, parallel-axis inertia; the
// body's frame keeps its orientation, so points given in world coordinates stay where they are
void add_point_mass(RigidBody& body, double mass, const Vec3& world_point);

}  // namespace talus::vehicle
