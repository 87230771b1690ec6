#include "vehicle/ground_contact.hpp"

#include <algorithm>
#include <limits>

namespace talus::vehicle {

namespace {
// rows per point: normal, friction along x, friction along y
constexpr int kRowsPerPoint = 3;
}  // namespace

void PointGroundContact::add_rows(const std::vector<RigidBody>& bodies, std::vector<ConstraintRow>& rows) {
  const BodyFrame ground{kWorld, Vec3::Zero(), Mat3::Identity()};
  const BodyFrame body{body_, Vec3::Zero(), Mat3::Identity()};
  clearance_ = std::numeric_limits<double>::infinity();
  for (size_t k = 0; k < points_.size(); ++k) {
    const Vec3 p = bodies.at(body_).point_to_world(points_[k]);
    const double gap = p.z() - p_.ground_height;
    clearance_ = std::min(clearance_, gap);
    // normal: gap g = z - ground, pushed apart only
    ConstraintRow normal = point_row(bodies, ground, body, p, p, Vec3::UnitZ());
    normal.kind = RowKind::holonomic;
    normal.unit = RowUnit::length;
    normal.violation = gap;
    normal.compliance = 1.0 / p_.stiffness;
    normal.damping_time = p_.damping_time;
    normal.force_min = 0.0;
    rows.push_back(normal);
    // friction along the ground's axes, bounded by this point's normal row
    for (const Vec3& t : {Vec3(Vec3::UnitX()), Vec3(Vec3::UnitY())}) {
      ConstraintRow f = point_row(bodies, ground, body, p, p, t);
      f.kind = RowKind::velocity;
      f.target_speed = 0.0;
      f.compliance = p_.viscous_compliance;
      f.friction_normal = static_cast<int>(kRowsPerPoint * k);
      f.friction_coefficient = p_.friction;
      rows.push_back(f);
    }
  }
}

double PointGroundContact::normal_force() const {
  double f = 0.0;
  for (size_t k = 0; k < forces_.size(); k += kRowsPerPoint) f += forces_[k];
  return f;
}

}  // namespace talus::vehicle
