// One interface for the sweep strategies over contact rows (solver2d-style: one file per
// algorithm, so projected Gauss-Seidel and projected Jacobi stay comparable).
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "host/device.hpp"
#include "solvers/dem_buffers.hpp"
#include "solvers/dem_settings.hpp"
#include "solvers/kinematic_tool_rows.hpp"

namespace talus {

// the kernel files of the contact rows and sweeps, in order: the shared helpers, the contact law
// (normal, friction and rolling projections), then the rows, sweeps and residual, then the rows
// against the bucket and tools (whose fused sweep calls the particle sweeps). One list, so every
// user builds the same program once (Device caches it by its files)
inline const std::vector<std::string> kSolverProgram = {"dem_common.cl", "contact_law.cl",
                                                        "solver.cl", "bucket.cl"};

class ContactSweep {
 public:
  virtual ~ContactSweep() = default;
  // runs `iterations` sweeps over all rows, updating impulses and body velocities in place
  virtual void iterate(DemBuffers& b, int iterations) = 0;
  // `iterations` sweeps, each over the particle rows and then the kinematic tools' rows (the
  // coupled order of ToolWorld); a strategy may fuse them (PGS: one launch for a small system)
  virtual void iterate_with_tools(DemBuffers& b, int iterations, KinematicToolRows& tools) {
    for (int it = 0; it < iterations; ++it) {
      if (b.n_contacts > 0) iterate(b, 1);
      tools.sweep(b.velocity, b.omega);
    }
  }
  virtual const char* name() const = 0;
  // whether systems of at most `rows` rows are swept by one work-item walking them in turn (PGS
  // on a CPU device, up to its one-group threshold): their rows then need no colours
  // (DemSettings::serial_lanes)
  virtual bool walks_in_one_item(int rows) const {
    (void)rows;
    return false;
  }
  // whether systems of `rows` rows are swept as runs that one work-item each walks, the parts
  // side by side and then the runs across them, level by level (PGS on a CPU device, above its
  // one-group threshold): their rows then need no colours (DemSettings::sweep_parts,
  // RowLayout::Runs)
  virtual bool walks_in_runs(int rows) const {
    (void)rows;
    return false;
  }
};

// graph-coloured projected Gauss-Seidel (solvers/pgs_sweep.cpp); systems of up to
// `one_group_rows` rows are swept in one work-group (DemSettings::one_group_rows)
std::unique_ptr<ContactSweep> make_pgs_sweep(Device& dev, int one_group_rows = kPgsOneGroupRows);
// projected Jacobi with mass splitting (solvers/jacobi_sweep.cpp)
std::unique_ptr<ContactSweep> make_jacobi_sweep(Device& dev, int particles);
// the sweep of `settings` (its kind; PGS's one-group threshold)
std::unique_ptr<ContactSweep> make_sweep(const DemSettings& settings, Device& dev, int particles);

}  // namespace talus
