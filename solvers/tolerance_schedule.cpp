#include "solvers/tolerance_schedule.hpp"

#include <algorithm>
#include <cmath>

#include "host/error.hpp"

namespace talus {

ToleranceSchedule::ToleranceSchedule(double tolerance) : tolerance_(tolerance) {
  if (!(tolerance > 0.0) || !std::isfinite(tolerance))
    throw InputError("ToleranceSchedule: the tolerance must be positive and finite [m/s]");
}

bool ToleranceSchedule::look(int sweeps, double residual) {
  // the look, kept with the one before it
  previous_sweeps_ = last_sweeps_;
  previous_residual_ = last_residual_;
  last_sweeps_ = sweeps;
  last_residual_ = residual;
  if (residual < tolerance_) return true;

  // the next look: ten sweeps on after the first look or a residual that did not fall (or was
  // not finite)
  int stride = kFirstLookInterval;
  if (previous_sweeps_ > 0 && sweeps > previous_sweeps_ && std::isfinite(previous_residual_) &&
      residual < previous_residual_) {
    // the power law r = A n^-p through the two looks, and the sweeps where it meets the tolerance
    const double p = std::log(previous_residual_ / residual) /
                     std::log(static_cast<double>(sweeps) / previous_sweeps_);
    const double reach = sweeps * std::pow(residual / tolerance_, 1.0 / p);
    // the first whole sweep past the crossing (at it the residual would equal the tolerance)
    const double ahead = std::floor(reach - sweeps) + 1.0;
    stride = static_cast<int>(std::clamp(ahead, 1.0, static_cast<double>(kMaxLookStride)));
  }
  next_ = sweeps + stride;
  return false;
}

}  // namespace talus
