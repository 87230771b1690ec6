// Points of a body against rigid flat ground z = ground_height: the bucket's bottom corners
// (cutting-edge ends and heel ends) resting on or sliding along the ground, as when the operator
// lowers the bucket flat to the ground (SPEC §3, FB35). Without it the machine, settling some
// centimetres into its tyres, would sink the bucket's bottom below the ground the particles lie on.
// Per point: a stiff one-sided normal row (λ_n >= 0) and two velocity rows along x and y with
// box-linearised Coulomb friction |λ_t| <= μ λ_n, as the tyre contacts (vehicle/tyre_contact.hpp).
// The rows are present every step (zero force when a point is above the ground), so the sparsity
// of the vehicle system never changes.
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

class PointGroundContact : public Constraint {
 public:
  // `points` in the body's frame
  PointGroundContact(int body, std::vector<Vec3> points, GroundContactParameters p)
      : body_(body), points_(std::move(points)), p_(p) {}
  void add_rows(const std::vector<RigidBody>& bodies, std::vector<ConstraintRow>& rows) override;
  // the sum of the points' normal forces of the last step [N]
  double normal_force() const;
  // the lowest point's height above the ground at the start of the last step [m]
  double clearance() const { return clearance_; }
  const std::vector<Vec3>& points() const { return points_; }

 private:
  int body_;
  std::vector<Vec3> points_;
  GroundContactParameters p_;
  double clearance_ = 0.0;
};

}  // namespace talus::vehicle
