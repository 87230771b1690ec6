// The bounded mixed complementarity problem (MCP) that one SPOOK step of the vehicle poses, in
// Schur-complement form (SPEC §2.3):
//   w = A λ - b,   lo <= λ <= hi,
//   lo < λ_i < hi  =>  w_i = 0,   λ_i = lo_i  =>  w_i >= 0,   λ_i = hi_i  =>  w_i <= 0.
// A = G M⁻¹ Gᵀ + Σ is symmetric positive definite, so this is the optimality system of the convex
// box-constrained QP  min ½ λᵀ A λ - bᵀ λ  over lo <= λ <= hi, and its solution is unique.
// Box-linearised friction: a row with normal[i] = k >= 0 has bounds ±mu_i max(λ_k, 0), which the
// solvers settle by a short fixed-point loop over the normal impulses.
#pragma once
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <vector>

namespace talus::vehicle {

struct BoundedMcp {
  Eigen::SparseMatrix<double> A;  // n x n, symmetric, both triangles stored
  Eigen::VectorXd b;
  Eigen::VectorXd lo;             // -inf allowed
  Eigen::VectorXd hi;             // +inf allowed
  std::vector<int> normal;        // empty, or per row: index of the normal row scaling its bounds, or -1
  Eigen::VectorXd mu;             // friction coefficient per row (used where normal[i] >= 0)
  int size() const { return static_cast<int>(b.size()); }
  bool has_friction() const;
};

// where a row sits in the active set
enum class RowState : signed char { free = 0, lower = 1, upper = 2 };

struct McpResult {
  Eigen::VectorXd lambda;
  std::vector<RowState> state;
  int iterations = 0;       // active-set (or pivoting) iterations, all friction passes together
  int factorisations = 0;   // numeric factorisations
  int friction_passes = 0;  // fixed-point passes over the friction bounds (1 without friction)
  bool converged = false;
};

// throws talus::Error when sizes disagree, a bound is NaN, lo > hi, or A is not square
void check_mcp(const BoundedMcp& p);

// fixed-point passes over the friction bounds, for every solver of the MCP. Each updates the bounds
// from the last normal impulses (a Picard iteration): where the friction rows push back on their
// own normals it converges linearly; a step of a G400 soak (bench/soak.py, 135 rows, at 153 s)
// closed 6 % a pass and needed about 270, where the former cap of 50 stopped the run. A pass on an
// unchanged active set costs one solve with the kept factor (vehicle/direct_solver), so the cap is
// generous
inline constexpr int kMaxFrictionPasses = 1000;

// set the bounds lo, hi of p's friction rows from the normal impulses in lambda (the other rows'
// untouched); returns the largest change. The solvers keep the bounds apart from the problem, so a
// friction pass does not copy its matrix
double apply_friction_bounds(const BoundedMcp& p, const Eigen::VectorXd& lambda,
                             Eigen::VectorXd& lo, Eigen::VectorXd& hi);
// the same on the problem's own bounds
inline double apply_friction_bounds(BoundedMcp& p, const Eigen::VectorXd& lambda) {
  return apply_friction_bounds(p, lambda, p.lo, p.hi);
}

// 1 + the largest friction bound in hi: the scale for the friction fixed-point tolerance
double friction_bound_scale(const BoundedMcp& p, const Eigen::VectorXd& hi);

// natural-map residual |λ - clamp(λ - w, lo, hi)|∞ with w = Aλ - b: zero exactly at a solution
// (friction rows use the bounds that the normal impulses in lambda give)
double mcp_residual(const BoundedMcp& p, const Eigen::VectorXd& lambda);

}  // namespace talus::vehicle
