#include "solvers/kinematic_tool_rows.hpp"

#include <algorithm>
#include <string>

#include "host/error.hpp"
#include "solvers/contact_sweep.hpp"

namespace talus {

KinematicToolRows::KinematicToolRows(Device& dev)
    : dev_(dev), rows_(dev, 1), group_start_(dev, 1), row_tool_(dev, 1), tools_(dev, 1) {
  const cl::Program& program = dev.program(kSolverProgram);
  warm_kernel_ = dev.kernel(program, "kinematic_tool_warm_start");
  sweep_kernel_ = dev.kernel(program, "kinematic_tool_sweep");
}

void KinematicToolRows::set(const std::vector<std::vector<TlRow>>& tool_rows,
                            const std::vector<BucketBody>& tools) {
  if (tool_rows.size() != tools.size())
    throw InputError("kinematic tool rows: " + std::to_string(tool_rows.size()) +
                     " lists of rows for " + std::to_string(tools.size()) + " tools");
  for (size_t t = 0; t < tools.size(); ++t)
    if (!tools[t].mobility.isZero(0.0))
      throw InputError("tool " + std::to_string(t) +
                       ": a tool with a non-zero mobility is not kinematic; its rows move it, so "
                       "they are solved in one chain (BucketRowBlock)");
  // the serial walk's order: tool by tool, row by row, each row by its (tool, row) place
  struct Place {
    int tool, row;
  };
  std::vector<Place> walk;
  tool_sizes_.clear();
  for (size_t t = 0; t < tool_rows.size(); ++t) {
    tool_sizes_.push_back(tool_rows[t].size());
    for (size_t k = 0; k < tool_rows[t].size(); ++k)
      walk.push_back({static_cast<int>(t), static_cast<int>(k)});
  }
  // grouped by particle, each group in the walk's order (a stable sort)
  const auto particle = [&](const Place& x) { return tool_rows[x.tool][x.row].a; };
  std::stable_sort(walk.begin(), walk.end(),
                   [&](const Place& x, const Place& y) { return particle(x) < particle(y); });
  std::vector<TlRow> grouped;
  std::vector<int> start;
  grouped.reserve(walk.size());
  tool_of_row_.clear();
  row_of_row_.clear();
  for (size_t k = 0; k < walk.size(); ++k) {
    if (k == 0 || particle(walk[k]) != grouped.back().a) start.push_back(static_cast<int>(k));
    grouped.push_back(tool_rows[walk[k].tool][walk[k].row]);
    tool_of_row_.push_back(walk[k].tool);
    row_of_row_.push_back(walk[k].row);
  }
  start.push_back(static_cast<int>(grouped.size()));
  groups_ = static_cast<int>(start.size()) - 1;
  if (grouped.empty()) return;
  std::vector<TlBucketBody> bodies;
  bodies.reserve(tools.size());
  for (const BucketBody& b : tools) bodies.push_back(to_device(b));
  rows_.upload(grouped);
  group_start_.upload(start);
  row_tool_.upload(tool_of_row_);
  tools_.upload(bodies);
}

void KinematicToolRows::warm_start(Buffer<cl_float4>& velocity, Buffer<cl_float4>& omega) {
  if (groups_ == 0) return;
  set_args(warm_kernel_, rows_, group_start_, groups_, velocity, omega);
  launch(dev_, warm_kernel_, static_cast<size_t>(groups_), "kinematic_tool_warm_start");
}

void KinematicToolRows::sweep(Buffer<cl_float4>& velocity, Buffer<cl_float4>& omega) {
  if (groups_ == 0) return;
  set_args(sweep_kernel_, rows_, group_start_, groups_, row_tool_, tools_, velocity, omega);
  launch(dev_, sweep_kernel_, static_cast<size_t>(groups_), "kinematic_tool_sweep");
}

std::vector<std::vector<TlRow>> KinematicToolRows::solved() const {
  std::vector<std::vector<TlRow>> out(tool_sizes_.size());
  for (size_t t = 0; t < out.size(); ++t) out[t].resize(tool_sizes_[t]);
  if (tool_of_row_.empty()) return out;
  const std::vector<TlRow> grouped = rows_.download(tool_of_row_.size());
  for (size_t k = 0; k < grouped.size(); ++k) out[tool_of_row_[k]][row_of_row_[k]] = grouped[k];
  return out;
}

}  // namespace talus
