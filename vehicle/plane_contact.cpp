#include "vehicle/plane_contact.hpp"

#include <cmath>
#include <limits>
#include <string>

#include "host/error.hpp"

namespace talus::vehicle {
namespace {
constexpr int kRowsPerPoint = 3;  // normal, two friction
}

PlaneContact::PlaneContact(int body_a, int body_b, int points, PlaneContactParameters p)
    : a_(body_a), b_(body_b), points_(points) {
  if (points < 1) throw Error("plane contact: a patch needs at least one point");
  g_.points.assign(points, Vec3::Zero());
  g_.gaps.assign(points, 0.0);
  set_parameters(p);
}

void PlaneContact::set_parameters(const PlaneContactParameters& p) {
  check_stiffness(p.stiffness, "plane contact '" + name + "'");
  p_ = p;
}

void PlaneContact::set_geometry(const PlaneContactGeometry& g) {
  if (static_cast<int>(g.points.size()) != points_)
    throw Error("plane contact '" + name + "': " + std::to_string(g.points.size()) +
                " points for a patch of " + std::to_string(points_));
  if (static_cast<int>(g.gaps.size()) != points_)
    throw Error("plane contact '" + name + "': " + std::to_string(g.gaps.size()) +
                " gaps for a patch of " + std::to_string(points_) + " points");
  for (double gap : g.gaps)
    if (std::isnan(gap) || gap == -std::numeric_limits<double>::infinity())
      throw Error("plane contact '" + name + "': a gap of " + std::to_string(gap) +
                  " m (a point's gap is finite, or +infinity with nothing under it)");
  g_ = g;
}

void PlaneContact::add_rows(const std::vector<RigidBody>& bodies,
                            std::vector<ConstraintRow>& rows) {
  const BodyFrame a{a_, Vec3::Zero(), Mat3::Identity()};
  const BodyFrame b{b_, Vec3::Zero(), Mat3::Identity()};
  frame_ = frame_from_axis(g_.normal);
  for (int k = 0; k < points_; ++k) {
    const Vec3& p = g_.points[k];
    // a point with nothing under it, in a contact that is active, carries nothing either
    const bool carries = g_.active && std::isfinite(g_.gaps[k]);
    // normal: the gap, pushed apart only; an inactive contact carries no force
    ConstraintRow normal = point_row(bodies, a, b, p, p, frame_.col(2));
    normal.kind = RowKind::holonomic;
    normal.unit = RowUnit::length;
    normal.violation = carries ? g_.gaps[k] : 0.0;
    normal.compliance = points_ / p_.stiffness;
    normal.damping_time = p_.damping_time;
    normal.force_min = 0.0;
    if (!carries) normal.force_max = 0.0;
    rows.push_back(normal);
    // friction along the plane, bounded by this point's normal row
    for (int t = 0; t < 2; ++t) {
      ConstraintRow f = point_row(bodies, a, b, p, p, frame_.col(t));
      f.kind = RowKind::velocity;
      f.target_speed = 0.0;
      f.compliance = p_.viscous_compliance;
      f.friction_normal = kRowsPerPoint * k;
      f.friction_coefficient = carries ? p_.friction : 0.0;
      if (!carries) f.force_min = f.force_max = 0.0;
      rows.push_back(f);
    }
  }
}

double PlaneContact::normal_force() const { return point_rows_normal_force(forces_); }

Vec3 PlaneContact::force_on_b() const { return point_rows_force(forces_, frame_); }

}  // namespace talus::vehicle
