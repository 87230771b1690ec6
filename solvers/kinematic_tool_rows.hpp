// The rows of kinematic tools solved a particle at a time (issue 14).
//
// A kinematic tool (mobility W = 0: the bucket of the type-G terrain, the cutting test's blade, the
// shear box's ring) moves as prescribed: its rows change their particles and never the tool. The
// serial walk of solvers/bucket_rows (BucketRowBlock, one work-item for all of a tool's rows, one
// launch per tool and sweep) is then a walk per particle in disguise: what a row does depends on
// its particle and the tool's fixed twist only. KinematicToolRows groups the rows of every
// kinematic tool by particle, keeping each particle's rows in the serial walk's order (tool by
// tool, row by row), and walks the groups a work-item each (kernels/bucket.cl
// kinematic_tool_sweep): the serial walk's arithmetic for every particle, so its results, with the
// rows spread over the device. A small system's sweeps and the tools' rows run in one launch
// (ContactSweep::iterate_with_tools, kernels/bucket.cl pgs_sweeps_one_group_tools).
#pragma once
#include <vector>

#include "host/device.hpp"
#include "kernels/common.h"
#include "kernels/dem_types.h"
#include "solvers/bucket_rows.hpp"

namespace talus {

class KinematicToolRows {
 public:
  explicit KinematicToolRows(Device& dev);

  // the rows of each tool (`a` already the particle's index in the whole system) and each tool's
  // twist (its mobility must be zero: InputError otherwise, naming the tool), replacing the last
  // step's; the rows are grouped by particle here
  void set(const std::vector<std::vector<TlRow>>& tool_rows, const std::vector<BucketBody>& tools);
  int rows() const { return static_cast<int>(tool_of_row_.size()); }
  // the particles that touch a tool (the groups)
  int groups() const { return groups_; }

  // each particle receives its rows' starting impulses (bucket_warm_start's bits)
  void warm_start(Buffer<cl_float4>& velocity, Buffer<cl_float4>& omega);
  // one sweep over the rows, a work-item per particle (bucket_sweep's bits, tool after tool)
  void sweep(Buffer<cl_float4>& velocity, Buffer<cl_float4>& omega);
  // the solved rows, back in each tool's order
  std::vector<std::vector<TlRow>> solved() const;

  // what the fused sweep reads (kernels/bucket.cl pgs_sweeps_one_group_tools)
  Buffer<TlRow>& row_buffer() { return rows_; }
  const Buffer<int>& group_start() const { return group_start_; }
  const Buffer<int>& row_tool() const { return row_tool_; }
  const Buffer<TlBucketBody>& tool_bodies() const { return tools_; }

 private:
  Device& dev_;
  Buffer<TlRow> rows_;
  Buffer<int> group_start_, row_tool_;
  Buffer<TlBucketBody> tools_;
  int groups_ = 0;
  // the grouped row k came from row row_of_row_[k] of tool tool_of_row_[k] (the device's
  // row_tool holds tool_of_row_ too)
  std::vector<int> tool_of_row_, row_of_row_;
  std::vector<size_t> tool_sizes_;
  cl::Kernel warm_kernel_, sweep_kernel_;
};

}  // namespace talus
