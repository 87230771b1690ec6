#include "vehicle/direct_solver.hpp"

#include <cholmod.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "host/error.hpp"

namespace talus::vehicle {

struct DirectSolver::Impl {
  DirectSolverOptions options;
  cholmod_common common{};
  cholmod_sparse* matrix = nullptr;  // lower triangle (stype -1) of A with W rows as identity
  cholmod_factor* factor = nullptr;
  // lower triangle of A in compressed columns, the diagonal first in each column and always stored
  std::vector<int> lower_outer, lower_inner;
  std::vector<double> lower_value;
  std::vector<int> next_outer, next_inner;  // set_matrix's scratch, kept to reuse its memory
  std::vector<double> next_value;
  std::vector<RowState> factor_state;  // active set the factor belongs to
  // whether the factor is of the matrix set last (set_matrix makes it stale unless the matrix is
  // the same): within one solve the friction passes change only the bounds, and a pass that starts
  // on the active set the last one ended on reuses its factor instead of factorising the same
  // numbers again (measured on load-carry: 3.35 factorisations per solve, one per friction pass,
  // for 3.35 iterations; 0.90 once the bound passes' repeated matrices keep it too)
  bool factor_current = false;
  int analyses = 0;
  double a_max = 0.0;  // largest |A_ij| of the matrix set last: the scale of the sign tolerance
  // buffers of one active-set iteration, kept between solves
  cholmod_dense* x_dense = nullptr;
  cholmod_dense* y_work = nullptr;
  cholmod_dense* e_work = nullptr;
  Eigen::MatrixXd rhs, solution;
  Eigen::VectorXd coupling;

  Impl() {
    cholmod_start(&common);
    // small systems: simplicial LDLᵀ, no messages on stderr (status is checked here)
    common.supernodal = CHOLMOD_SIMPLICIAL;
    common.final_ll = 0;
    common.print = 0;
  }
  ~Impl() {
    for (cholmod_dense** d : {&x_dense, &y_work, &e_work}) {
      if (*d) cholmod_free_dense(d, &common);
    }
    if (factor) cholmod_free_factor(&factor, &common);
    if (matrix) cholmod_free_sparse(&matrix, &common);
    cholmod_finish(&common);
  }

  // the lower triangle with an explicit diagonal, column by column; a new symbolic analysis only if
  // the pattern changed, and the factor kept if the matrix is the last one entry for entry (the
  // multibody system's bound passes solve a step again with new bounds only)
  void set_matrix(const Eigen::SparseMatrix<double>& A) {
    const int n = static_cast<int>(A.rows());
    next_outer.assign(n + 1, 0);
    next_inner.clear();
    next_value.clear();
    for (int j = 0; j < n; ++j) {
      // the diagonal first, then the rows below it in Eigen's ascending order
      next_inner.push_back(j);
      next_value.push_back(0.0);
      const std::size_t diagonal = next_value.size() - 1;
      for (Eigen::SparseMatrix<double>::InnerIterator it(A, j); it; ++it) {
        if (it.row() == j) {
          next_value[diagonal] += it.value();
        } else if (it.row() > j) {
          next_inner.push_back(static_cast<int>(it.row()));
          next_value.push_back(it.value());
        }
      }
      next_outer[j + 1] = static_cast<int>(next_inner.size());
    }
    const bool same_pattern =
        matrix && factor && next_outer == lower_outer && next_inner == lower_inner;
    if (!(same_pattern && next_value == lower_value)) factor_current = false;
    std::swap(lower_outer, next_outer);
    std::swap(lower_inner, next_inner);
    std::swap(lower_value, next_value);
    a_max = 0.0;
    for (const double v : lower_value) a_max = std::max(a_max, std::abs(v));
    if (same_pattern) return;
    if (factor) cholmod_free_factor(&factor, &common);
    if (matrix) cholmod_free_sparse(&matrix, &common);
    const auto nonzeros = lower_value.size();
    matrix = cholmod_allocate_sparse(n, n, nonzeros, 1, 1, -1, CHOLMOD_REAL, &common);
    if (!matrix) throw Error("direct solver: CHOLMOD could not allocate a " + std::to_string(n) + "-row matrix");
    std::copy(lower_outer.begin(), lower_outer.end(), static_cast<int*>(matrix->p));
    std::copy(lower_inner.begin(), lower_inner.end(), static_cast<int*>(matrix->i));
    std::fill_n(static_cast<double*>(matrix->x), nonzeros, 1.0);
    factor = cholmod_analyze(matrix, &common);
    if (!factor)
      throw Error("direct solver: CHOLMOD analysis failed (status " +
                  std::to_string(common.status) + ")");
    ++analyses;
  }

