// Device arrays of one DEM system, owned by DemWorld and shared with its stages and sweeps.
#pragma once
#include <array>
#include <cstddef>
#include <initializer_list>
#include <vector>

#include "host/device.hpp"
#include "kernels/common.h"
#include "kernels/dem_types.h"

namespace talus {

// how a step's rows are laid out for the PGS sweeps (DemWorld::colour_contacts):
// Colours: colour after colour, no dynamic body twice in a colour (any sweep may take them);
// Interleaved: one "colour" whose rows share bodies, for one work-item to walk
//   (DemSettings::serial_lanes);
// Runs: the runs of a large system's parts (kernels/dem_types.h tl_run_of), each interleaved
//   within itself, for a work-item per run to walk, level by level (DemSettings::sweep_parts):
//   colour_start holds the runs' rows
enum class RowLayout { Colours, Interleaved, Runs };

struct DemBuffers {
  explicit DemBuffers(Device& dev);
  // the device memory of every array below [bytes] (their capacities)
  std::size_t device_bytes() const;
  // the largest of them [bytes] (the rows of a dense packing): what one allocation must hold
  std::size_t largest_buffer_bytes() const;
  // f(bytes) for every device array below: the one list of them
  template <class F>
  void for_each_buffer_bytes(F&& f) const {
    for (std::size_t b : {position.bytes(),
                          velocity.bytes(),
                          omega.bytes(),
                          rotation.bytes(),
                          geoms.bytes(),
                          geom_column_start.bytes(),
                          geom_column_list.bytes(),
                          particle_cell.bytes(),
                          cell_counts.bytes(),
                          cell_start.bytes(),
                          cell_fill.bytes(),
                          cell_particles.bytes(),
                          contact_counts.bytes(),
                          contact_partners.bytes(),
                          owner_offsets[0].bytes(),
                          owner_offsets[1].bytes(),
                          contacts[0].bytes(),
                          contacts[1].bytes(),
                          degree.bytes(),
                          adjacency_offsets.bytes(),
                          adjacency_fill.bytes(),
                          adjacency.bytes(),
                          colour.bytes(),
                          colour_next.bytes(),
                          colour_previous.bytes(),
                          colour_status.bytes(),
                          colour_histogram.bytes(),
                          colour_offsets.bytes(),
                          colour_start_dev.bytes(),
                          order.bytes(),
                          row_of_contact.bytes(),
                          part.bytes(),
                          by_part.bytes(),
                          pairs_differ.bytes(),
                          rows.bytes(),
                          impulses.bytes(),
                          delta_lin.bytes(),
                          delta_ang.bytes(),
                          residual.bytes(),
                          residual_block_sums.bytes(),
                          first_non_finite.bytes()})
      f(b);
  }

  // particle state (layouts in kernels/dem_types.h)
  Buffer<cl_float4> position, velocity, omega, rotation;
  Buffer<TlGeom> geoms;
  // static geometry binned by the grid's (x, y) columns (CSR, each list in index order): the
  // geometries whose bounds, grown by one cell, reach the column (planes reach every column)
  Buffer<int> geom_column_start, geom_column_list;

  // broad phase: particle cell, per-cell counts and starts, particles sorted by cell
  Buffer<int> particle_cell, cell_counts, cell_start, cell_fill, cell_particles;

  // narrow phase: per-particle counts, owner offsets and contacts; [current] and [previous]
  Buffer<int> contact_counts;
  // each particle's first DemSettings::narrow_phase_slots partners found by the count pass (the
  // other particle, or TL_STATIC_BODY(geometry)), which the write pass writes from
  Buffer<int> contact_partners;
  std::array<Buffer<int>, 2> owner_offsets;
  std::array<Buffer<TlContact>, 2> contacts;
  int current = 0;          // which of the pairs above is this step's
  bool has_previous = false;
  // last step's static contacts may be matched too (false after DemWorld::set_geoms renumbered
  // the geometry: its particle pairs still warm start)
  bool static_previous = false;
  int n_contacts = 0;

  // body -> contact adjacency (CSR, each list in contact order)
  Buffer<int> degree, adjacency_offsets, adjacency_fill, adjacency;

  // colouring: colour per contact (-1 uncoloured) and the next round's copy; partition into rows
  Buffer<int> colour, colour_next, colour_status, colour_histogram, colour_offsets, colour_start_dev;
  // last step's colours, by its contact index: what this step's colouring carries (copied from
  // `colour` when a step ends, so a colouring redone within a step carries the same colours)
  Buffer<int> colour_previous;
  Buffer<int> order, row_of_contact;
  std::vector<int> colour_start;  // host copy: rows of colour k are [start[k], start[k+1])
  // how the rows are laid out (RowLayout); colour_start holds the colours' or the runs' rows
  RowLayout row_layout = RowLayout::Colours;
  // runs: the parts they were made for, each contact's run (kernels/colouring.cl contact_part)
  // and the contacts run after run in contact order, which the runs' interleaving reads
  int run_parts = 0;
  Buffer<int> part, by_part;
  int colour_rounds = 0;
  // set by kernels/colouring.cl contact_pairs_differ when this step's contacts pair other bodies
  // than the last step's (DemWorld keeps the colouring otherwise)
  Buffer<int> pairs_differ;

  // the particle rows, their impulses (kernels/dem_types.h TlParticleRow, TlImpulse) and the
  // Jacobi impulse changes
  Buffer<TlParticleRow> rows;
  Buffer<TlImpulse> impulses;
  Buffer<cl_float4> delta_lin, delta_ang;
  // each row's squared residual (-1 for a row that does not act: kernels/solver.cl
  // residual_entry), and per block their sum and the number of rows that act
  // (DemWorld::residual)
  Buffer<float> residual;
  Buffer<cl_float2> residual_block_sums;

  // the lowest index of a particle with a non-finite state (INT_MAX: none), checked every step
  Buffer<int> first_non_finite;
};

}  // namespace talus
