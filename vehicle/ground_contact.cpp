#include "vehicle/ground_contact.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>

#include "host/error.hpp"

namespace talus::vehicle {

namespace {
// rows per point: normal, friction along the plane's two tangents
constexpr int kRowsPerPoint = 3;
}  // namespace

PointGroundContact::PointGroundContact(int body, std::vector<Vec3> points,
                                       GroundContactParameters p)
    : PointGroundContact(body, std::move(points), p, RigidPlane{Vec3::UnitZ(), p.ground_height},
                         0) {}

PointGroundContact::PointGroundContact(int body, std::vector<Vec3> points,
                                       GroundContactParameters p, const RigidPlane& plane,
                                       int max_points)
    : body_(body), points_(std::move(points)), p_(p), plane_(plane) {
  if (points_.empty()) throw Error("point-plane contact: no points");
  check_stiffness(p_.stiffness, "point-plane contact");
  if (!(std::abs(plane_.normal.norm() - 1.0) < 1e-9))
    throw Error("point-plane contact: the plane's normal is not a unit vector");
  const int n = static_cast<int>(points_.size());
  rows_points_ = max_points > 0 ? std::min(max_points, n) : n;
  // world x and y along the ground (frame_from_axis of +z is the identity)
  frame_ = frame_from_axis(plane_.normal);
}

void PointGroundContact::add_rows(const std::vector<RigidBody>& bodies,
                                  std::vector<ConstraintRow>& rows) {
  const BodyFrame world{kWorld, Vec3::Zero(), Mat3::Identity()};
  const BodyFrame body{body_, Vec3::Zero(), Mat3::Identity()};
  // every candidate's world position and gap g = n·p - offset
  const int n = static_cast<int>(points_.size());
  std::vector<Vec3> at(n);
  std::vector<double> gap(n);
  for (int k = 0; k < n; ++k) {
    at[k] = bodies.at(body_).point_to_world(points_[k]);
    gap[k] = plane_.normal.dot(at[k]) - plane_.offset;
  }
  // the rows' points: all of them in order, or the nearest rows_points_ (by gap, then index)
  std::vector<int> chosen(n);
  std::iota(chosen.begin(), chosen.end(), 0);
  if (rows_points_ < n) {
    // (a NaN gap sorts last: the comparison stays a strict weak order)
    const auto key = [&](int k) {
      return std::isnan(gap[k]) ? std::numeric_limits<double>::infinity() : gap[k];
    };
    std::stable_sort(chosen.begin(), chosen.end(), [&](int a, int b) { return key(a) < key(b); });
    chosen.resize(rows_points_);
    // rows in index order: while the same points stay nearest, each row keeps its point and the
    // direct solver's warm start (row by row) stays with it
    std::sort(chosen.begin(), chosen.end());
  }
  clearance_ = std::numeric_limits<double>::infinity();
  for (int k : chosen) clearance_ = std::min(clearance_, gap[k]);
  for (size_t c = 0; c < chosen.size(); ++c) {
    const Vec3& p = at[chosen[c]];
    // normal: the gap, pushed apart only
    ConstraintRow normal = point_row(bodies, world, body, p, p, frame_.col(2));
    normal.kind = RowKind::holonomic;
    normal.unit = RowUnit::length;
    normal.violation = gap[chosen[c]];
    normal.compliance = 1.0 / p_.stiffness;
    normal.damping_time = p_.damping_time;
    normal.force_min = 0.0;
    rows.push_back(normal);
    // friction along the plane, bounded by this point's normal row
    for (int t = 0; t < 2; ++t) {
      ConstraintRow f = point_row(bodies, world, body, p, p, frame_.col(t));
      f.kind = RowKind::velocity;
      f.target_speed = 0.0;
      f.compliance = p_.viscous_compliance;
      f.friction_normal = static_cast<int>(kRowsPerPoint * c);
      f.friction_coefficient = p_.friction;
      rows.push_back(f);
    }
  }
}

double PointGroundContact::normal_force() const { return point_rows_normal_force(forces_); }

Vec3 PointGroundContact::force_on_body() const { return point_rows_force(forces_, frame_); }

}  // namespace talus::vehicle
