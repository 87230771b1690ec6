#include "vehicle/point_brake.hpp"

namespace talus::vehicle {

void PointBrake::add_rows(const std::vector<RigidBody>& bodies, std::vector<ConstraintRow>& rows) {
  const BodyFrame world{kWorld, Vec3::Zero(), Mat3::Identity()};
  const BodyFrame body{body_, Vec3::Zero(), Mat3::Identity()};
  const Vec3 p = bodies.at(body_).point_to_world(point_);
  // the point's velocity along the direction held at zero, by a force on the body against the
  // direction of at most max_force (the row's force acts along +direction: its range is
  // [-max_force, 0])
  ConstraintRow row = point_row(bodies, world, body, p, p, direction_);
  row.kind = RowKind::velocity;
  row.target_speed = 0.0;
  row.compliance = 1e-10;  // [m/(N s)]: as the motors', a stiff but regular row
  row.force_min = -max_force_;
  row.force_max = 0.0;
  rows.push_back(row);
}

}  // namespace talus::vehicle
