// Direct solver for the vehicle's bounded MCP (SPEC §2.3): the Schur complement A = G M⁻¹ Gᵀ + Σ
// is factorised with CHOLMOD (simplicial LDLᵀ), and bounded rows (motor force ranges, range limits,
// contact normals, box-linearised friction) are settled by a primal active-set method:
//   - rows in the working set W sit at a bound; in the matrix they are replaced by identity rows
//     and columns, and the factor holds only A_FF's pattern (the free rows' couplings): each free
//     set has its own symbolic analysis, kept for the free sets met since A's pattern last changed
//     (the least recently used dropped beyond a few dozen), so a machine whose contacts come and go
//     factorises a seventh of the full pattern's work without analysing every step;
//   - each iteration solves for the free rows, steps towards that solution until the first free
//     row meets a bound (which joins W), or, at the full step, releases the clamped row whose
//     multiplier w = Aλ - b has the most wrong sign; no wrong sign left means optimal;
//   - every active-set change is one numeric factorisation (none when the free set's kept factor
//     was made of the same values).
// Warm starting from the previous step's impulses and active set makes most steps take one or two
// factorisations. The factor of the final active set stays available for mobility queries
// (solve_free), which is how the bucket's effective mobility is derived.
#pragma once
#include <memory>

#include "vehicle/mcp.hpp"

namespace talus::vehicle {

struct DirectSolverOptions {
  int max_iterations = 0;             // active-set iterations per friction pass; 0: 20 n + 100
  int max_friction_passes = kMaxFrictionPasses;  // fixed-point passes over friction bounds
  double friction_tolerance = 1e-12;  // relative change of friction bounds that ends the passes
};

class DirectSolver {
 public:
  explicit DirectSolver(DirectSolverOptions options = {});
  ~DirectSolver();
  DirectSolver(const DirectSolver&) = delete;
  DirectSolver& operator=(const DirectSolver&) = delete;
  DirectSolver(DirectSolver&&) noexcept;
  DirectSolver& operator=(DirectSolver&&) noexcept;

  // solve; warm_lambda and warm_state (either may be null or of the wrong size: then cold start)
  // throws talus::Error when A is not positive definite on the free rows
  McpResult solve(const BoundedMcp& problem, const Eigen::VectorXd* warm_lambda = nullptr,
                  const std::vector<RowState>* warm_state = nullptr);

  // with the factor of the last solve's final active set: X_F = A_FF⁻¹ R_F, X_W = 0
  // (clamped rows do not respond: the linearisation of the MCP around its solution)
  Eigen::MatrixXd solve_free(const Eigen::MatrixXd& rhs) const;

  // symbolic analyses done so far (a new one for a free set not kept, and all anew when A's
  // pattern changes)
  int analyses() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace talus::vehicle
