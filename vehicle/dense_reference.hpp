// Dense reference solver for the bounded MCP of vehicle/mcp.hpp, for tests only: block principal
// pivoting (Júdice & Pires 1994, box-constrained form) with Murty's single-pivot rule as the
// fallback that guarantees termination, and an Eigen LDLT of the free block each iteration.
// Deliberately a different algorithm and different linear algebra from the direct solver, so that
// agreement between the two means something. O(n³) per iteration: keep n in the hundreds.
#pragma once
#include "vehicle/mcp.hpp"

namespace talus::vehicle {

struct DenseReferenceOptions {
  int max_iterations = 0;        // 0: 50 n + 100
  int max_friction_passes = kMaxFrictionPasses;  // fixed-point passes over friction bounds
  double friction_tolerance = 1e-12;  // relative change of friction bounds that ends the passes
};

McpResult solve_dense_reference(const BoundedMcp& problem, const DenseReferenceOptions& options = {});

}  // namespace talus::vehicle
