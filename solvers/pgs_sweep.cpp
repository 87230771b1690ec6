// Projected Gauss-Seidel in one of three row layouts (RowLayout). Colours: solved one after
// another, the rows of one colour in parallel (they share no dynamic body, so the updates never
// race). On a CPU device, whose work-groups run one item at a time on a core, no colours: a
// system of up to one_group_rows rows comes as one "colour" of interleaved rows that one
// work-item walks (DemSettings::serial_lanes), a larger one as runs, its parts walked side by
// side by a work-item each and then the runs across them, level by level (DemSettings::sweep_parts,
// kernels/dem_types.h). Rows that share
// bodies may only reach the walk they were laid out for (check_layout). Within a contact the
// normal row goes first, then friction, then rolling (kernels/solver.cl).
#include <algorithm>
#include <string>

#include "host/error.hpp"
#include "solvers/contact_sweep.hpp"

namespace talus {

namespace {

// the work-group of pgs_sweeps_one_group(_tools) on a device that runs a group's items side by
// side (a GPU): as many work-items as the kernel allows there, at most this many (a colour of a
// small system has tens to hundreds of rows). A CPU device (PoCL) runs a group's items one after
// another on one core, so there extra items only add their turns at every colour's barrier: one
// item walks the rows instead (HD27-G200 sweeps 0.95-0.97 ms a step with 1 item, 0.95-0.99 with
// 8, 1.11-1.16 with 256, the same bits; bench/RESULTS.md 2026-11-30)
constexpr size_t kOneGroupSize = 256;

class PgsSweep : public ContactSweep {
 public:
  PgsSweep(Device& dev, int one_group_rows) : dev_(dev), one_group_rows_(one_group_rows) {
    const cl::Program& program = dev.program(kSolverProgram);
    kernel_ = dev.kernel(program, "pgs_colour");
    one_group_ = dev.kernel(program, "pgs_sweeps_one_group");
    one_group_tools_ = dev.kernel(program, "pgs_sweeps_one_group_tools");
    runs_ = dev.kernel(program, "pgs_runs");
    group_size_ = group_size(one_group_);
    tools_group_size_ = group_size(one_group_tools_);
  }
  const char* name() const override { return "pgs"; }

  bool walks_in_one_item(int rows) const override {
    return group_size_ == 1 && tools_group_size_ == 1 && rows <= one_group_rows_;
  }

  bool walks_in_runs(int rows) const override {
    return group_size_ == 1 && tools_group_size_ == 1 && rows > one_group_rows_;
  }

  void iterate(DemBuffers& b, int iterations) override {
    int colours = static_cast<int>(b.colour_start.size()) - 1;
    if (colours <= 0 || iterations <= 0) return;
    check_layout(b);
    // a small system: every sweep's colours in one launch, one work-group (with colours the same
    // bits as a launch per colour)
    if (b.colour_start.back() <= one_group_rows_) {
      sweeps_in_one_group(b, colours, iterations);
      return;
    }
    // one launch per colour (or per set of runs) and sweep, all on the in-order queue without
    // host waits
    for (int it = 0; it < iterations; ++it) sweep_large(b, colours);
  }

  void iterate_with_tools(DemBuffers& b, int iterations, KinematicToolRows& tools) override {
    // the step's colours; none when it has no particle rows (only tool rows)
    const int colours = b.n_contacts > 0 ? static_cast<int>(b.colour_start.size()) - 1 : 0;
    if (iterations <= 0 || (colours <= 0 && tools.groups() == 0)) return;
    if (colours > 0) check_layout(b);
    // a small system: the sweeps and the tools' rows in one launch (with colours the same bits)
    const int particle_rows = colours > 0 ? b.colour_start.back() : 0;
    if (particle_rows + tools.rows() <= one_group_rows_) {
      set_args(one_group_tools_, b.rows, b.impulses, b.colour_start_dev, std::max(colours, 0),
               iterations, b.velocity, b.omega, tools.row_buffer(), tools.group_start(),
               tools.groups(), tools.row_tool(), tools.tool_bodies());
      launch_group(dev_, one_group_tools_, tools_group_size_, "pgs_sweeps_one_group_tools");
      return;
    }
    // each sweep: the particle rows (in one work-group while they alone are small enough), then
    // the tools' rows across the device
    const bool one_group = colours > 0 && particle_rows <= one_group_rows_;
    for (int it = 0; it < iterations; ++it) {
      if (one_group) {
        sweeps_in_one_group(b, colours, 1);
      } else {
        sweep_large(b, colours);
      }
      tools.sweep(b.velocity, b.omega);
    }
  }

