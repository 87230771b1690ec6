// Voxel beds shared by the type-G terrain's tests (active_zone, bucket_support).
#pragma once
#include <cmath>

#include "terrain/voxel_terrain.hpp"

namespace talus::test {

// a level bed `height` high at bank density on a square grid of cells h over [-3, 3] m in x and y,
// with a metre of room above it
inline VoxelTerrain level_bed(double h, double height) {
  const int n = static_cast<int>(std::lround(6.0 / h));
  VoxelTerrain t(-3.0, -3.0, 0.0, h, n, n, static_cast<int>(std::ceil((height + 1.0) / h)),
                 kFieldBulkDensity);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) t.deposit(i, j, height * h * h * kFieldBulkDensity, 1.0);
  return t;
}

}  // namespace talus::test
