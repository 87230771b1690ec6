// A brake on one point of a body along a direction: one velocity row that holds the point still
// along the direction unless the force it needs exceeds a bound, and then lets it go on against
// that bound, as Coulomb friction does. Its owner sets the direction and the bound every step; a
// bound of zero makes the row carry nothing, so it stays in the system and the sparsity never
// changes. The type-G terrain's penetration resistance (issue 14, paper §4.4, "constraint C"):
// the bucket's cutting edge cannot advance into dense soil until the machine pushes harder than
// the soil's resistance to the edge (terrain/penetration).
#pragma once
#include "vehicle/constraint.hpp"

namespace talus::vehicle {

class PointBrake : public Constraint {
 public:
  explicit PointBrake(int body) : body_(body) {}
  // the point (in the body's frame), the direction the brake resists its motion along (world,
  // unit) and the largest force it gives against that motion [N]; motion the other way is free
  void set(const Vec3& point, const Vec3& direction, double max_force) {
    point_ = point;
    direction_ = direction;
    max_force_ = max_force;
  }
  void add_rows(const std::vector<RigidBody>& bodies, std::vector<ConstraintRow>& rows) override;
  // the force the brake gave the body along -direction in the last solve [N] (>= 0)
  double force() const { return forces_.empty() ? 0.0 : -forces_[0]; }
  double max_force() const { return max_force_; }
  const Vec3& direction() const { return direction_; }

 private:
  int body_;
  Vec3 point_ = Vec3::Zero();
  Vec3 direction_ = Vec3::UnitX();
  double max_force_ = 0.0;
};

}  // namespace talus::vehicle
