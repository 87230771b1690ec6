#include "terrain/earthmoving_equation.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "host/error.hpp"

namespace talus {
namespace {

constexpr double kGravity = 9.81;  // [m/s^2], as DemSettings::gravity
constexpr double kDegree = M_PI / 180.0;

// N_q at failure angle beta [rad], or infinity where the wedge cannot fail along that plane
double n_q(double alpha, double delta, double phi, double beta) {
  const double den = std::cos(alpha + delta) + std::sin(alpha + delta) / std::tan(beta + phi);
  if (!(den > 0.0)) return INFINITY;
  return (1.0 / std::tan(alpha) + 1.0 / std::tan(beta)) / den;
}

}  // namespace

double fee_failure_angle(double rake_deg, double tool_friction_deg, double internal_friction_deg) {
  const double alpha = rake_deg * kDegree, delta = tool_friction_deg * kDegree;
  const double phi = internal_friction_deg * kDegree;
  // coarse: the best point of a 0.1 deg grid over (0, 90) deg, k = 1 ... kGridPoints (the first
  // one where two tie). Where the angles are non-negative and sum below 180 deg, N_q is finite
  // exactly below beta = 180 deg - alpha - delta - phi and unimodal there (it falls from infinity
  // at beta -> 0 and rises to infinity where den reaches zero), so the best point lies within one
  // coarse step of the best point of the sub-grid {1, 10, 20, ..., 890, kGridPoints}: both found
  // in at most 91 + 21 evaluations instead of 899, the same point (tests/terrain
  // earthmoving_equation_test). Elsewhere every point is tried
  constexpr int kGridPoints = 899;
  constexpr int kCoarseStride = 10;
  auto grid_nq = [&](int k) { return n_q(alpha, delta, phi, 0.1 * k * kDegree); };
  double best = INFINITY;
  int best_k = 0;
  auto try_points = [&](int first, int last) {
    for (int k = first; k <= last; ++k)
      if (const double f = grid_nq(k); f < best) {
        best = f;
        best_k = k;
      }
  };
  const bool unimodal = rake_deg > 0.0 && tool_friction_deg >= 0.0 &&
                        internal_friction_deg >= 0.0 &&
                        rake_deg + tool_friction_deg + internal_friction_deg < 180.0;
  if (unimodal) {
    // the sub-grid's points: 1, then every tenth point, then the last
    constexpr int kCoarsePoints = kGridPoints / kCoarseStride + 2;
    auto coarse = [&](int c) {
      return c == 0 ? 1 : c == kCoarsePoints - 1 ? kGridPoints : c * kCoarseStride;
    };
    int best_c = -1;
    for (int c = 0; c < kCoarsePoints; ++c)
      if (const double f = grid_nq(coarse(c)); f < best) {
        best = f;
        best_c = c;
      }
    best = INFINITY;
    if (best_c >= 0)
      try_points(coarse(std::max(best_c - 1, 0)), coarse(std::min(best_c + 1, kCoarsePoints - 1)));
  } else {
    try_points(1, kGridPoints);
  }
  if (best_k == 0)
    throw InputError("earthmoving equation: no failure plane for rake " + std::to_string(rake_deg) +
                     " deg, tool friction " + std::to_string(tool_friction_deg) +
                     " deg and internal friction " + std::to_string(internal_friction_deg) +
                     " deg: their sum must stay below 180 deg");
  // fine: golden sections on the bracket around it (N_q is unimodal there)
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  double lo = std::max(1e-9, 0.1 * (best_k - 1)) * kDegree, hi = 0.1 * (best_k + 1) * kDegree;
  double a = hi - g * (hi - lo), b = lo + g * (hi - lo);
  double fa = n_q(alpha, delta, phi, a), fb = n_q(alpha, delta, phi, b);
  while (hi - lo > 1e-9 * kDegree) {
    if (fa < fb) {
      hi = b;
      b = a;
      fb = fa;
      a = hi - g * (hi - lo);
      fa = n_q(alpha, delta, phi, a);
    } else {
      lo = a;
      a = b;
      fa = fb;
      b = lo + g * (hi - lo);
      fb = n_q(alpha, delta, phi, b);
    }
  }
  return 0.5 * (lo + hi) / kDegree;
}

double fee_n_q(double rake_deg, double tool_friction_deg, double internal_friction_deg,
               double beta_deg) {
  return n_q(rake_deg * kDegree, tool_friction_deg * kDegree, internal_friction_deg * kDegree,
             beta_deg * kDegree);
}

double fee_force(double density, double depth, double width, double rake_deg,
                 double tool_friction_deg, double internal_friction_deg, double surcharge,
                 double* beta_deg) {
  const double beta = fee_failure_angle(rake_deg, tool_friction_deg, internal_friction_deg);
  if (beta_deg) *beta_deg = beta;
  const double alpha = rake_deg * kDegree, delta = tool_friction_deg * kDegree;
  const double nq = n_q(alpha, delta, internal_friction_deg * kDegree, beta * kDegree);
  // F / (rho g w) = d^2 N_gamma + h d N_q with N_gamma = N_q / 2
  const double f = (0.5 * depth * depth + std::max(0.0, surcharge) * depth) * nq;
  return density * kGravity * f * width * std::sin(alpha + delta);
}

}  // namespace talus
