#include "vehicle/direct_solver.hpp"

#include <cholmod.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

#include "host/error.hpp"

namespace talus::vehicle {

// how many free sets keep their symbolic analysis: the active set of a digging machine moves
// among a few dozen (HD27-G400: 29 final sets in 200 steps), and each analysis is a few kB
constexpr std::size_t kKeptAnalyses = 32;

struct DirectSolver::Impl {
  // the symbolic analysis of one free set F: the lower triangle of A_FF with the clamped rows as
  // identity rows, so the factor's pattern holds only what the free rows couple. Factorising the
  // whole pattern with the clamped entries set to zero (the former way) did the work of every row:
  // on HD27-G400's 135 rows with 62 clamped, 117 kflop a factorisation for 13 (measured with
  // CHOLMOD's own count), 87 µs against 17 µs plus 25 µs for a new analysis.
  // Its CHOLMOD objects are freed by Impl (release): moved, never copied
  struct Analysis {
    Analysis() = default;
    Analysis(const Analysis&) = delete;
    Analysis& operator=(const Analysis&) = delete;
    Analysis(Analysis&&) = default;
    Analysis& operator=(Analysis&&) = default;
    std::vector<char> free;            // 1 where the row is free
    std::vector<int> source;           // per stored entry: its index in lower_value, -1: identity
    cholmod_sparse* matrix = nullptr;  // stype -1, values refilled per factorisation
    cholmod_factor* factor = nullptr;
    std::uint64_t factored_values = 0;  // the values generation its factor holds; 0: none
    std::uint64_t last_use = 0;
  };

  DirectSolverOptions options;
  cholmod_common common{};
  // lower triangle of A in compressed columns, the diagonal first in each column and always stored
  std::vector<int> lower_outer, lower_inner;
  std::vector<double> lower_value;
  std::vector<int> lower_from;                // per entry, its index in A's values (-1: zero)
  std::vector<int> input_outer, input_inner;  // A's pattern when the lower triangle was made
  // the analyses of the free sets met since A's pattern last changed, least recently used evicted
  std::vector<Analysis> kept;
  int current = -1;                    // the analysis whose factor the solves use
  std::vector<RowState> factor_state;  // active set the current factor belongs to
  // a generation per set of values: set_matrix starts a new one when the values differ from the
  // last matrix's (within one solve the friction passes change only the bounds, and the multibody
  // system's bound passes solve a step again with new bounds only), so an analysis whose factor was
  // made of the same values is used again without factorising (measured on load-carry: 3.35
  // factorisations per solve, one per friction pass, for 3.35 iterations; 0.90 once the repeated
  // matrices keep their factor)
  std::uint64_t values = 0;
  std::uint64_t uses = 0;
  int analyses = 0;
  double a_max = 0.0;  // largest |A_ij| of the matrix set last: the scale of the sign tolerance
  // buffers of one active-set iteration, kept between solves
  cholmod_dense* x_dense = nullptr;
  cholmod_dense* y_work = nullptr;
  cholmod_dense* e_work = nullptr;
  Eigen::MatrixXd rhs, solution;
  Eigen::VectorXd coupling;
  Eigen::VectorXd lo, hi;  // the bounds of one solve, moved by its friction passes
  std::vector<char> free_rows;

  Impl() {
    kept.reserve(kKeptAnalyses);  // so adding one never reallocates (nor throws with it unowned)
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
    forget_analyses();
    cholmod_finish(&common);
  }

  // frees one analysis's CHOLMOD objects (null pointers are skipped)
  void release(Analysis& a) {
    if (a.factor) cholmod_free_factor(&a.factor, &common);
    if (a.matrix) cholmod_free_sparse(&a.matrix, &common);
  }

  void forget_analyses() {
    for (Analysis& a : kept) release(a);
    kept.clear();
    current = -1;
  }

  // whether the current factor was made of the values set last
  bool factor_current() const { return current >= 0 && kept[current].factored_values == values; }

  // the lower triangle with an explicit diagonal, column by column; the kept analyses are dropped
  // if the pattern changed, and a new values generation starts unless the matrix is the last one
  // entry for entry
  void set_matrix(const Eigen::SparseMatrix<double>& A) {
    // an uncompressed A (one a caller inserted into) is read through a compressed copy
    if (!A.isCompressed()) {
      Eigen::SparseMatrix<double> compressed = A;
      compressed.makeCompressed();
      set_matrix(compressed);
      return;
    }
    // A's pattern as last given: each of its entries' place in lower_value is known, so only the
    // values are copied (the machine's pattern holds for hundreds of steps; rebuilding the lower
    // triangle entry by entry each solve was a tenth of a load-carry simulation)
    if (!same_input_pattern(A)) {
      // the analyses hold while the lower triangle's pattern does (A's upper entries may differ)
      const std::vector<int> old_outer = std::move(lower_outer), old_inner = std::move(lower_inner);
      set_pattern(A);
      if (lower_outer != old_outer || lower_inner != old_inner) forget_analyses();
      ++values;
    }
    const double* from = A.valuePtr();
    bool same_values = true;
    a_max = 0.0;
    for (std::size_t e = 0; e < lower_from.size(); ++e) {
      const double v = lower_from[e] >= 0 ? from[lower_from[e]] : 0.0;
      same_values = same_values && v == lower_value[e];
      lower_value[e] = v;
      a_max = std::max(a_max, std::abs(v));
    }
    if (!same_values) ++values;
  }

