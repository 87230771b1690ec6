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
  Eigen::SparseMatrix<double> lower;  // lower triangle of A, diagonal always stored
  std::vector<int> cached_outer, cached_inner;
  std::vector<RowState> factor_state;  // active set the factor belongs to
  // whether the factor is of the matrix set last (set_matrix makes it stale): within one solve the
  // friction passes change only the bounds, and a pass that starts on the active set the last one
  // ended on reuses its factor instead of factorising the same numbers again (measured on
  // load-carry: 3.35 factorisations per solve, one per friction pass, for 3.35 iterations)
  bool factor_current = false;
  int analyses = 0;

  Impl() {
    cholmod_start(&common);
    // small systems: simplicial LDLᵀ, no messages on stderr (status is checked here)
    common.supernodal = CHOLMOD_SIMPLICIAL;
    common.final_ll = 0;
    common.print = 0;
  }
  ~Impl() {
    if (factor) cholmod_free_factor(&factor, &common);
    if (matrix) cholmod_free_sparse(&matrix, &common);
    cholmod_finish(&common);
  }

  // lower triangle with an explicit diagonal; new symbolic analysis only if the pattern changed
  void set_matrix(const Eigen::SparseMatrix<double>& A) {
    factor_current = false;
    const int n = static_cast<int>(A.rows());
    std::vector<Eigen::Triplet<double>> t;
    t.reserve(A.nonZeros() / 2 + n);
    for (int j = 0; j < n; ++j) t.emplace_back(j, j, 0.0);
    for (int j = 0; j < A.outerSize(); ++j) {
      for (Eigen::SparseMatrix<double>::InnerIterator it(A, j); it; ++it) {
        if (it.row() >= it.col()) t.emplace_back(static_cast<int>(it.row()), static_cast<int>(it.col()), it.value());
      }
    }
    lower.resize(n, n);
    lower.setFromTriplets(t.begin(), t.end());
    lower.makeCompressed();
    const std::vector<int> outer(lower.outerIndexPtr(), lower.outerIndexPtr() + n + 1);
    const std::vector<int> inner(lower.innerIndexPtr(), lower.innerIndexPtr() + lower.nonZeros());
    if (matrix && factor && outer == cached_outer && inner == cached_inner) return;
    if (factor) cholmod_free_factor(&factor, &common);
    if (matrix) cholmod_free_sparse(&matrix, &common);
    matrix = cholmod_allocate_sparse(n, n, lower.nonZeros(), 1, 1, -1, CHOLMOD_REAL, &common);
    if (!matrix) throw Error("direct solver: CHOLMOD could not allocate a " + std::to_string(n) + "-row matrix");
    std::copy(outer.begin(), outer.end(), static_cast<int*>(matrix->p));
    std::copy(inner.begin(), inner.end(), static_cast<int*>(matrix->i));
    std::fill_n(static_cast<double*>(matrix->x), lower.nonZeros(), 1.0);
    for (int j = 0; j < n; ++j) static_cast<double*>(matrix->x)[outer[j]] = 1.0;
    factor = cholmod_analyze(matrix, &common);
    if (!factor) throw Error("direct solver: CHOLMOD analysis failed (status " + std::to_string(common.status) + ")");
    cached_outer = outer;
    cached_inner = inner;
    ++analyses;
  }

  // numeric factorisation of A with rows outside the free set replaced by identity
  void factorise(const std::vector<RowState>& state) {
    factor_current = false;  // until this factorisation succeeds
    const int n = static_cast<int>(lower.rows());
    double* x = static_cast<double*>(matrix->x);
    const double* v = lower.valuePtr();
    const int* outer = lower.outerIndexPtr();
    const int* inner = lower.innerIndexPtr();
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

  Eigen::MatrixXd solve(const Eigen::MatrixXd& rhs) {
    const int n = static_cast<int>(rhs.rows());
    const int k = static_cast<int>(rhs.cols());
    cholmod_dense* B = cholmod_allocate_dense(n, k, n, CHOLMOD_REAL, &common);
    std::copy(rhs.data(), rhs.data() + static_cast<std::ptrdiff_t>(n) * k, static_cast<double*>(B->x));
    cholmod_dense* X = cholmod_solve(CHOLMOD_A, factor, B, &common);
    if (!X) {
      cholmod_free_dense(&B, &common);
      throw Error("direct solver: CHOLMOD solve failed (status " + std::to_string(common.status) + ")");
    }
    Eigen::MatrixXd out = Eigen::Map<Eigen::MatrixXd>(static_cast<double*>(X->x), n, k);
    cholmod_free_dense(&X, &common);
    cholmod_free_dense(&B, &common);
    return out;
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
    // scale of A for the tolerance on the multipliers' signs
    double a_max = 0.0;
    for (int j = 0; j < p.A.outerSize(); ++j) {
      for (Eigen::SparseMatrix<double>::InnerIterator it(p.A, j); it; ++it) a_max = std::max(a_max, std::abs(it.value()));
    }
    converged = false;
    bool need_factor = !(factor_current && state == factor_state);
    int it = 0;
    for (; it < max_iterations; ++it) {
      if (need_factor) {
        factorise(state);
        ++factorisations;
        need_factor = false;
      }
      // free rows: A_FF x_F = b_F - A_FW λ_W; clamped rows keep their value
      Eigen::VectorXd clamped = Eigen::VectorXd::Zero(n);
      for (int i = 0; i < n; ++i) {
        if (state[i] != RowState::free) clamped[i] = lambda[i];
      }
      const Eigen::VectorXd coupling = p.A * clamped;
      Eigen::VectorXd rhs(n);
      for (int i = 0; i < n; ++i) rhs[i] = state[i] == RowState::free ? p.b[i] - coupling[i] : lambda[i];
      const Eigen::VectorXd x = solve(rhs);
      // ratio test: the largest step towards x that keeps every free row inside its bounds
      double alpha = 1.0;
      int blocking = -1;
      RowState blocking_side = RowState::free;
      for (int i = 0; i < n; ++i) {
        if (state[i] != RowState::free) continue;
        const double d = x[i] - lambda[i];
        if (x[i] < p.lo[i]) {
          const double a = d < 0.0 ? std::max(0.0, (p.lo[i] - lambda[i]) / d) : 0.0;
          if (blocking < 0 ? a <= alpha : a < alpha) {
            alpha = a;
            blocking = i;
            blocking_side = RowState::lower;
          }
        } else if (x[i] > p.hi[i]) {
          const double a = d > 0.0 ? std::max(0.0, (p.hi[i] - lambda[i]) / d) : 0.0;
          if (blocking < 0 ? a <= alpha : a < alpha) {
            alpha = a;
            blocking = i;
            blocking_side = RowState::upper;
          }
        }
      }
      for (int i = 0; i < n; ++i) {
        if (state[i] == RowState::free) lambda[i] += alpha * (x[i] - lambda[i]);
      }
      if (blocking >= 0) {
        // the blocking row joins the working set at its bound
        state[blocking] = blocking_side;
        lambda[blocking] = blocking_side == RowState::lower ? p.lo[blocking] : p.hi[blocking];
        need_factor = true;
        continue;
      }
      // full step: release the clamped row whose multiplier has the most wrong sign
      const Eigen::VectorXd w = p.A * lambda - p.b;
      const double wtol = 1e-13 * (p.b.cwiseAbs().maxCoeff() + a_max * lambda.cwiseAbs().maxCoeff());
      int release = -1;
      double worst = wtol;
      for (int i = 0; i < n; ++i) {
        if (state[i] == RowState::free || p.lo[i] == p.hi[i]) continue;
        const double wrong = state[i] == RowState::lower ? -w[i] : w[i];
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