  // numeric factorisation of A with rows outside the free set replaced by identity
  void factorise(const std::vector<RowState>& state) {
    factor_current = false;  // until this factorisation succeeds
    const int n = static_cast<int>(lower_outer.size()) - 1;
    double* x = static_cast<double*>(matrix->x);
    const double* v = lower_value.data();
    const int* outer = lower_outer.data();
    const int* inner = lower_inner.data();
    for (int j = 0; j < n; ++j) {
      for (int k = outer[j]; k < outer[j + 1]; ++k) {
        const int i = inner[k];
        const bool both_free = state[i] == RowState::free && state[j] == RowState::free;
        x[k] = both_free ? v[k] : (i == j ? 1.0 : 0.0);
      }
    }
    cholmod_factorize(matrix, factor, &common);
    if (common.status != CHOLMOD_OK) {
      throw Error("direct solver: CHOLMOD factorisation failed (status " + std::to_string(common.status) +
                  ", minor " + std::to_string(factor->minor) +
                  "): the constraint system is singular; give redundant rows a compliance");
    }
    factor_state = state;
    factor_current = true;
  }

  // x = A⁻¹ rhs with the current factor. CHOLMOD's solve2 keeps its dense results and workspaces
  // (x_dense, y_work, e_work) between calls, so the friction passes' solves allocate nothing; rhs
  // is lent to CHOLMOD as a column-major view, read only
  const Eigen::MatrixXd& solve(const Eigen::MatrixXd& rhs) {
    cholmod_dense b{};
    b.nrow = static_cast<size_t>(rhs.rows());
    b.ncol = static_cast<size_t>(rhs.cols());
    b.nzmax = b.nrow * b.ncol;
    b.d = b.nrow;
    b.x = const_cast<double*>(rhs.data());
    b.xtype = CHOLMOD_REAL;
    b.dtype = CHOLMOD_DOUBLE;
    if (!cholmod_solve2(CHOLMOD_A, factor, &b, nullptr, &x_dense, nullptr, &y_work, &e_work,
                        &common)) {
      throw Error("direct solver: CHOLMOD solve failed (status " + std::to_string(common.status) + ")");
    }
    solution = Eigen::Map<const Eigen::MatrixXd>(static_cast<const double*>(x_dense->x), rhs.rows(),
                                                 rhs.cols());
    return solution;
  }