  // whether A's pattern (compressed) is the one set_pattern last read
  bool same_input_pattern(const Eigen::SparseMatrix<double>& A) const {
    if (A.rows() + 1 != static_cast<Eigen::Index>(input_outer.size())) return false;
    const int* outer = A.outerIndexPtr();
    return std::equal(input_outer.begin(), input_outer.end(), outer) &&
           std::equal(input_inner.begin(), input_inner.end(), A.innerIndexPtr(),
                      A.innerIndexPtr() + outer[A.rows()]);
  }

  // the lower triangle's pattern from A's (compressed): the diagonal first in each column and
  // always stored, then the rows below it in ascending order, and where each entry comes from in
  // A's values (-1: a diagonal A does not store, zero)
  void set_pattern(const Eigen::SparseMatrix<double>& A) {
    const int n = static_cast<int>(A.rows());
    const int* outer = A.outerIndexPtr();
    const int* inner = A.innerIndexPtr();
    lower_outer.assign(n + 1, 0);
    lower_inner.clear();
    lower_from.clear();
    for (int j = 0; j < n; ++j) {
      lower_inner.push_back(j);
      lower_from.push_back(-1);
      const std::size_t diagonal = lower_from.size() - 1;
      for (int k = outer[j]; k < outer[j + 1]; ++k) {
        if (inner[k] == j) {
          lower_from[diagonal] = k;
        } else if (inner[k] > j) {
          lower_inner.push_back(inner[k]);
          lower_from.push_back(k);
        }
      }
      lower_outer[j + 1] = static_cast<int>(lower_inner.size());
    }
    lower_value.assign(lower_from.size(), 0.0);
    input_outer.assign(outer, outer + n + 1);
    input_inner.assign(inner, inner + outer[n]);
  }

  // the kept analysis of this free set, or a new one (evicting the least recently used)
  Analysis& analysis_of(const std::vector<char>& free) {
    for (int k = 0; k < static_cast<int>(kept.size()); ++k) {
      if (kept[k].free == free) {
        current = k;
        kept[k].last_use = ++uses;
        return kept[k];
      }
    }
    // no current factor until the new one is made: an analysis that throws leaves none to misuse
    current = -1;
    if (kept.size() >= kKeptAnalyses) {
      const auto oldest = std::min_element(
          kept.begin(), kept.end(),
          [](const Analysis& a, const Analysis& b) { return a.last_use < b.last_use; });
      release(*oldest);
      kept.erase(oldest);
    }
    // the pattern of A_FF plus the clamped rows' diagonals, each entry's source in lower_value
    Analysis a;
    a.free = free;
    const int n = static_cast<int>(lower_outer.size()) - 1;
    std::vector<int> outer(n + 1, 0), inner;
    for (int j = 0; j < n; ++j) {
      for (int k = lower_outer[j]; k < lower_outer[j + 1]; ++k) {
        const int i = lower_inner[k];
        if (i == j) {
          inner.push_back(i);
          a.source.push_back(free[j] ? k : -1);
        } else if (free[i] && free[j]) {
          inner.push_back(i);
          a.source.push_back(k);
        }
      }
      outer[j + 1] = static_cast<int>(inner.size());
    }
    a.matrix = cholmod_allocate_sparse(n, n, inner.size(), 1, 1, -1, CHOLMOD_REAL, &common);
    if (!a.matrix)
      throw Error("direct solver: CHOLMOD could not allocate a " + std::to_string(n) +
                  "-row matrix");
    std::copy(outer.begin(), outer.end(), static_cast<int*>(a.matrix->p));
    std::copy(inner.begin(), inner.end(), static_cast<int*>(a.matrix->i));
    std::fill_n(static_cast<double*>(a.matrix->x), inner.size(), 1.0);
    a.factor = cholmod_analyze(a.matrix, &common);
    if (!a.factor) {
      cholmod_free_sparse(&a.matrix, &common);
      throw Error("direct solver: CHOLMOD analysis failed (status " +
                  std::to_string(common.status) + ")");
    }
    ++analyses;
    a.last_use = ++uses;
    kept.push_back(std::move(a));
    current = static_cast<int>(kept.size()) - 1;
    return kept.back();
  }

