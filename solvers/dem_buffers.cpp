#include "solvers/dem_buffers.hpp"

#include <algorithm>

namespace talus {

DemBuffers::DemBuffers(Device& dev)
    : position(dev, 1),
      velocity(dev, 1),
      omega(dev, 1),
      rotation(dev, 1),
      geoms(dev, 1),
      geom_column_start(dev, 2),
      geom_column_list(dev, 1),
      particle_cell(dev, 1),
      cell_counts(dev, 1),
      cell_start(dev, 1),
      cell_fill(dev, 1),
      cell_particles(dev, 1),
      contact_counts(dev, 1),
      contact_partners(dev, 1),
      owner_offsets{Buffer<int>(dev, 1), Buffer<int>(dev, 1)},
      contacts{Buffer<TlContact>(dev, 1), Buffer<TlContact>(dev, 1)},
      degree(dev, 1),
      adjacency_offsets(dev, 1),
      adjacency_fill(dev, 1),
      adjacency(dev, 1),
      colour(dev, 1),
      colour_next(dev, 1),
      colour_status(dev, 1),
      colour_histogram(dev, 1),
      colour_offsets(dev, 1),
      colour_start_dev(dev, TL_MAX_COLOURS + 1),
      colour_previous(dev, 1),
      order(dev, 1),
      row_of_contact(dev, 1),
      part(dev, 1),
      by_part(dev, 1),
      pairs_differ(dev, 1),
      rows(dev, 1),
      impulses(dev, 1),
      delta_lin(dev, 1),
      delta_ang(dev, 1),
      residual(dev, 1),
      residual_block_sums(dev, 1),
      first_non_finite(dev, 1) {}

std::size_t DemBuffers::device_bytes() const {
  std::size_t sum = 0;
  for_each_buffer_bytes([&](std::size_t b) { sum += b; });
  return sum;
}

std::size_t DemBuffers::largest_buffer_bytes() const {
  std::size_t largest = 0;
  for_each_buffer_bytes([&](std::size_t b) { largest = std::max(largest, b); });
  return largest;
}

}  // namespace talus
