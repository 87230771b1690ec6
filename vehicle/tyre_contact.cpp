#include "vehicle/tyre_contact.hpp"

#include "host/error.hpp"

namespace talus::vehicle {

void TyreContact::add_rows(const std::vector<RigidBody>& bodies, std::vector<ConstraintRow>& rows) {
  const RigidBody& w = bodies.at(wheel_);
  const Vec3 n = Vec3::UnitZ();
  const Vec3 axis = w.vector_to_world(axis_).normalized();
  // lowest point of the wheel's circle: -z with its axial part removed
  Vec3 down = -n + n.dot(axis) * axis;
  if (down.norm() < 1e-9) throw Error("tyre contact: wheel '" + w.name + "' lies flat (axis vertical)");
  down.normalize();
  const Vec3 p = w.position + p_.radius * down;
  deflection_ = p_.ground_height - p.z();
  const BodyFrame ground{kWorld, Vec3::Zero(), Mat3::Identity()};
  const BodyFrame wheel{wheel_, Vec3::Zero(), Mat3::Identity()};
  // normal: gap g = p_z - ground, stiffness E w (a line contact across the tread)
  ConstraintRow normal = point_row(bodies, ground, wheel, p, p, n);
  normal.kind = RowKind::holonomic;
  normal.unit = RowUnit::length;
  normal.violation = -deflection_;
  normal.compliance = 1.0 / (p_.elastic_modulus * p_.width);
  normal.damping_time = p_.damping_time;
  normal.force_min = 0.0;
  const int first = static_cast<int>(rows.size());
  rows.push_back(normal);
  // friction: longitudinal t1 = axis x n (forward for a wheel turning about +y), lateral t2 = n x t1
  longitudinal_ = axis.cross(n).normalized();
  const Vec3 lateral = n.cross(longitudinal_);
  for (const Vec3& t : {longitudinal_, lateral}) {
    ConstraintRow f = point_row(bodies, ground, wheel, p, p, t);
    f.kind = RowKind::velocity;
    f.target_speed = 0.0;
    f.compliance = p_.viscous_compliance;
    f.friction_normal = 0;
    f.friction_coefficient = p_.friction;
    rows.push_back(f);
  }
  (void)first;
}

void TyreContact::save_state(ByteWriter& w) const {
  Constraint::save_state(w);
  w.f64(deflection_);
  write_matrix(w, longitudinal_);
}

void TyreContact::restore_state(ByteReader& r) {
  Constraint::restore_state(r);
  deflection_ = r.f64("tyre contact");
  read_matrix(r, longitudinal_, "tyre contact");
}

}  // namespace talus::vehicle
