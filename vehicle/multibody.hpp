// The multibody system and its SPOOK stepper, solved directly (SPEC §2.1, §2.3).
// One step, in stages so that a later particle coupling can sit between them:
//   assemble(h)   rows of all constraints from the start-of-step state: G, Σ, right-hand sides
//   solve()       the bounded MCP  (G M⁻¹ Gᵀ + Σ) λ = rhs - G v*,  v* = v + h M⁻¹ f,  with the
//                 direct solver; v⁺ = v* + M⁻¹ Gᵀ λ (not yet committed); may be called again
//                 after set_external_wrench to re-solve with a new wrench, warm started
//   integrate()   commit v⁺, then positions q⁺ = q + h v⁺ (quaternions exactly)
// Coupling hooks:
//   set_external_wrench(body, wrench) adds a wrench [force at COM; torque] (world, N, N m) that
//   acts over the current step only (cleared by integrate());
//   mobility(body) is the 6x6 map from an impulse wrench on that body to the change of its twist
//   [v; ω] with all joints, motors and contacts of the last solve active: the Schur complement
//   M_b⁻¹ - M_b⁻¹ G_bᵀ A_FF⁻¹ G_b M_b⁻¹ from the direct solver's factor.
#pragma once
#include <memory>
#include <utility>
#include <vector>

#include "vehicle/direct_solver.hpp"
#include "vehicle/constraint.hpp"
#include "vehicle/rigid_body.hpp"

namespace talus::vehicle {

class MultibodySystem {
 public:
  MultibodySystem();
  int add_body(RigidBody body);
  template <class C>
  C& add_constraint(std::unique_ptr<C> c) {
    C& ref = *c;
    constraints_.push_back(std::move(c));
    return ref;
  }
  std::vector<RigidBody>& bodies() { return bodies_; }
  const std::vector<RigidBody>& bodies() const { return bodies_; }
  RigidBody& body(int i) { return bodies_.at(i); }
  const RigidBody& body(int i) const { return bodies_.at(i); }
  int body_index(const std::string& name) const;  // throws talus::Error if absent
  void set_gravity(const Vec3& g) { gravity_ = g; }
  const Vec3& gravity() const { return gravity_; }

  // coupling hook (a): an extra wrench on a body for the current step
  void set_external_wrench(int body, const Vec6& wrench);

  void assemble(double h);
  void solve();
  void integrate();
  void step(double h) {
    assemble(h);
    solve();
    integrate();
  }

  // coupling hook (b): the body's effective mobility [m/s per N s, rad/s per N m s] after solve()
  Mat6 mobility(int body) const;
  // the twist [v; ω] the last solve gives the body (before integrate commits it)
  Vec6 solved_twist(int body) const;

  double timestep() const { return h_; }
  double time() const { return time_; }
  int row_count() const { return static_cast<int>(rows_.size()); }
  const McpResult& last_result() const { return result_; }
  int bound_passes() const { return bound_passes_; }
  // the bounded MCP of the last assemble() (A and the bounds; b once solve() has run)
  const BoundedMcp& problem() const { return mcp_; }
  // the state between two steps, for a saved state (digging/saved_state): the bodies' poses and
  // velocities, the clock, the direct solver's warm start (impulses and active set) and every
  // constraint's own (Constraint::save_state), in the order they were added. restore_state reads
  // it into a system built the same way (InputError naming the reader's file when the bodies or
  // constraints differ in number); the system then steps on as the saved one would have
  void save_state(ByteWriter& w) const;
  void restore_state(ByteReader& r);
  // largest violation of bilateral joint rows at the start of the last step: length [m], angle [rad]
  double max_joint_position_violation() const;
  double max_joint_angle_violation() const;

 private:
  // G_ from this step's rows, minv_ from the bodies' masses and inverse_inertia_
  void assemble_jacobian();
  void assemble_inverse_mass();
  // mcp_.A = G M⁻¹ Gᵀ + Σ from this step's rows, Σ and the bodies' inverse masses
  void assemble_schur_complement();
  // mcp_.A's pattern and the entries each pair of blocks adds to, from on_body_ and row_bodies_
  void build_schur_pattern();

  // one Jacobian block on a moving body: its row, J_b and M_b⁻¹ J_bᵀ
  struct BodyBlock {
    int row;
    Vec6 jacobian, mobility;
  };
  // one non-zero entry of a row of G: its velocity column and value
  struct JacobianEntry {
    int column;
    double value;
  };
  // where one pair of blocks on a body adds J_p M_b⁻¹ J_qᵀ in mcp_.A's values: its entry in the
  // lower triangle and the mirrored upper one (the same on the diagonal)
  struct SchurTerm {
    int lower, upper;
  };

  std::vector<RigidBody> bodies_;
  std::vector<std::unique_ptr<Constraint>> constraints_;
  Vec3 gravity_ = Vec3(0.0, 0.0, -9.81);
  std::vector<Vec6> external_;  // per body, this step
  DirectSolver solver_;
  double h_ = 0.0, time_ = 0.0;
  // this step's assembly
  std::vector<ConstraintRow> rows_;
  std::vector<int> constraint_offset_;  // first row of each constraint
  std::vector<int> column_;             // first velocity column of each body, -1 if fixed
  int columns_ = 0;
  Eigen::SparseMatrix<double> G_;
  std::vector<JacobianEntry> jacobian_entries_;  // G's rows' entries, row after row (scratch)
  std::vector<int> jacobian_row_start_;          // per row, its first entry (scratch)
  std::vector<int> jacobian_fill_;               // per column, its next free place (scratch)
  Eigen::SparseMatrix<double> minv_;
  std::vector<Mat3> inverse_inertia_;  // per body, world frame, this step (unset for fixed bodies)
  Eigen::VectorXd sigma_, rhs_;
  std::vector<std::vector<BodyBlock>> on_body_;  // per body, this step's blocks (scratch)
  std::vector<int> row_bodies_;          // each row's moving bodies, row ends kWorld (this step)
  std::vector<int> pattern_row_bodies_;  // row_bodies_ of the step mcp_.A's pattern was built for
  std::vector<SchurTerm> schur_terms_;   // per pair of blocks on a body, in on_body_ order
  std::vector<int> schur_diagonal_;      // per row, its diagonal entry in mcp_.A's values
  BoundedMcp mcp_;
  // the impulse bounds as assembled: solve() starts from them, so bounds that a previous solve
  // of the same step lowered (the engine's speed-dependent torque limit) do not stick when the
  // step is solved again with another external wrench (the particle coupling's outer passes)
  std::vector<std::pair<double, double>> assembled_force_range_;  // per row [N or N m]
  McpResult result_;
  Eigen::VectorXd velocity_after_;  // v⁺ of the last solve
  Eigen::VectorXd warm_lambda_;
  std::vector<RowState> warm_state_;
  int bound_passes_ = 0;
  bool assembled_ = false, solved_ = false;
};

}  // namespace talus::vehicle
