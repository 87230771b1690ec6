// Constraint rows for the SPOOK stepper (SPEC §2.1). A constraint (joint, motor, contact, driveline)
// contributes rows each step; a row couples any number of bodies through 1x6 Jacobian blocks, and
// carries its kind (holonomic with violation g, or velocity with target u), compliance and damping,
// and force bounds. Body index -1 is the world (no columns).
#pragma once
#include <limits>
#include <string>
#include <vector>

#include "host/binary.hpp"
#include "vehicle/rigid_body.hpp"

namespace talus::vehicle {

inline constexpr double kInfinity = std::numeric_limits<double>::infinity();
inline constexpr int kWorld = -1;

struct JacobianBlock {
  int body = kWorld;
  Vec6 jacobian = Vec6::Zero();  // [∂/∂v; ∂/∂ω] of the row velocity
};

enum class RowKind { holonomic, velocity };
// what a holonomic row's violation measures, for diagnostics
enum class RowUnit { length, angle, other };

struct ConstraintRow {
  std::vector<JacobianBlock> blocks;
  RowKind kind = RowKind::holonomic;
  RowUnit unit = RowUnit::other;
  double violation = 0.0;       // g (holonomic rows)
  double target_speed = 0.0;    // u (velocity rows)
  double compliance = 0.0;      // ε: holonomic [m/N or rad/(N m)], velocity rows [m/(N s)] viscous
  double damping_time = 0.0;    // τ [s] (holonomic rows)
  double force_min = -kInfinity;  // N or N m; the impulse range is h [force_min, force_max]
  double force_max = kInfinity;
  int friction_normal = -1;     // >= 0: index, among this constraint's rows, of the normal row
  double friction_coefficient = 0.0;
  bool joint = false;           // a bilateral joint row (counted in joint-violation diagnostics)
};

// the parameters that make a joint non-ideal (paper eq. 2): compliance ε and damping time τ
struct RowParameters {
  double compliance = 1e-10;    // m/N (rad/(N m) for rotation rows)
  double damping_time = 0.02;   // s
};

class Constraint {
 public:
  virtual ~Constraint() = default;
  // append this step's rows, from the bodies' state at the start of the step
  virtual void add_rows(const std::vector<RigidBody>& bodies, std::vector<ConstraintRow>& rows) = 0;
  // after a solve: this constraint's row velocities G v⁺ and impulses; return true if it changed
  // its rows' bounds (a speed-dependent torque limit) so that the system must solve again
  virtual bool update_bounds(const double* row_velocity, const double* impulse, ConstraintRow* rows, int count) {
    (void)row_velocity; (void)impulse; (void)rows; (void)count;
    return false;
  }
  // the impulses of this constraint's rows after the solve, converted to forces (impulse / h)
  virtual void store_forces(const double* impulse, int count, double h);
  const std::vector<double>& forces() const { return forces_; }
  // what this constraint carries from one step to the next, for a saved state (digging/
  // saved_state): the base keeps the last step's forces, which the sensors read; a constraint
  // with more adds its own after them. restore_state reads what save_state wrote
  virtual void save_state(ByteWriter& w) const;
  virtual void restore_state(ByteReader& r);
  std::string name;

 protected:
  std::vector<double> forces_;
};

// a point fixed to a body with a frame of axes (columns), both in body coordinates
struct BodyFrame {
  int body = kWorld;
  Vec3 anchor = Vec3::Zero();
  Mat3 axes = Mat3::Identity();
  // from a world pose at assembly
  static BodyFrame from_world(const std::vector<RigidBody>& bodies, int body, const Vec3& world_anchor,
                              const Mat3& world_axes);
  Vec3 world_anchor(const std::vector<RigidBody>& bodies) const;
  Mat3 world_axes(const std::vector<RigidBody>& bodies) const;
  // lever from the body's centre of mass to a world point (zero for the world)
  Vec3 lever(const std::vector<RigidBody>& bodies, const Vec3& world_point) const;
};

// an orthonormal frame whose z axis is the given direction
Mat3 frame_from_axis(const Vec3& axis);

// the forces of point contacts whose rows come in threes per point (normal along frame column 2,
// then friction along columns 0 and 1: vehicle/ground_contact, vehicle/plane_contact): the sum of
// the normal forces, and the whole force in the world [N]
double point_rows_normal_force(const std::vector<double>& forces);
// a contact's stiffness [N/m] must be positive and finite: its rows' compliance is its inverse,
// and an infinite compliance corrupts the machine's solve whether the rows are active or not;
// talus::Error naming `what` otherwise
void check_stiffness(double stiffness, const std::string& what);
Vec3 point_rows_force(const std::vector<double>& forces, const Mat3& frame);

// row helpers: the velocity of a world point p on frame b minus that on frame a, along direction n
ConstraintRow point_row(const std::vector<RigidBody>& bodies, const BodyFrame& a, const BodyFrame& b,
                        const Vec3& point_a, const Vec3& point_b, const Vec3& n);
// the relative angular velocity (ω_b - ω_a) along direction n
ConstraintRow angular_row(const BodyFrame& a, const BodyFrame& b, const Vec3& n);
// the row of g = u·w with u fixed in a and w fixed in b: ġ = (ω_b - ω_a)·(w × u)
ConstraintRow dot_row(const BodyFrame& a, const BodyFrame& b, const Vec3& u, const Vec3& w);

}  // namespace talus::vehicle
