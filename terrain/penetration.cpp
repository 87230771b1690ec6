#include "terrain/penetration.hpp"

#include <algorithm>
#include <cmath>

namespace talus {
namespace {
constexpr double kGravity = 9.81;  // [m/s^2], as DemSettings::gravity
constexpr double kDegree = M_PI / 180.0;
}  // namespace

double penetration_resistance(double depth, double width, const BulkSoil& soil,
                              const PenetrationParameters& edge, double density) {
  if (!(depth > 0.0)) return 0.0;
  // bearing capacity of a strip as wide as the edge is thick (Terzaghi, Vesić's factors)
  const double phi = soil.effective_friction_deg() * kDegree;
  const double n_q =
      std::exp(M_PI * std::tan(phi)) * std::pow(std::tan(0.25 * M_PI + 0.5 * phi), 2);
  const double n_gamma = 2.0 * (n_q + 1.0) * std::tan(phi);
  const double b = 2.0 * edge.edge_max_radius;
  const double q = density * kGravity * (depth * n_q + 0.5 * b * n_gamma);
  // the tapered edge's faces add their friction
  const double theta = std::atan((edge.edge_max_radius - edge.edge_min_radius) / edge.tooth_length);
  const double faces = 1.0 + soil.tool_friction / std::tan(theta);
  // the ramp from the surface to full depth
  const double ramp =
      edge.ramp_start + (1.0 - edge.ramp_start) * std::min(depth / edge.full_depth, 1.0);
  return q * b * width * faces * ramp;
}

}  // namespace talus
