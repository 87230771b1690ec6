// Broad phase: a uniform grid built by counting sort. Particles of one cell end up
// contiguous and in index order, so the narrow phase enumerates pairs deterministically.

// cell of each particle, and the per-cell particle count (integer atomics: exact)
__kernel void cell_count(__global const float4* position, __global int* particle_cell,
                         __global int* cell_counts, const TlStepParams p) {
  int i = get_global_id(0);
  if (i >= p.particles) return;
  int cell = cell_index(cell_of(position[i].xyz, p), p);
  particle_cell[i] = cell;
  atomic_inc(&cell_counts[cell]);
}

// each particle takes a slot in its cell (slot order is arbitrary; cell_sort fixes it)
__kernel void cell_fill(__global const int* particle_cell, __global const int* cell_start,
                        __global int* cell_fill_count, __global int* cell_particles,
                        const TlStepParams p) {
  int i = get_global_id(0);
  if (i >= p.particles) return;
  int cell = particle_cell[i];
  int slot = atomic_inc(&cell_fill_count[cell]);
  cell_particles[cell_start[cell] + slot] = i;
}

// insertion sort of each occupied cell's few particles into index order
__kernel void cell_sort(__global const int* cell_start, __global int* cell_particles, int cells) {
  int cell = get_global_id(0);
  if (cell >= cells) return;
  int begin = cell_start[cell];
  int end = cell_start[cell + 1];
  for (int k = begin + 1; k < end; ++k) {
    int v = cell_particles[k];
    int m = k - 1;
    while (m >= begin && cell_particles[m] > v) {
      cell_particles[m + 1] = cell_particles[m];
      --m;
    }
    cell_particles[m + 1] = v;
  }
}
