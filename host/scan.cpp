#include "host/scan.hpp"

#include <string>

#include "host/error.hpp"
#include "kernels/common.h"

namespace talus {

namespace {
// the items one work-group scans (kernels/common.h)
constexpr size_t kScanBlockItems = size_t{TL_SCAN_GROUP} * TL_SCAN_ITEMS;
// the longest scan a CPU device runs item after item in one work-item (scan_serial); longer ones
// take the blocks, whose groups spread over the device's threads
constexpr size_t kSerialScanItems = 32 * kScanBlockItems;
}

DeviceScan::DeviceScan(Device& dev) : dev_(dev) {
  const cl::Program& program = dev.program({"scan.cl"});
  blocks_ = dev.kernel(program, "scan_blocks");
  add_ = dev.kernel(program, "scan_add_offsets");
  serial_ = dev.kernel(program, "scan_serial");
  // the kernels scan in groups of exactly TL_SCAN_GROUP work-items
  for (const cl::Kernel* k : {&blocks_, &add_}) {
    const size_t most = cl_checked("querying the scan's work-group size", [&] {
      return k->getWorkGroupInfo<CL_KERNEL_WORK_GROUP_SIZE>(dev.device());
    });
    if (most < TL_SCAN_GROUP)
      throw Error("the prefix sum needs work-groups of " + std::to_string(TL_SCAN_GROUP) +
                  " work-items and the device " + dev.description() + " allows " +
                  std::to_string(most) + " for it; lower TL_SCAN_GROUP in kernels/common.h");
  }
}

void DeviceScan::exclusive(const Buffer<int>& in, Buffer<int>& out, size_t n) {
  // n + 1 outputs: the kernel reads item n as zero, so out[n] is the total
  out.resize(n + 1);
  // a short scan on a CPU device: one work-item, no barriers (the same sums: integers are exact)
  if (dev_.is_cpu() && n + 1 <= kSerialScanItems) {
    cl_checked("scan_serial", [&] {
      serial_.setArg(0, in.raw());
      serial_.setArg(1, out.raw());
      serial_.setArg(2, static_cast<int>(n));
      serial_.setArg(3, static_cast<int>(n + 1));
      return dev_.queue().enqueueNDRangeKernel(serial_, cl::NullRange, cl::NDRange(1),
                                               cl::NDRange(1));
    });
    return;
  }
  scan_level(in.raw(), out.raw(), n, n + 1, 0);
}

void DeviceScan::scan_level(const cl::Buffer& in, const cl::Buffer& out, size_t n_in, size_t n_out,
                            size_t level) {
  size_t blocks = (n_out + kScanBlockItems - 1) / kScanBlockItems;
  while (sums_.size() <= level) sums_.emplace_back(dev_, 1);
  while (offsets_.size() <= level) offsets_.emplace_back(dev_, 1);
  Buffer<int>& sums = sums_[level];
  sums.resize(blocks);
  cl_checked("scan_blocks", [&] {
    blocks_.setArg(0, in);
    blocks_.setArg(1, out);
    blocks_.setArg(2, sums.raw());
    blocks_.setArg(3, static_cast<int>(n_in));
    blocks_.setArg(4, static_cast<int>(n_out));
    return dev_.queue().enqueueNDRangeKernel(
        blocks_, cl::NullRange, cl::NDRange(blocks * TL_SCAN_GROUP), cl::NDRange(TL_SCAN_GROUP));
  });
  if (blocks == 1) return;
  // scan the block totals, then add each block's offset to its items
  Buffer<int>& offs = offsets_[level];
  offs.resize(blocks);
  scan_level(sums.raw(), offs.raw(), blocks, blocks, level + 1);
  cl_checked("scan_add_offsets", [&] {
    add_.setArg(0, out);
    add_.setArg(1, offs.raw());
    add_.setArg(2, static_cast<int>(n_out));
    return dev_.queue().enqueueNDRangeKernel(
        add_, cl::NullRange, cl::NDRange(blocks * TL_SCAN_GROUP), cl::NDRange(TL_SCAN_GROUP));
  });
}

}  // namespace talus
