#include "vehicle/dense_reference.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

namespace talus::vehicle {

namespace {

// one bounded MCP with fixed bounds by block principal pivoting; state is warm start and result
int solve_fixed_bounds(const Eigen::MatrixXd& A, const BoundedMcp& p, int max_iterations,
                       Eigen::VectorXd& lambda, std::vector<RowState>& state, bool& converged) {
  const int n = p.size();
  int best_infeasible = n + 1;
  int full_exchanges_left = 3;  // Júdice–Pires: full block exchanges allowed without progress
  converged = false;
  // rows with lo = hi never move
  for (int i = 0; i < n; ++i) {
    if (p.lo[i] == p.hi[i]) state[i] = RowState::lower;
    if (state[i] == RowState::lower && !std::isfinite(p.lo[i])) state[i] = RowState::free;
    if (state[i] == RowState::upper && !std::isfinite(p.hi[i])) state[i] = RowState::free;
  }
  int it = 0;
  for (; it < max_iterations; ++it) {
    // clamped rows at their bounds, free rows from the free block: A_FF λ_F = b_F - A_FW λ_W
    std::vector<int> freeset;
    for (int i = 0; i < n; ++i) {
      if (state[i] == RowState::lower) lambda[i] = p.lo[i];
      else if (state[i] == RowState::upper) lambda[i] = p.hi[i];
      else freeset.push_back(i);
    }
    const int nf = static_cast<int>(freeset.size());
    if (nf > 0) {
      Eigen::MatrixXd Aff(nf, nf);
      Eigen::VectorXd rhs(nf);
      for (int a = 0; a < nf; ++a) {
        rhs[a] = p.b[freeset[a]];
        for (int j = 0; j < n; ++j) {
          if (state[j] != RowState::free) rhs[a] -= A(freeset[a], j) * lambda[j];
        }
        for (int c = 0; c < nf; ++c) Aff(a, c) = A(freeset[a], freeset[c]);
      }
      const Eigen::VectorXd x = Aff.ldlt().solve(rhs);
      for (int a = 0; a < nf; ++a) lambda[freeset[a]] = x[a];
    }
    // infeasibilities: free rows out of bounds, clamped rows whose w has the wrong sign
    const Eigen::VectorXd w = A * lambda - p.b;
    const double wtol = 1e-13 * (p.b.cwiseAbs().maxCoeff() + A.cwiseAbs().maxCoeff() * lambda.cwiseAbs().maxCoeff());
    std::vector<int> bad;
    for (int i = 0; i < n; ++i) {
      const double span = 1e-13 * (1.0 + std::abs(lambda[i]));
      if (state[i] == RowState::free) {
        if (lambda[i] < p.lo[i] - span || lambda[i] > p.hi[i] + span) bad.push_back(i);
      } else if (p.lo[i] != p.hi[i]) {
        if ((state[i] == RowState::lower && w[i] < -wtol) || (state[i] == RowState::upper && w[i] > wtol)) {
          bad.push_back(i);
        }
      }
    }
    if (bad.empty()) {
      converged = true;
      // clip roundoff on free rows
      for (int i = 0; i < n; ++i) lambda[i] = std::clamp(lambda[i], p.lo[i], p.hi[i]);
      return it + 1;
    }
    // exchange: all infeasible rows while their number falls, else Murty's largest-index rule
    const int count = static_cast<int>(bad.size());
    if (count < best_infeasible) {
      best_infeasible = count;
      full_exchanges_left = 3;
    } else if (full_exchanges_left > 0) {
      --full_exchanges_left;
    } else {
      bad = {bad.back()};
    }
    for (int i : bad) {
      if (state[i] == RowState::free) {
        state[i] = lambda[i] < p.lo[i] ? RowState::lower : RowState::upper;
      } else {
        state[i] = RowState::free;
      }
    }
  }
  return it;
}

}  // namespace

McpResult solve_dense_reference(const BoundedMcp& problem, const DenseReferenceOptions& options) {
  check_mcp(problem);
  BoundedMcp p = problem;
  const int n = p.size();
  const Eigen::MatrixXd A = Eigen::MatrixXd(p.A);
  const int max_iterations = options.max_iterations > 0 ? options.max_iterations : 50 * n + 100;
  McpResult r;
  r.lambda = Eigen::VectorXd::Zero(n);
  r.state.assign(n, RowState::free);
  // friction rows start with zero bounds, then follow the normal impulses to a fixed point
  if (p.has_friction()) apply_friction_bounds(p, r.lambda);
  const int passes = p.has_friction() ? options.max_friction_passes : 1;
  for (int pass = 0; pass < passes; ++pass) {
    bool converged = false;
    r.iterations += solve_fixed_bounds(A, p, max_iterations, r.lambda, r.state, converged);
    r.friction_passes = pass + 1;
    r.converged = converged;
    if (!converged || !p.has_friction()) break;
    const double change = apply_friction_bounds(p, r.lambda);
    if (change <= options.friction_tolerance * friction_bound_scale(p, p.hi)) break;
    r.converged = false;  // bounds moved: another pass must confirm
  }
  r.factorisations = r.iterations;
  return r;
}

}  // namespace talus::vehicle