 private:
  // rows laid out for one work-item (interleaved) or in runs share bodies: they must reach only
  // the walk they were laid out for, never the parallel per-colour launches (which would race)
  void check_layout(const DemBuffers& b) const {
    const int rows = b.colour_start.back();
    if (b.row_layout == RowLayout::Interleaved && !walks_in_one_item(rows))
      throw Error("PGS sweep: " + std::to_string(rows) +
                  " rows laid out for one work-item reached a sweep that runs them in parallel "
                  "(internal error: the layout and the sweep disagree on one_group_rows)");
    if (b.row_layout == RowLayout::Runs && !walks_in_runs(rows))
      throw Error("PGS sweep: " + std::to_string(rows) +
                  " rows laid out in runs reached a sweep that does not walk runs (internal "
                  "error: the layout and the sweep disagree on one_group_rows or the device)");
  }

  // one sweep of a system above the one-group threshold: its runs or its colours
  void sweep_large(DemBuffers& b, int colours) {
    if (b.row_layout == RowLayout::Runs) {
      sweep_runs(b);
    } else {
      sweep_colours(b, colours);
    }
  }

  // one sweep over runs: level by level, each level's runs side by side (a work-group of one
  // item each; the in-order queue keeps the levels in turn), a level without rows skipped
  void sweep_runs(DemBuffers& b) {
    const int parts = b.run_parts;
    for (int level = 0; level < tl_run_levels(parts); ++level) {
      const int first = tl_run_first(parts, level);
      const int groups = tl_run_groups(parts, level);
      if (b.colour_start[first + groups] == b.colour_start[first]) continue;
      set_args(runs_, b.rows, b.impulses, b.colour_start_dev, first, b.velocity, b.omega);
      launch_walks(dev_, runs_, static_cast<size_t>(groups), "pgs_runs");
    }
  }

  // `sweeps` sweeps of every colour in one launch of one work-group
  void sweeps_in_one_group(DemBuffers& b, int colours, int sweeps) {
    set_args(one_group_, b.rows, b.impulses, b.colour_start_dev, colours, sweeps, b.velocity,
             b.omega);
    launch_group(dev_, one_group_, group_size_, "pgs_sweeps_one_group");
  }

  // one sweep: a launch per colour
  void sweep_colours(DemBuffers& b, int colours) {
    for (int k = 0; k < colours; ++k) {
      int begin = b.colour_start[k];
      int end = b.colour_start[k + 1];
      if (end == begin) continue;
      set_args(kernel_, b.rows, b.impulses, begin, end, b.velocity, b.omega);
      launch(dev_, kernel_, static_cast<size_t>(end - begin), "pgs_colour");
    }
  }

  // a one-group kernel's work-group: one item on a CPU device, else as many work-items as the
  // device allows it, at most kOneGroupSize
  size_t group_size(const cl::Kernel& kernel) const {
    if (dev_.is_cpu()) return 1;
    return std::min(kOneGroupSize, cl_checked("querying the sweep's work-group size", [&] {
                      return kernel.getWorkGroupInfo<CL_KERNEL_WORK_GROUP_SIZE>(dev_.device());
                    }));
  }

  Device& dev_;
  int one_group_rows_;
  cl::Kernel kernel_, one_group_, one_group_tools_, runs_;
  size_t group_size_ = 1, tools_group_size_ = 1;
};

}  // namespace

std::unique_ptr<ContactSweep> make_pgs_sweep(Device& dev, int one_group_rows) {
  return std::make_unique<PgsSweep>(dev, one_group_rows);
}

std::unique_ptr<ContactSweep> make_sweep(const DemSettings& settings, Device& dev, int particles) {
  if (settings.sweep == SweepKind::Pgs) return make_pgs_sweep(dev, settings.one_group_rows);
  return make_jacobi_sweep(dev, particles);
}

}  // namespace talus
