#include "solvers/tolerance_schedule.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "host/error.hpp"

namespace talus {

ToleranceSchedule::ToleranceSchedule(double tolerance) : tolerance_(tolerance) {
  if (!(tolerance > 0.0) || !std::isfinite(tolerance))
    throw InputError("ToleranceSchedule: the tolerance must be positive and finite [m/s]");
}

bool ToleranceSchedule::look(int sweeps, double residual) {
  // the look before this one, and this one kept for the next
  const int previous_sweeps = std::exchange(last_sweeps_, sweeps);
  const double previous_residual = std::exchange(last_residual_, residual);
  if (residual < tolerance_) return true;

  // the next look: ten sweeps on after the first look or a residual that did not fall (or was
  // not finite)
  int stride = kFirstLookInterval;
  if (previous_sweeps > 0 && sweeps > previous_sweeps && std::isfinite(previous_residual) &&
      residual < previous_residual) {
    // the power law r = A n^-p through the two looks, and the sweeps where it meets the tolerance
    const double p = std::log(previous_residual / residual) /
                     std::log(static_cast<double>(sweeps) / previous_sweeps);
    const double reach = sweeps * std::pow(residual / tolerance_, 1.0 / p);
    // the first whole sweep past the crossing (at it the residual would equal the tolerance)
    const double ahead = std::floor(reach - sweeps) + 1.0;
    stride = static_cast<int>(std::clamp(ahead, 1.0, static_cast<double>(kMaxLookStride)));
  }
  next_ = sweeps + stride;
  return false;
}

}  // namespace talus