  // the factor of A with rows outside the free set replaced by identity: the free set's kept
  // analysis, factorised unless its factor already holds these values. Returns whether it
  // factorised
  bool factorise(const std::vector<RowState>& state) {
    const int n = static_cast<int>(state.size());
    free_rows.resize(n);
    for (int i = 0; i < n; ++i) free_rows[i] = state[i] == RowState::free;
    Analysis& a = analysis_of(free_rows);
    factor_state = state;
    if (a.factored_values == values) return false;
    a.factored_values = 0;  // until this factorisation succeeds
    double* x = static_cast<double*>(a.matrix->x);
    const double* v = lower_value.data();
    for (std::size_t e = 0; e < a.source.size(); ++e)
      x[e] = a.source[e] >= 0 ? v[a.source[e]] : 1.0;
    cholmod_factorize(a.matrix, a.factor, &common);
    if (common.status != CHOLMOD_OK) {
      throw Error("direct solver: CHOLMOD factorisation failed (status " +
                  std::to_string(common.status) + ", minor " + std::to_string(a.factor->minor) +
                  "): the constraint system is singular; give redundant rows a compliance");
    }
    a.factored_values = values;
    return true;
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
    if (!cholmod_solve2(CHOLMOD_A, kept[current].factor, &b, nullptr, &x_dense, nullptr, &y_work,
                        &e_work, &common)) {
      throw Error("direct solver: CHOLMOD solve failed (status " + std::to_string(common.status) + ")");
    }
    solution = Eigen::Map<const Eigen::MatrixXd>(static_cast<const double*>(x_dense->x), rhs.rows(),
                                                 rhs.cols());
    return solution;
  }

  // primal active set for fixed bounds lo, hi (p's matrix and right-hand side); lambda and state
  // are the warm start and the result
  int active_set(const BoundedMcp& p, const Eigen::VectorXd& lo, const Eigen::VectorXd& hi,
                 Eigen::VectorXd& lambda, std::vector<RowState>& state, int& factorisations,
                 bool& converged) {
    const int n = p.size();
    const int max_iterations = options.max_iterations > 0 ? options.max_iterations : 20 * n + 100;
    // a feasible start: clamped rows at their bound, free rows clipped into their range
    for (int i = 0; i < n; ++i) {
      if (lo[i] == hi[i]) state[i] = RowState::lower;
      if (state[i] == RowState::lower && !std::isfinite(lo[i])) state[i] = RowState::free;
      if (state[i] == RowState::upper && !std::isfinite(hi[i])) state[i] = RowState::free;
      if (state[i] == RowState::lower)
        lambda[i] = lo[i];
      else if (state[i] == RowState::upper)
        lambda[i] = hi[i];
      else
        lambda[i] = std::clamp(lambda[i], lo[i], hi[i]);
    }
    converged = false;
    rhs.resize(n, 1);
    // the factor depends on which rows are free, not on the bound a clamped row sits at
    bool need_factor = !factor_current() || factor_state.size() != state.size();
    for (int i = 0; i < n && !need_factor; ++i) {
      need_factor = (state[i] == RowState::free) != (factor_state[i] == RowState::free);
    }
    int it = 0;
    for (; it < max_iterations; ++it) {
      if (need_factor) {
        if (factorise(state)) ++factorisations;
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
        if (x(i, 0) < lo[i]) {
          const double a = d < 0.0 ? std::max(0.0, (lo[i] - lambda[i]) / d) : 0.0;
          if (blocking < 0 ? a <= alpha : a < alpha) {
            alpha = a;
            blocking = i;
            blocking_side = RowState::lower;
          }
        } else if (x(i, 0) > hi[i]) {
          const double a = d > 0.0 ? std::max(0.0, (hi[i] - lambda[i]) / d) : 0.0;
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
        lambda[blocking] = blocking_side == RowState::lower ? lo[blocking] : hi[blocking];
        need_factor = true;
        continue;
      }
      // full step: release the clamped row whose multiplier has the most wrong sign; w_i = (A λ)_i
      // - b_i of a clamped row is its column's dot product with λ (A is symmetric)
      const double wtol = 1e-13 * (p.b.cwiseAbs().maxCoeff() + a_max * lambda.cwiseAbs().maxCoeff());
      int release = -1;
      double worst = wtol;
      for (int i = 0; i < n; ++i) {
        if (state[i] == RowState::free || lo[i] == hi[i]) continue;
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
  Eigen::VectorXd& lo = impl_->lo;
  Eigen::VectorXd& hi = impl_->hi;
  lo = problem.lo;
  hi = problem.hi;
  const bool friction = problem.has_friction();
  if (friction) apply_friction_bounds(problem, r.lambda, lo, hi);
  const int passes = friction ? impl_->options.max_friction_passes : 1;
  for (int pass = 0; pass < passes; ++pass) {
    bool converged = false;
    r.iterations +=
        impl_->active_set(problem, lo, hi, r.lambda, r.state, r.factorisations, converged);
    r.friction_passes = pass + 1;
    r.converged = converged;
    if (!converged || !friction) break;
    const double change = apply_friction_bounds(problem, r.lambda, lo, hi);
    if (change <= impl_->options.friction_tolerance * friction_bound_scale(problem, hi)) break;
    r.converged = false;  // bounds moved: another pass must confirm
  }
  return r;
}

Eigen::MatrixXd DirectSolver::solve_free(const Eigen::MatrixXd& rhs) const {
  // a factorisation that threw leaves the factor half made (factor_current false): refuse it
  if (!impl_->factor_current() || rhs.rows() != static_cast<int>(impl_->factor_state.size())) {
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