  // primal active set for fixed bounds; lambda and state are the warm start and the result
  int active_set(const BoundedMcp& p, Eigen::VectorXd& lambda, std::vector<RowState>& state, int& factorisations,
                 bool& converged) {
    const int n = p.size();
    const int max_iterations = options.max_iterations > 0 ? options.max_iterations : 20 * n + 100;
    // a feasible start: clamped rows at their bound, free rows clipped into their range
    for (int i = 0; i < n; ++i) {
      if (p.lo[i] == p.hi[i]) state[i] = RowState::lower;
      if (state[i] == RowState::lower && !std::isfinite(p.lo[i])) state[i] = RowState::free;
      if (state[i] == RowState::upper && !std::isfinite(p.hi[i])) state[i] = RowState::free;
      if (state[i] == RowState::lower) lambda[i] = p.lo[i];
      else if (state[i] == RowState::upper) lambda[i] = p.hi[i];
      else lambda[i] = std::clamp(lambda[i], p.lo[i], p.hi[i]);
    }
    converged = false;
    rhs.resize(n, 1);
    // the factor depends on which rows are free, not on the bound a clamped row sits at
    bool need_factor = !factor_current || factor_state.size() != state.size();
    for (int i = 0; i < n && !need_factor; ++i) {
      need_factor = (state[i] == RowState::free) != (factor_state[i] == RowState::free);
    }
    int it = 0;
    for (; it < max_iterations; ++it) {
      if (need_factor) {
        factorise(state);
        ++factorisations;
        need_factor = false;
      }
      // free rows: A_FF x_F = b_F - A_FW λ_W; clamped rows keep their value. A_FW λ_W sums the
      // clamped columns alone (most rows are free joint rows), in the order A * λ_W would
      coupling.setZero(n);
      for (int j = 0; j < n; ++j) {
        if (state[j] == RowState::free) continue;
        for (Eigen::SparseMatrix<double>::InnerIterator it(p.A, j); it; ++it)
          coupling[it.row()] += it.value() * lambda[j];
      }
      for (int i = 0; i < n; ++i)
        rhs(i, 0) = state[i] == RowState::free ? p.b[i] - coupling[i] : lambda[i];
      const Eigen::MatrixXd& x = solve(rhs);
      // ratio test: the largest step towards x that keeps every free row inside its bounds
      double alpha = 1.0;
      int blocking = -1;
      RowState blocking_side = RowState::free;
      for (int i = 0; i < n; ++i) {
        if (state[i] != RowState::free) continue;
        const double d = x(i, 0) - lambda[i];
        if (x(i, 0) < p.lo[i]) {
          const double a = d < 0.0 ? std::max(0.0, (p.lo[i] - lambda[i]) / d) : 0.0;
          if (blocking < 0 ? a <= alpha : a < alpha) {
            alpha = a;
            blocking = i;
            blocking_side = RowState::lower;
          }
        } else if (x(i, 0) > p.hi[i]) {
          const double a = d > 0.0 ? std::max(0.0, (p.hi[i] - lambda[i]) / d) : 0.0;
          if (blocking < 0 ? a <= alpha : a < alpha) {
            alpha = a;
            blocking = i;
            blocking_side = RowState::upper;
          }
        }
      }
      for (int i = 0; i < n; ++i) {
        if (state[i] == RowState::free) lambda[i] += alpha * (x(i, 0) - lambda[i]);
      }
      if (blocking >= 0) {
        // the blocking row joins the working set at its bound
        state[blocking] = blocking_side;
        lambda[blocking] = blocking_side == RowState::lower ? p.lo[blocking] : p.hi[blocking];
        need_factor = true;
        continue;
      }
      // full step: release the clamped row whose multiplier has the most wrong sign; w_i = (A λ)_i
      // - b_i of a clamped row is its column's dot product with λ (A is symmetric)
      const double wtol = 1e-13 * (p.b.cwiseAbs().maxCoeff() + a_max * lambda.cwiseAbs().maxCoeff());
      int release = -1;
      double worst = wtol;
      for (int i = 0; i < n; ++i) {
        if (state[i] == RowState::free || p.lo[i] == p.hi[i]) continue;
        double w = -p.b[i];
        for (Eigen::SparseMatrix<double>::InnerIterator it(p.A, i); it; ++it)
          w += it.value() * lambda[it.index()];
        const double wrong = state[i] == RowState::lower ? -w : w;
        if (wrong > worst) {
          worst = wrong;
          release = i;
        }
      }
      if (release < 0) {
        converged = true;
        return it + 1;
      }
      state[release] = RowState::free;
      need_factor = true;
    }
    return it;
  }
};

DirectSolver::DirectSolver(DirectSolverOptions options) : impl_(std::make_unique<Impl>()) {
  impl_->options = options;
}
DirectSolver::~DirectSolver() = default;
DirectSolver::DirectSolver(DirectSolver&&) noexcept = default;
DirectSolver& DirectSolver::operator=(DirectSolver&&) noexcept = default;

int DirectSolver::analyses() const { return impl_->analyses; }

McpResult DirectSolver::solve(const BoundedMcp& problem, const Eigen::VectorXd* warm_lambda,
                              const std::vector<RowState>* warm_state) {
  check_mcp(problem);
  const int n = problem.size();
  McpResult r;
  r.lambda = warm_lambda && warm_lambda->size() == n ? *warm_lambda : Eigen::VectorXd::Zero(n);
  r.state.assign(n, RowState::free);
  if (warm_state && static_cast<int>(warm_state->size()) == n) {
    for (int i = 0; i < n; ++i) r.state[i] = (*warm_state)[i];
  }
  if (n == 0) {
    r.converged = true;
    return r;
  }
  impl_->set_matrix(problem.A);
  // friction bounds follow the normal impulses to a fixed point, warm from the given impulses
  BoundedMcp p = problem;
  const bool friction = p.has_friction();
  if (friction) apply_friction_bounds(p, r.lambda);
  const int passes = friction ? impl_->options.max_friction_passes : 1;
  for (int pass = 0; pass < passes; ++pass) {
    bool converged = false;
    r.iterations += impl_->active_set(p, r.lambda, r.state, r.factorisations, converged);
    r.friction_passes = pass + 1;
    r.converged = converged;
    if (!converged || !friction) break;
    const double change = apply_friction_bounds(p, r.lambda);
    if (change <= impl_->options.friction_tolerance * friction_bound_scale(p)) break;
    r.converged = false;  // bounds moved: another pass must confirm
  }
  return r;
}

Eigen::MatrixXd DirectSolver::solve_free(const Eigen::MatrixXd& rhs) const {
  // a factorisation that threw leaves the factor half made (factor_current false): refuse it
  if (!impl_->factor || !impl_->factor_current ||
      rhs.rows() != static_cast<int>(impl_->factor_state.size())) {
    throw Error("direct solver: solve_free needs a previous successful solve of the same size");
  }
  Eigen::MatrixXd r = rhs;
  for (int i = 0; i < r.rows(); ++i) {
    if (impl_->factor_state[i] != RowState::free) r.row(i).setZero();
  }
  Eigen::MatrixXd x = impl_->solve(r);
  for (int i = 0; i < x.rows(); ++i) {
    if (impl_->factor_state[i] != RowState::free) x.row(i).setZero();
  }
  return x;
}

}  // namespace talus::vehicle
