#include "sim2real/response_surface.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

#include "host/error.hpp"

namespace talus::sim2real {

FitWindow fit_window(const std::vector<double>& axis, double best, int per_side) {
  FitWindow w;
  // the neighbours of the best point among the scan's values, or the range's bounds
  const auto at = std::find(axis.begin(), axis.end(), best);
  if (at == axis.end()) throw Error("fit_window: the best point is not one of the scan's values");
  w.lo = at == axis.begin() ? 0.0 : *(at - 1);
  w.hi = at + 1 == axis.end() ? 1.0 : *(at + 1);
  // a bound is sampled as a point of its own; a neighbour was scanned already
  if (at == axis.begin() && w.lo < best) w.new_points.push_back(w.lo);
  // per_side points evenly between the best point and each neighbour
  for (int k = 1; k <= per_side; ++k)
    w.new_points.push_back(w.lo + (best - w.lo) * k / (per_side + 1));
  for (int k = 1; k <= per_side; ++k)
    w.new_points.push_back(best + (w.hi - best) * k / (per_side + 1));
  if (at + 1 == axis.end() && w.hi > best) w.new_points.push_back(w.hi);
  w.spacing = std::min(best - w.lo, w.hi - best) / (per_side + 1);
  return w;
}

double LocalParabola::roughness() const {
  return rise > 0.0 ? residual_rms / rise : std::numeric_limits<double>::infinity();
}

LocalParabola fit_parabola(const std::vector<double>& u, const std::vector<double>& y, double lo,
                           double hi) {
  const std::size_t n = u.size();
  if (n != y.size() || n < 3 || !(hi > lo))
    throw Error("fit_parabola: needs at least three samples in a window of positive width");
  // u mapped to t in [-1, 1] over the window, so the columns 1, t, t^2 are of one size
  const double centre = 0.5 * (lo + hi), half = 0.5 * (hi - lo);
  Eigen::MatrixXd a(n, 3);
  Eigen::VectorXd b(n);
  for (std::size_t k = 0; k < n; ++k) {
    const double t = (u[k] - centre) / half;
    a.row(static_cast<Eigen::Index>(k)) << 1.0, t, t * t;
    b(static_cast<Eigen::Index>(k)) = y[k];
  }
  // the samples must hold three distinct u for the three coefficients to be determined
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(a);
  if (qr.rank() < 3) throw Error("fit_parabola: the samples hold fewer than three distinct points");
  const Eigen::Vector3d coef = qr.solve(b);
  const auto value = [&](double t) { return coef(0) + coef(1) * t + coef(2) * t * t; };
  LocalParabola p;
  p.residual_rms = std::sqrt((a * coef - b).squaredNorm() / static_cast<double>(n));
  p.convex = coef(2) > 0.0;
  if (!p.convex) return p;
  // its minimum in the window, and how far it climbs from there to the farther end
  const double t_free = -coef(1) / (2.0 * coef(2));
  const double t_min = std::clamp(t_free, -1.0, 1.0);
  p.clamped = t_min != t_free;
  p.vertex = centre + half * t_min;
  p.at_vertex = value(t_min);
  p.rise = std::max(value(-1.0), value(1.0)) - p.at_vertex;
  return p;
}

int local_minima(const std::vector<double>& u, const std::vector<double>& y) {
  if (u.size() != y.size()) throw Error("local_minima: as many u as y");
  for (double v : y)
    if (!std::isfinite(v)) throw Error("local_minima: a sample is not finite");
  // the samples in the order of u
  std::vector<std::size_t> order(u.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return u[a] < u[b]; });
  // the signs of the steps between neighbours, equal neighbours skipped; a minimum is a fall
  // followed by a rise, with the ends taken as falls into them
  int minima = 0;
  int last = -1;  // before the first sample: as if falling into it
  for (std::size_t k = 1; k < order.size(); ++k) {
    const double step = y[order[k]] - y[order[k - 1]];
    if (step == 0.0) continue;
    const int sign = step > 0.0 ? 1 : -1;
    if (last < 0 && sign > 0) ++minima;
    last = sign;
  }
  // after the last sample: as if rising out of it
  if (last < 0) ++minima;
  return minima;
}

bool WindowTrend::rough() const { return parabola.convex && !parabola.clamped && local_minima > 1; }

WindowTrend window_trend(const std::vector<double>& u, const std::vector<double>& y,
                         const FitWindow& window) {
  return {fit_parabola(u, y, window.lo, window.hi), local_minima(u, y)};
}

}  // namespace talus::sim2real
