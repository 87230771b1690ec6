// Points of a body against a rigid plane of the world: the flat ground z = ground_height (the
// default), where the bucket's bottom corners (cutting-edge and heel ends) rest on or slide along
// it as when the operator lowers the bucket flat to the ground (SPEC §3, FB35), or a wall of the
// pile's container (SPEC §2.5: "piles of gravel confined with vertical walls at the sides and
// the rear", paper §5), which the bucket meets when a cycle drives it through the pile. Without
// the ground the machine, settling some centimetres into its tyres, would sink the bucket's bottom
// below the ground the particles lie on; without the walls it would drive the bucket through the
// rear wall while the wall held its load back (docs/multiscale.md, "The sweep's empty-bucket
// cycles").
// Per point: a stiff one-sided normal row (λ_n >= 0) and two velocity rows along the plane with
// box-linearised Coulomb friction |λ_t| <= μ λ_n, as the tyre contacts (vehicle/tyre_contact.hpp);
// the tangents are frame_from_axis(normal)'s, world x and y for the ground.
// A contact may hold more candidate points than it has rows (`max_points`): each step the rows go
// to the candidates nearest the plane (the deepest first; equal gaps by index, so the choice is
// the same on every run), as a bucket's hull meets a wall with whichever part leads. The rows are
// present every step (zero force when a point is off the plane), so the sparsity of the vehicle
// system never changes.
#pragma once
#include <vector>

#include "vehicle/constraint.hpp"

namespace talus::vehicle {

struct GroundContactParameters {
  double stiffness = 1.0e8;          // N/m per point
  double friction = 0.2;             // μ
  double damping_time = 0.05;        // s
  double viscous_compliance = 1e-9;  // m/(N s) of the friction rows
  double ground_height = 0.0;        // m
};

// a rigid plane of the world: the points x with normal · x = offset, free on the side `normal`
// points to (unit)
struct RigidPlane {
  Vec3 normal = Vec3::UnitZ();
  double offset = 0.0;  // [m]
};

class PointGroundContact : public Constraint {
 public:
  // `points` in the body's frame, against the flat ground z = p.ground_height
  PointGroundContact(int body, std::vector<Vec3> points, GroundContactParameters p);
  // `points` in the body's frame against `plane` (p.ground_height unused); rows for the
  // `max_points` of them nearest the plane each step (all of them when 0 or more than there are).
  // Throws talus::Error for a normal that is not unit length, no points or a stiffness that is
  // not positive and finite
  PointGroundContact(int body, std::vector<Vec3> points, GroundContactParameters p,
                     const RigidPlane& plane, int max_points);
  void add_rows(const std::vector<RigidBody>& bodies, std::vector<ConstraintRow>& rows) override;
  // the sum of the points' normal forces of the last step [N]
  double normal_force() const;
  // the whole force of the plane on the body in the last step, friction included [N]
  Vec3 force_on_body() const;
  // the nearest point's distance from the plane at the start of the last step [m] (negative: it
  // was pressed in)
  double clearance() const { return clearance_; }
  const std::vector<Vec3>& points() const { return points_; }
  const RigidPlane& plane() const { return plane_; }

 private:
  int body_;
  std::vector<Vec3> points_;
  GroundContactParameters p_;
  RigidPlane plane_;
  int rows_points_;  // how many points get rows each step
  Mat3 frame_;       // tangents and normal of the rows (columns 0, 1: along the plane; 2: normal)
  double clearance_ = 0.0;
};

}  // namespace talus::vehicle
