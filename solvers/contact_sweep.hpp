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

// rows up to which PGS sweeps all colours in one work-group (kernels/solver.cl
// pgs_sweeps_one_group), a launch per sweep instead of one per colour: below it the launches
// cost more than one compute unit's loss of the others (bench/RESULTS.md, 2026-11-27)
inline constexpr int kPgsOneGroupRows = 4096;

// graph-coloured projected Gauss-Seidel (solvers/pgs_sweep.cpp); systems of up to
// `one_group_rows` rows are swept in one work-group
std::unique_ptr<ContactSweep> make_pgs_sweep(Device& dev, int one_group_rows = kPgsOneGroupRows);
// projected Jacobi with mass splitting (solvers/jacobi_sweep.cpp)
std::unique_ptr<ContactSweep> make_jacobi_sweep(Device& dev, int particles);
std::unique_ptr<ContactSweep> make_sweep(SweepKind kind, Device& dev, int particles);

}  // namespace talus
