// Exclusive prefix sum of ints on the device (kernels/scan.cl), used to turn per-item counts
// into offsets. The output has n + 1 entries: offsets, then the total. A CPU device scans a short
// array in one work-item (scan_serial), anything else in blocks of TL_SCAN_GROUP work-items.
#pragma once
#include <deque>

#include "host/device.hpp"

namespace talus {

class DeviceScan {
 public:
  explicit DeviceScan(Device& dev);
  // out[0..n-1] = exclusive scan of in[0..n-1], out[n] = total; `in` and `out` may not alias.
  // Read out[n] with Buffer::read_one when the total is needed on the host.
  void exclusive(const Buffer<int>& in, Buffer<int>& out, size_t n);

 private:
  void scan_level(const cl::Buffer& in, const cl::Buffer& out, size_t n_in, size_t n_out,
                  size_t level);
  Device& dev_;
  cl::Kernel blocks_;
  cl::Kernel add_;
  cl::Kernel serial_;
  // per level: block totals and their scans (a deque keeps references valid as levels grow)
  std::deque<Buffer<int>> sums_;
  std::deque<Buffer<int>> offsets_;
};

}  // namespace talus
