#include "vehicle/spook.hpp"

#include <string>

#include "host/error.hpp"

namespace talus::spook {

RowCoefficients holonomic_row(double h, double compliance, double damping_time) {
  if (!(h > 0.0) || compliance < 0.0 || damping_time < 0.0) {
    throw Error("SPOOK row needs h > 0, compliance >= 0 and damping time >= 0 (got h = " +
                std::to_string(h) + ", compliance = " + std::to_string(compliance) +
                ", damping time = " + std::to_string(damping_time) + ")");
  }
  // Υ = 1/(1 + 4τ/h), Σ = 4ε/(h² (1 + 4τ/h))
  const double d = 1.0 + 4.0 * damping_time / h;
  RowCoefficients c;
  c.upsilon = 1.0 / d;
  c.sigma = 4.0 * compliance / (h * h * d);
  return c;
}

double velocity_row_sigma(double h, double viscous_compliance) {
  if (!(h > 0.0) || viscous_compliance < 0.0) {
    throw Error("SPOOK velocity row needs h > 0 and compliance >= 0");
  }
  // force = -v/ε_v, impulse = h force, so v + (ε_v/h) λ = 0
  return viscous_compliance / h;
}

double holonomic_rhs(double h, const RowCoefficients& c, double violation, double row_velocity) {
  return -(4.0 / h) * c.upsilon * violation + c.upsilon * row_velocity;
}

}  // namespace talus::spook
