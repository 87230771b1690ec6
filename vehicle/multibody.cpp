#include "vehicle/multibody.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <tuple>

#include "host/error.hpp"
#include "vehicle/spook.hpp"

namespace talus::vehicle {

namespace {
// passes over speed-dependent bounds (engine power limit) per solve; each pass is a warm re-solve
constexpr int kMaxBoundPasses = 6;
}  // namespace

MultibodySystem::MultibodySystem() = default;

int MultibodySystem::add_body(RigidBody body) {
  if (!(body.mass > 0.0) && !body.fixed) throw Error("body '" + body.name + "': mass must be > 0");
  bodies_.push_back(std::move(body));
  external_.push_back(Vec6::Zero());
  return static_cast<int>(bodies_.size()) - 1;
}

int MultibodySystem::body_index(const std::string& name) const {
  for (int i = 0; i < static_cast<int>(bodies_.size()); ++i) {
    if (bodies_[i].name == name) return i;
  }
  throw Error("multibody system: no body named '" + name + "'");
}

void MultibodySystem::set_external_wrench(int body, const Vec6& wrench) {
  external_.at(body) = wrench;
  solved_ = false;
}

void MultibodySystem::assemble(double h) {
  if (!(h > 0.0)) throw Error("multibody step: timestep must be > 0");
  h_ = h;
  // velocity columns: six per moving body
  column_.assign(bodies_.size(), -1);
  columns_ = 0;
  for (size_t i = 0; i < bodies_.size(); ++i) {
    if (!bodies_[i].fixed) {
      column_[i] = columns_;
      columns_ += 6;
    }
  }
  // rows of every constraint, in order
  rows_.clear();
  constraint_offset_.clear();
  for (auto& c : constraints_) {
    constraint_offset_.push_back(static_cast<int>(rows_.size()));
    c->add_rows(bodies_, rows_);
  }
  const int m = static_cast<int>(rows_.size());
  // Jacobian G and block-diagonal M⁻¹ in compressed columns
  assemble_jacobian();
  inverse_inertia_.resize(bodies_.size());
  for (size_t i = 0; i < bodies_.size(); ++i) {
    if (column_[i] >= 0) inverse_inertia_[i] = bodies_[i].inverse_inertia_world();
  }
  assemble_inverse_mass();
  // SPOOK: Σ per row and the constraint right-hand side
  Eigen::VectorXd v(columns_);
  for (size_t i = 0; i < bodies_.size(); ++i) {
    if (column_[i] >= 0) v.segment<6>(column_[i]) = bodies_[i].twist();
  }
  const Eigen::VectorXd gv = G_ * v;
  sigma_.resize(m);
  rhs_.resize(m);
  mcp_.lo.resize(m);
  mcp_.hi.resize(m);
  mcp_.normal.assign(m, -1);
  mcp_.mu = Eigen::VectorXd::Zero(m);
  for (size_t c = 0; c < constraints_.size(); ++c) {
    const int end = c + 1 < constraints_.size() ? constraint_offset_[c + 1] : m;
    for (int r = constraint_offset_[c]; r < end; ++r) {
      const ConstraintRow& row = rows_[r];
      if (row.kind == RowKind::holonomic) {
        const auto k = spook::holonomic_row(h, row.compliance, row.damping_time);
        sigma_[r] = k.sigma;
        rhs_[r] = spook::holonomic_rhs(h, k, row.violation, gv[r]);
      } else {
        sigma_[r] = spook::velocity_row_sigma(h, row.compliance);
        rhs_[r] = row.target_speed;
      }
      mcp_.lo[r] = h * row.force_min;
      mcp_.hi[r] = h * row.force_max;
      if (row.friction_normal >= 0) {
        mcp_.normal[r] = constraint_offset_[c] + row.friction_normal;
        mcp_.mu[r] = row.friction_coefficient;
      }
    }
  }
  assemble_schur_complement();
  assembled_force_range_.resize(m);
  for (int r = 0; r < m; ++r) assembled_force_range_[r] = {rows_[r].force_min, rows_[r].force_max};
  if (warm_lambda_.size() != m) {
    warm_lambda_ = Eigen::VectorXd::Zero(m);
    warm_state_.assign(m, RowState::free);
  }
  assembled_ = true;
  solved_ = false;
}

void MultibodySystem::assemble_jacobian() {
  // the entries setFromTriplets made of one triplet per non-zero block entry, written straight
  // into compressed columns (the triplets and their transposed copy were a tenth of a load-carry
  // simulation): two blocks of one row on one body sum into one entry in block order, zeros are
  // not stored, and each column's rows ascend. The same matrix, so the products keep their bits
  const int m = static_cast<int>(rows_.size());
  // each row's entries (column, value), its blocks merged, rows one after another; written by
  // index into room for every block entry (a push_back of the pair stalled on its store)
  std::size_t room = 0;
  for (const auto& row : rows_) room += 6 * row.blocks.size();
  jacobian_entries_.resize(room);
  jacobian_row_start_.assign(m + 1, 0);
  int n = 0;
  for (int r = 0; r < m; ++r) {
    const int first = n;
    const auto& blocks = rows_[r].blocks;
    for (std::size_t b = 0; b < blocks.size(); ++b) {
      const JacobianBlock& blk = blocks[b];
      const int c0 = blk.body == kWorld ? -1 : column_.at(blk.body);
      if (c0 < 0) continue;  // the world and fixed bodies have no columns
      // only a body met earlier in the row (the driveline's shared frames) can repeat a column
      const bool repeated = std::any_of(blocks.begin(), blocks.begin() + b,
                                        [&](const JacobianBlock& e) { return e.body == blk.body; });
      for (int k = 0; k < 6; ++k) {
        const double v = blk.jacobian[k];
        if (v == 0.0) continue;
        int same = -1;
        for (int e = first; repeated && e < n && same < 0; ++e) {
          if (jacobian_entries_[e].column == c0 + k) same = e;
        }
        if (same >= 0) {
          jacobian_entries_[same].value += v;
        } else {
          jacobian_entries_[n].column = c0 + k;
          jacobian_entries_[n].value = v;
          ++n;
        }
      }
    }
    jacobian_row_start_[r + 1] = n;
  }
  jacobian_entries_.resize(n);
  // counted per column, then placed row by row, so each column's rows ascend
  G_.resize(m, columns_);
  G_.resizeNonZeros(n);
  int* outer = G_.outerIndexPtr();
  std::fill_n(outer, columns_ + 1, 0);
  for (const JacobianEntry& e : jacobian_entries_) ++outer[e.column + 1];
  for (int c = 0; c < columns_; ++c) outer[c + 1] += outer[c];
  jacobian_fill_.assign(outer, outer + columns_);
  for (int r = 0; r < m; ++r) {
    for (int e = jacobian_row_start_[r]; e < jacobian_row_start_[r + 1]; ++e) {
      const int at = jacobian_fill_[jacobian_entries_[e].column]++;
      G_.innerIndexPtr()[at] = r;
      G_.valuePtr()[at] = jacobian_entries_[e].value;
    }
  }
}

void MultibodySystem::assemble_inverse_mass() {
  // per moving body six columns: 1/m on the linear diagonal, then the 3x3 world inverse inertia
  // (every entry stored, zeros too, as the triplets did)
  const int bodies_moving = columns_ / 6;
  minv_.resize(columns_, columns_);
  minv_.resizeNonZeros(bodies_moving * 12);
  int* outer = minv_.outerIndexPtr();
  int* inner = minv_.innerIndexPtr();
  double* value = minv_.valuePtr();
  int at = 0;
  for (size_t i = 0; i < bodies_.size(); ++i) {
    const int c0 = column_[i];
    if (c0 < 0) continue;
    for (int k = 0; k < 3; ++k) {
      outer[c0 + k] = at;
      inner[at] = c0 + k;
      value[at++] = 1.0 / bodies_[i].mass;
    }
    const Mat3& iinv = inverse_inertia_[i];
    for (int c = 0; c < 3; ++c) {
      outer[c0 + 3 + c] = at;
      for (int r = 0; r < 3; ++r) {
        inner[at] = c0 + 3 + r;
        value[at++] = iinv(r, c);
      }
    }
  }
  outer[columns_] = at;
}

void MultibodySystem::assemble_schur_complement() {
  // A = G M⁻¹ Gᵀ + Σ block by block: rows i and j couple only through a body both act on, with
  // A_ij = Σ_b J_ib M_b⁻¹ J_jbᵀ. Measured on load-carry (86 rows, 13 bodies), the general sparse
  // triple product took 22 % of a vehicle step; this takes a few microseconds. The pattern is
  // structural (which rows share a body), not the values' zeros, so the direct solver's symbolic
  // analysis is reused while the machine's rows stay the same, and A is exactly symmetric
  const int m = static_cast<int>(rows_.size());
  // per moving body, the blocks acting on it (in row order) with M_b⁻¹ J_bᵀ beside each; the
  // lists keep their memory from step to step
  on_body_.resize(bodies_.size());
  for (auto& blocks : on_body_) blocks.clear();
  for (int r = 0; r < m; ++r) {
    for (const auto& blk : rows_[r].blocks) {
      if (blk.body == kWorld || column_.at(blk.body) < 0) continue;  // no columns
      const RigidBody& body = bodies_[blk.body];
      Vec6 w;
      w.head<3>() = blk.jacobian.head<3>() / body.mass;
      w.tail<3>() = inverse_inertia_[blk.body] * blk.jacobian.tail<3>();
      on_body_[blk.body].push_back({r, blk.jacobian, w});
    }
  }
  // the pattern (which rows share a moving body, both triangles, the diagonal always stored since
  // it carries Σ) changes only when the rows' bodies do: kept from the last step while they agree
  row_bodies_.clear();
  for (const auto& row : rows_) {
    for (const auto& blk : row.blocks) {
      if (blk.body != kWorld && column_[blk.body] >= 0) row_bodies_.push_back(blk.body);
    }
    row_bodies_.push_back(kWorld);  // end of the row
  }
  Eigen::SparseMatrix<double>& A = mcp_.A;
  if (row_bodies_ != pattern_row_bodies_ || A.rows() != m) build_schur_pattern();
  // the values: each pair of blocks on one body adds J_p M_b⁻¹ J_qᵀ to its lower entry and, off
  // the diagonal, to the mirrored upper one, in the same order for both, so A is exactly symmetric
  double* value = A.valuePtr();
  std::fill_n(value, A.nonZeros(), 0.0);
  const SchurTerm* term = schur_terms_.data();
  for (const auto& blocks : on_body_) {
    for (size_t p = 0; p < blocks.size(); ++p) {
      for (size_t q = p; q < blocks.size(); ++q, ++term) {
        const double v = blocks[p].jacobian.dot(blocks[q].mobility);
        // two blocks of one row on one body: the cross term appears as (p, q) and (q, p)
        const double add = p != q && term->lower == term->upper ? 2.0 * v : v;
        value[term->lower] += add;
        if (term->upper != term->lower) value[term->upper] += add;
      }
    }
  }
  // Σ on the stored diagonal
  for (int j = 0; j < m; ++j) value[schur_diagonal_[j]] += sigma_[j];
}

void MultibodySystem::build_schur_pattern() {
  const int m = static_cast<int>(rows_.size());
  Eigen::SparseMatrix<double>& A = mcp_.A;
  std::vector<char> coupled(static_cast<size_t>(m) * m, 0);
  for (const auto& blocks : on_body_) {
    for (const BodyBlock& a : blocks) {
      for (const BodyBlock& b : blocks) coupled[static_cast<size_t>(a.row) * m + b.row] = 1;
    }
  }
  std::vector<Eigen::Triplet<double>> t;
  for (int j = 0; j < m; ++j) {
    for (int i = 0; i < m; ++i) {
      if (i == j || coupled[static_cast<size_t>(j) * m + i]) t.emplace_back(i, j, 0.0);
    }
  }
  A.resize(m, m);
  A.setFromTriplets(t.begin(), t.end());
  A.makeCompressed();
  // where each entry (i, j) lives in A's values
  const int* outer = A.outerIndexPtr();
  const int* inner = A.innerIndexPtr();
  auto entry = [&](int i, int j) {
    const int* at = std::lower_bound(inner + outer[j], inner + outer[j + 1], i);
    return static_cast<int>(at - inner);
  };
  schur_diagonal_.resize(m);
  for (int j = 0; j < m; ++j) schur_diagonal_[j] = entry(j, j);
  // each pair of blocks on one body, in the order the values loop visits them
  schur_terms_.clear();
  for (const auto& blocks : on_body_) {
    for (size_t p = 0; p < blocks.size(); ++p) {
      for (size_t q = p; q < blocks.size(); ++q) {
        const int i = std::max(blocks[p].row, blocks[q].row);
        const int j = std::min(blocks[p].row, blocks[q].row);
        schur_terms_.push_back({entry(i, j), entry(j, i)});
      }
    }
  }
  pattern_row_bodies_ = row_bodies_;
}

void MultibodySystem::solve() {
  if (!assembled_) throw Error("multibody system: solve() before assemble()");
  const int m = static_cast<int>(rows_.size());
  // free velocity v* = v + h M⁻¹ f (gravity and external wrenches)
  Eigen::VectorXd v(columns_), f(columns_);
  for (size_t i = 0; i < bodies_.size(); ++i) {
    const int c0 = column_[i];
    if (c0 < 0) continue;
    v.segment<6>(c0) = bodies_[i].twist();
    f.segment<6>(c0) = external_[i];
    f.segment<3>(c0) += bodies_[i].mass * gravity_;
  }
  const Eigen::VectorXd vstar = v + h_ * (minv_ * f);
  mcp_.b = rhs_ - G_ * vstar;
  // every solve of the step starts from the assembled bounds
  for (int r = 0; r < m; ++r) {
    std::tie(rows_[r].force_min, rows_[r].force_max) = assembled_force_range_[r];
    mcp_.lo[r] = h_ * rows_[r].force_min;
    mcp_.hi[r] = h_ * rows_[r].force_max;
  }
  // solve, then let constraints with speed-dependent bounds correct them and solve again
  bound_passes_ = 0;
  for (int pass = 0; pass < kMaxBoundPasses; ++pass) {
    result_ = solver_.solve(mcp_, &warm_lambda_, &warm_state_);
    ++bound_passes_;
    if (!result_.converged) {
      throw Error("multibody step at t = " + std::to_string(time_) +
                  " s: the direct solver did not converge (" + std::to_string(result_.iterations) +
                  " iterations, " + std::to_string(result_.friction_passes) + " friction passes)");
    }
    warm_lambda_ = result_.lambda;
    warm_state_ = result_.state;
    velocity_after_ = vstar + minv_ * (G_.transpose() * result_.lambda);
    const Eigen::VectorXd gv = G_ * velocity_after_;
    bool changed = false;
    for (size_t c = 0; c < constraints_.size(); ++c) {
      const int r0 = constraint_offset_[c];
      const int end = c + 1 < constraints_.size() ? constraint_offset_[c + 1] : m;
      if (end == r0) continue;
      if (constraints_[c]->update_bounds(gv.data() + r0, result_.lambda.data() + r0, rows_.data() + r0, end - r0)) {
        changed = true;
        for (int r = r0; r < end; ++r) {
          mcp_.lo[r] = h_ * rows_[r].force_min;
          mcp_.hi[r] = h_ * rows_[r].force_max;
        }
      }
    }
    if (!changed) break;
  }
  // forces of every constraint from its impulses
  for (size_t c = 0; c < constraints_.size(); ++c) {
    const int r0 = constraint_offset_[c];
    const int end = c + 1 < constraints_.size() ? constraint_offset_[c + 1] : m;
    constraints_[c]->store_forces(result_.lambda.data() + r0, end - r0, h_);
  }
  solved_ = true;
}

void MultibodySystem::integrate() {
  if (!solved_) throw Error("multibody system: integrate() before solve()");
  // a non-finite solve stops the run here with the time, rather than moving bodies to NaN
  if (!velocity_after_.allFinite()) {
    std::ostringstream m;
    m << "machine state became non-finite at t = " << time_ << " s: the direct solve returned "
      << "non-finite velocities. Likely causes: a non-finite or absurd input (payload, forces, "
      << "speeds in the machine or scenario file, or a flag), or a blow-up of the coupled step";
    throw Error(m.str());
  }
  for (size_t i = 0; i < bodies_.size(); ++i) {
    const int c0 = column_[i];
    if (c0 < 0) continue;
    bodies_[i].velocity = velocity_after_.segment<3>(c0);
    bodies_[i].angular_velocity = velocity_after_.segment<3>(c0 + 3);
    bodies_[i].integrate(h_);
  }
  for (auto& w : external_) w.setZero();
  time_ += h_;
  assembled_ = solved_ = false;
}

Vec6 MultibodySystem::solved_twist(int body) const {
  if (!solved_) throw Error("multibody system: solved_twist() needs solve() first");
  const int c0 = column_.at(body);
  return c0 < 0 ? Vec6::Zero() : Vec6(velocity_after_.segment<6>(c0));
}

Mat6 MultibodySystem::mobility(int body) const {
  if (!solved_) throw Error("multibody system: mobility() needs solve() first");
  const int c0 = column_.at(body);
  if (c0 < 0) return Mat6::Zero();
  // Y = G_b M_b⁻¹ (rows x 6); W = M_b⁻¹ - Yᵀ A_FF⁻¹ Y with the final active set
  const Eigen::MatrixXd mb = Eigen::MatrixXd(minv_.block(c0, c0, 6, 6));
  const Eigen::MatrixXd gb = Eigen::MatrixXd(G_.middleCols(c0, 6));
  const Eigen::MatrixXd Y = gb * mb;
  const Eigen::MatrixXd X = solver_.solve_free(Y);
  Mat6 W = mb - Y.transpose() * X;
  return W;
}

double MultibodySystem::max_joint_position_violation() const {
  double v = 0.0;
  for (const auto& r : rows_) {
    if (r.joint && r.unit == RowUnit::length) v = std::max(v, std::abs(r.violation));
  }
  return v;
}

double MultibodySystem::max_joint_angle_violation() const {
  double v = 0.0;
  for (const auto& r : rows_) {
    if (r.joint && r.unit == RowUnit::angle) v = std::max(v, std::abs(r.violation));
  }
  return v;
}

void MultibodySystem::save_state(ByteWriter& w) const {
  // between steps only: a solve's assembly and result are not kept
  if (assembled_ || solved_)
    throw Error(
        "multibody system: save_state() inside a step (after assemble(), before integrate())");
  w.u64(bodies_.size());
  for (const RigidBody& b : bodies_) {
    w.f64(b.mass);
    write_matrix(w, b.inertia);
    write_matrix(w, b.position);
    write_matrix(w, b.orientation.coeffs());
    write_matrix(w, b.velocity);
    write_matrix(w, b.angular_velocity);
  }
  write_matrix(w, gravity_);
  w.f64(h_);
  w.f64(time_);
  w.u64(static_cast<std::uint64_t>(warm_lambda_.size()));
  w.f64s(warm_lambda_.data(), static_cast<std::size_t>(warm_lambda_.size()));
  w.u64(warm_state_.size());
  for (const RowState s : warm_state_) w.u8(static_cast<std::uint8_t>(s));
  // each constraint under its name, so a file of a build that ordered them otherwise is refused
  w.u64(constraints_.size());
  for (const auto& c : constraints_) {
    w.tag(c->name);
    c->save_state(w);
  }
}

void MultibodySystem::restore_state(ByteReader& r) {
  // the same machine: as many bodies and constraints as were saved
  const std::uint64_t bodies = r.u64("machine bodies");
  if (bodies != bodies_.size())
    throw InputError(r.where() + ": the saved machine has " + std::to_string(bodies) +
                     " bodies, this one " + std::to_string(bodies_.size()) +
                     "; restore a state into a simulation made with the same machine");
  for (RigidBody& b : bodies_) {
    b.mass = r.f64("machine bodies");
    read_matrix(r, b.inertia, "machine bodies");
    read_matrix(r, b.position, "machine bodies");
    read_matrix(r, b.orientation.coeffs(), "machine bodies");
    read_matrix(r, b.velocity, "machine bodies");
    read_matrix(r, b.angular_velocity, "machine bodies");
  }
  read_matrix(r, gravity_, "machine gravity");
  h_ = r.f64("machine clock");
  time_ = r.f64("machine clock");
  // the direct solver's warm start
  const std::uint64_t lambdas = r.u64("machine warm start");
  r.need_elements(lambdas, 8, "machine warm start");
  warm_lambda_.resize(static_cast<Eigen::Index>(lambdas));
  r.f64s(warm_lambda_.data(), lambdas, "machine warm start");
  const std::uint64_t states = r.u64("machine active set");
  r.need_elements(states, 1, "machine active set");
  warm_state_.resize(states);
  for (RowState& s : warm_state_) {
    const std::uint8_t v = r.u8("machine active set");
    if (v > static_cast<std::uint8_t>(RowState::upper))
      throw InputError(r.where() + ": a row state " + std::to_string(v) +
                       " in the machine's active set (corrupt)");
    s = static_cast<RowState>(v);
  }
  const std::uint64_t constraints = r.u64("machine constraints");
  if (constraints != constraints_.size())
    throw InputError(r.where() + ": the saved machine has " + std::to_string(constraints) +
                     " constraints, this one " + std::to_string(constraints_.size()) +
                     "; restore a state into a simulation made with the same machine");
  for (const auto& c : constraints_) {
    r.expect(c->name);
    c->restore_state(r);
  }
  // nothing of a step in progress
  for (auto& e : external_) e.setZero();
  assembled_ = solved_ = false;
}

}  // namespace talus::vehicle
