#include "sim2real/metrics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "host/error.hpp"

namespace talus::sim2real {

namespace {

// a normaliser must be a positive finite scale, otherwise the error is meaningless
void check_normaliser(double value, const char* what) {
  if (!(value > 0.0) || !std::isfinite(value)) {
    throw InputError(std::string(what) + " must be positive and finite, got " +
                     std::to_string(value) +
                     " (an all-zero or constant reference channel cannot normalise an error)");
  }
}

}  // namespace

double max_abs(const std::vector<double>& f) {
  double m = 0.0;
  for (double v : f) m = std::max(m, std::abs(v));
  return m;
}

double normalised_mae(const std::vector<double>& f, const std::vector<double>& reference,
                      double f_norm) {
  if (f.size() != reference.size() || f.empty()) {
    throw Error("normalised_mae: series must have equal, non-zero length (got " +
                std::to_string(f.size()) + " and " + std::to_string(reference.size()) + ")");
  }
  check_normaliser(f_norm, "f_norm");
  double sum = 0.0;
  for (std::size_t n = 0; n < f.size(); ++n) sum += std::abs(f[n] - reference[n]);
  return sum / (static_cast<double>(f.size()) * f_norm);
}

double normalised_mae(const std::vector<double>& f, const std::vector<double>& reference) {
  return normalised_mae(f, reference, max_abs(reference));
}

double normalised_mee(const Trajectory& x, const Trajectory& reference, double l_norm) {
  if (x.rows() != reference.rows() || x.cols() != reference.cols() || x.rows() == 0) {
    throw Error("normalised_mee: trajectories must have equal, non-zero shape");
  }
  check_normaliser(l_norm, "L_norm");
  const double sum = (x - reference).rowwise().norm().sum();
  return sum / (static_cast<double>(x.rows()) * l_norm);
}

double dtw_distance(const Trajectory& a, const Trajectory& b) {
  if (a.rows() == 0 || b.rows() == 0 || a.cols() != b.cols()) {
    throw Error("dtw_distance: trajectories must be non-empty with the same number of columns");
  }
  const Eigen::Index n = a.rows();
  const Eigen::Index m = b.rows();
  // c[i,j] as scipy cdist 'euclidean': sqrt of the summed squared differences
  auto cost = [&](Eigen::Index i, Eigen::Index j) { return (a.row(i) - b.row(j)).norm(); };

  // row 0: d[0,0] = c[0,0], d[0,j] = d[0,j-1] + c[0,j]
  std::vector<double> prev(static_cast<std::size_t>(m));
  std::vector<double> cur(static_cast<std::size_t>(m));
  prev[0] = cost(0, 0);
  for (Eigen::Index j = 1; j < m; ++j) {
    prev[static_cast<std::size_t>(j)] = prev[static_cast<std::size_t>(j - 1)] + cost(0, j);
  }
  // rows 1..n-1, in the same operation order as the Python loop so results agree to rounding
  for (Eigen::Index i = 1; i < n; ++i) {
    cur[0] = prev[0] + cost(i, 0);
    for (Eigen::Index j = 1; j < m; ++j) {
      const auto ju = static_cast<std::size_t>(j);
      cur[ju] = cost(i, j) + std::min({prev[ju], cur[ju - 1], prev[ju - 1]});
    }
    std::swap(prev, cur);
  }
  return prev[static_cast<std::size_t>(m - 1)];
}

double normalised_dtw(double distance, std::size_t n, double l_norm) {
  if (n == 0) throw Error("normalised_dtw: N must be positive");
  check_normaliser(l_norm, "L_norm");
  return distance / (static_cast<double>(n) * l_norm);
}

double trajectory_extent(const Trajectory& reference) {
  if (reference.rows() == 0) throw Error("trajectory_extent: empty trajectory");
  return (reference.colwise().maxCoeff() - reference.colwise().minCoeff()).norm();
}

double relative_error(double value, double reference) {
  if (reference == 0.0 || !std::isfinite(reference)) {
    throw InputError("relative error: the reference value must be non-zero and finite, got " +
                     std::to_string(reference));
  }
  return (value - reference) / reference;
}

double loaded_mass_error(double simulated_kg, double measured_kg) {
  for (const double m : {simulated_kg, measured_kg})
    if (!(m >= 0.0) || !std::isfinite(m))
      throw InputError("loaded mass error: a loaded mass must be finite and not negative, got " +
                       std::to_string(m) + " kg");
  if (measured_kg == 0.0)
    return simulated_kg == 0.0 ? 0.0 : std::numeric_limits<double>::quiet_NaN();
  return relative_error(simulated_kg, measured_kg);
}

double paper_mean(const std::array<double, 7>& columns) {
  double sum = 0.0;
  int defined = 0;
  for (double v : columns) {
    if (std::isnan(v)) continue;
    sum += std::abs(v);
    ++defined;
  }
  return defined > 0 ? sum / defined : std::numeric_limits<double>::quiet_NaN();
}

double paper_mean(const ErrorColumns& e) { return paper_mean(e.as_array()); }

}  // namespace talus::sim2real
