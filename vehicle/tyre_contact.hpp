// Tyre-ground contact on rigid flat ground z = ground_height (SPEC §2.4, paper §4.2): one contact
// at the lowest point of the wheel's circle, a compliant normal row (linear elastic modulus E over the
// tyre width: stiffness k = E w, so ε = 1/(E w)) with λ_n >= 0, and two velocity rows (longitudinal,
// lateral) with box-linearised Coulomb friction |λ_t| <= μ λ_n, solved by the direct solver.
// The rows are present every step (zero force when the wheel is off the ground), so the sparsity
// pattern of the vehicle system never changes.
#pragma once
#include "vehicle/constraint.hpp"

namespace talus::vehicle {

struct TyreParameters {
  double radius = 0.695;            // m
  double width = 0.52;              // m
  double elastic_modulus = 1.0e6;   // Pa
  double friction = 2.0;            // μ
  double damping_time = 0.02;       // s
  double viscous_compliance = 1e-9;  // m/(N s) of the friction rows
  double ground_height = 0.0;       // m
};

class TyreContact : public Constraint {
 public:
  // wheel body and its spin axis in the wheel's body frame
  TyreContact(int wheel, const Vec3& local_axis, TyreParameters p) : wheel_(wheel), axis_(local_axis), p_(p) {}
  void add_rows(const std::vector<RigidBody>& bodies, std::vector<ConstraintRow>& rows) override;
  double normal_force() const { return forces_.empty() ? 0.0 : forces_[0]; }
  double longitudinal_force() const { return forces_.size() > 1 ? forces_[1] : 0.0; }
  double lateral_force() const { return forces_.size() > 2 ? forces_[2] : 0.0; }
  // tyre deflection at the start of the last step [m] (positive: pressed into the ground)
  double deflection() const { return deflection_; }
  // the longitudinal direction of the last step (wheel heading on the ground)
  const Vec3& longitudinal() const { return longitudinal_; }
  int wheel() const { return wheel_; }
  const TyreParameters& parameters() const { return p_; }
  // the base's forces, the deflection and the heading of the last step
  void save_state(ByteWriter& w) const override;
  void restore_state(ByteReader& r) override;

 private:
  int wheel_;
  Vec3 axis_;
  TyreParameters p_;
  double deflection_ = 0.0;
  Vec3 longitudinal_ = Vec3::UnitX();
};

}  // namespace talus::vehicle
