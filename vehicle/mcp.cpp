#include "vehicle/mcp.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "host/error.hpp"

namespace talus::vehicle {

bool BoundedMcp::has_friction() const {
  return std::any_of(normal.begin(), normal.end(), [](int k) { return k >= 0; });
}

void check_mcp(const BoundedMcp& p) {
  const int n = p.size();
  if (p.A.rows() != n || p.A.cols() != n || p.lo.size() != n || p.hi.size() != n) {
    throw Error("bounded MCP: A must be n x n and b, lo, hi of length n (n = " + std::to_string(n) + ")");
  }
  if (!p.normal.empty() && (static_cast<int>(p.normal.size()) != n || p.mu.size() != n)) {
    throw Error("bounded MCP: normal and mu must have one entry per row");
  }
  for (int i = 0; i < n; ++i) {
    if (std::isnan(p.lo[i]) || std::isnan(p.hi[i]) || std::isnan(p.b[i]) || p.lo[i] > p.hi[i]) {
      throw Error("bounded MCP: row " + std::to_string(i) + " has a NaN or lo > hi");
    }
    if (!p.normal.empty() && p.normal[i] >= n) {
      throw Error("bounded MCP: row " + std::to_string(i) + " names a normal row out of range");
    }
  }
}

double apply_friction_bounds(const BoundedMcp& p, const Eigen::VectorXd& lambda,
                             Eigen::VectorXd& lo, Eigen::VectorXd& hi) {
  double change = 0.0;
  for (int i = 0; i < static_cast<int>(p.normal.size()); ++i) {
    const int k = p.normal[i];
    if (k < 0) continue;
    // box-linearised Coulomb: |λ_t| <= μ λ_n, with the current normal impulse
    const double bound = p.mu[i] * std::max(lambda[k], 0.0);
    change = std::max(change, std::abs(bound - hi[i]));
    lo[i] = -bound;
    hi[i] = bound;
  }
  return change;
}

double friction_bound_scale(const BoundedMcp& p, const Eigen::VectorXd& hi) {
  double s = 1.0;
  for (int i = 0; i < static_cast<int>(p.normal.size()); ++i) {
    if (p.normal[i] >= 0) s = std::max(s, 1.0 + std::abs(hi[i]));
  }
  return s;
}

double mcp_residual(const BoundedMcp& p, const Eigen::VectorXd& lambda) {
  const Eigen::VectorXd w = p.A * lambda - p.b;
  // friction rows are judged against the bounds their normal impulse gives
  BoundedMcp bounds = p;
  apply_friction_bounds(bounds, lambda);
  double r = 0.0;
  for (int i = 0; i < p.size(); ++i) {
    const double projected = std::clamp(lambda[i] - w[i], bounds.lo[i], bounds.hi[i]);
    r = std::max(r, std::abs(lambda[i] - projected));
  }
  return r;
}

}  // namespace talus::vehicle
