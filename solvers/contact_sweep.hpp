// One interface for the sweep strategies over contact rows (solver2d-style: one file per
// algorithm, so projected Gauss-Seidel and projected Jacobi stay comparable).
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "host/device.hpp"
#include "solvers/dem_buffers.hpp"
#include "solvers/dem_settings.hpp"

namespace talus {

// the kernel files of the contact rows and sweeps, in order: the shared helpers, the contact law
// (normal, friction and rolling projections), then the rows, sweeps and residual. One list, so
// every user builds the same program once (Device caches it by its files)
inline const std::vector<std::string> kSolverProgram = {"dem_common.cl", "contact_law.cl", "solver.cl"};

class ContactSweep {
 public:
  virtual ~ContactSweep() = default;
  // runs `iterations` sweeps over all rows, updating impulses and body velocities in place
  virtual void iterate(DemBuffers& b, int iterations) = 0;
  virtual const char* name() const = 0;
};

// graph-coloured projected Gauss-Seidel (solvers/pgs_sweep.cpp); systems of up to
// `one_group_rows` rows are swept in one work-group (DemSettings::one_group_rows)
std::unique_ptr<ContactSweep> make_pgs_sweep(Device& dev, int one_group_rows = kPgsOneGroupRows);
// projected Jacobi with mass splitting (solvers/jacobi_sweep.cpp)
std::unique_ptr<ContactSweep> make_jacobi_sweep(Device& dev, int particles);
// the sweep of `settings` (its kind; PGS's one-group threshold)
std::unique_ptr<ContactSweep> make_sweep(const DemSettings& settings, Device& dev, int particles);

}  // namespace talus
