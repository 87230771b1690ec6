#include "solvers/bucket_selection.hpp"

#include <algorithm>

#include "solvers/dem_world.hpp"

namespace talus {

namespace {
// relative growth of the box on the device: float centres are rounded to ~6e-8 relative, so a
// part per million of the box's size (plus its distance from the origin) keeps every particle
// the double-precision host test accepts
constexpr double kFloatSafety = 1e-6;
}  // namespace

DeviceBoxSelection::DeviceBoxSelection(Device& dev)
    : dev_(dev), scan_(dev), flags_(dev, 1), offsets_(dev, 1), selected_(dev, 1) {
  const cl::Program& program = dev.program({"selection.cl"});
  flags_kernel_ = dev.kernel(program, "box_flags");
  compact_kernel_ = dev.kernel(program, "box_compact");
}

std::vector<int> DeviceBoxSelection::select(const Buffer<cl_float4>& position, size_t n, const Aabb& box) {
  if (n == 0) return {};
  // grow the box by the float safety margin, then flag, scan and compact
  double scale = std::max(box.lo.cwiseAbs().maxCoeff(), box.hi.cwiseAbs().maxCoeff()) +
                 (box.hi - box.lo).maxCoeff();
  Vec3 pad = Vec3::Constant(kFloatSafety * scale);
  cl_float4 lo = to_float4(box.lo - pad, 0.0), hi = to_float4(box.hi + pad, 0.0);
  flags_.resize(n);
  set_args(flags_kernel_, position, static_cast<int>(n), lo, hi, flags_);
  launch(dev_, flags_kernel_, n, "box_flags");
  scan_.exclusive(flags_, offsets_, n);
  int count = offsets_.read_one(n);
  if (count == 0) return {};
  selected_.resize(count);
  set_args(compact_kernel_, flags_, offsets_, static_cast<int>(n), selected_);
  launch(dev_, compact_kernel_, n, "box_compact");
  return selected_.download(count);
}

}  // namespace talus
