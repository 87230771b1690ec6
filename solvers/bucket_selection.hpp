// Device-side selection of the particles near the bucket (SPEC §1 step 3): only these go to
// the Embree closest-point queries on the host (solvers/bucket_contacts.hpp). The box is the
// bucket's world bounds grown by the largest radius and the contact margin, as the host
// selection BucketScene::select_candidates; float rounding is covered by growing it a further
// part per million, so the device never misses a particle the host would select.
#pragma once
#include <vector>

#include "host/device.hpp"
#include "host/scan.hpp"
#include "solvers/bucket_contacts.hpp"

namespace talus {

class DeviceBoxSelection {
 public:
  explicit DeviceBoxSelection(Device& dev);
  // indices of the first n particles of `position` (xyz centre, w radius) inside `box`, in order
  std::vector<int> select(const Buffer<cl_float4>& position, size_t n, const Aabb& box);

 private:
  Device& dev_;
  DeviceScan scan_;
  cl::Kernel flags_kernel_, compact_kernel_;
  Buffer<int> flags_, offsets_, selected_;
};

}  // namespace talus
