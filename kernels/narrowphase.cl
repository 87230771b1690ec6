// Narrow phase: sphere-sphere and sphere-static contacts, grouped by owner particle a
// (the lower index of a pair), written at offsets from a prefix sum of per-particle counts.
// Enumeration order (27 cells in z,y,x order, particles in index order, then static
// geometry in index order) is fixed, so the contact list is deterministic.
// Static geometry comes from the list of the particle's (x, y) column of the grid (DemWorld's
// geometry bins): every geometry within a cell of the column, in index order, so the contacts
// are those of a loop over all of them, without testing the hundreds of voxel columns of the
// multiscale terrain (issue 14) against every particle.

// the margin below which a pair becomes a (possibly speculative) contact: the relative margin
// plus the speculative reach, the fastest particle's 2 h v_max for every pair, or (pair_reach)
// what this pair can close within the step, 2 h (its closing speed along n + |g| h), no more than
// that: a bed at rest makes no speculative rows, a grain falling onto it does
float contact_margin(float ra, float rb, float closing, const TlStepParams p) {
  float reach = p.speculative;
  if (p.pair_reach)
    reach = min(reach, 2.0f * p.dt * max(0.0f, closing + length(p.gravity.xyz) * p.dt));
  return p.margin_rel * min(ra, rb) + reach;
}

// finds where the previous step stored the pair (a, b); -1 when it is new
int find_previous(int a, int b, __global const int* prev_offsets, __global const TlContact* prev) {
  int begin = prev_offsets[a];
  int end = prev_offsets[a + 1];
  for (int k = begin; k < end; ++k)
    if (prev[k].b == b) return k;
  return -1;
}

// fills one contact, carrying over last step's impulses when the pair persists
void emit_contact(__global TlContact* out, int a, int b, float3 n, float gap, float3 arm_a,
                  float3 arm_b, float reduced_radius, const TlStepParams p,
                  __global const int* prev_offsets, __global const TlContact* prev, int has_prev) {
  TlContact c;
  c.normal = (float4)(n, gap);
  c.arm_a = (float4)(arm_a, reduced_radius);
  c.arm_b = (float4)(arm_b, hertz_stiffness(reduced_radius, p));
  c.impulse_t = (float4)(0.0f);
  c.impulse_r = (float4)(0.0f);
  c.a = a;
  c.b = b;
  c.pad1 = 0;
  // the same pair in last step's list (any flag set: that list is of these particles)
  int k = has_prev ? find_previous(a, b, prev_offsets, prev) : -1;
  c.previous = k;
  // which of last step's contacts give their impulses: particle pairs, static ones (their
  // geometry may have been renumbered: DemWorld::set_geoms), both or neither
  int match = b >= 0 ? (has_prev & TL_MATCH_PAIRS) : (has_prev & TL_MATCH_STATIC);
  if (match && k >= 0) {
    c.impulse_t = prev[k].impulse_t;
    c.impulse_r = prev[k].impulse_r;
  }
  *out = c;
}

// visits particle i's contacts; writes them when `write` is set, returns their number
// write mode stops at `limit` contacts (the count pass's number), so a pair that rounds
// differently between the passes can never write into the next particle's slots
int visit_contacts(int i, int write, int limit, __global const float4* position,
                   __global const float4* velocity, __global const int* cell_start,
                   __global const int* cell_particles, __global const TlGeom* geoms,
                   __global const int* geom_column_start, __global const int* geom_column_list,
                   const TlStepParams p, __global TlContact* out, __global const int* prev_offsets,
                   __global const TlContact* prev, int has_prev) {
  float4 pi = position[i];
  float3 xi = pi.xyz;
  float ri = pi.w;
  int3 ci = cell_of(xi, p);
  // fixed particles (zero inverse mass) need no rows among themselves or with static geometry
  int fixed_i = velocity[i].w == 0.0f;
  int count = 0;
  // particle pairs (i, j) with j > i in the 27 surrounding cells
  for (int dz = -1; dz <= 1; ++dz) {
    int z = ci.z + dz;
    if (z < 0 || z >= p.grid_nz) continue;
    for (int dy = -1; dy <= 1; ++dy) {
      int y = ci.y + dy;
      if (y < 0 || y >= p.grid_ny) continue;
      for (int dx = -1; dx <= 1; ++dx) {
        int x = ci.x + dx;
        if (x < 0 || x >= p.grid_nx) continue;
        int cell = cell_index((int3)(x, y, z), p);
        int end = cell_start[cell + 1];
        for (int k = cell_start[cell]; k < end; ++k) {
          int j = cell_particles[k];
          if (j <= i || (fixed_i && velocity[j].w == 0.0f)) continue;
          float4 pj = position[j];
          float3 d = pj.xyz - xi;
          // farther apart than the widest margin any pair can have (contact_margin's, with the
          // full speculative reach): no contact, rejected on the squared distance before the root,
          // the division and the velocities' loads. The 1e-4 slack is far above float rounding,
          // so the test below still decides every pair it could accept: the same contacts
          float widest = ri + pj.w + p.margin_rel * min(ri, pj.w) + p.speculative;
          if (dot(d, d) > 1.0001f * widest * widest) continue;
          float dist = length(d);
          float gap = dist - ri - pj.w;
          float3 n = dist > 0.0f ? d / dist : (float3)(0.0f, 0.0f, 1.0f);
          float closing = dot(velocity[i].xyz - velocity[j].xyz, n);
          if (gap >= contact_margin(ri, pj.w, closing, p)) continue;
          if (write && count >= limit) return count;
          if (write) {
            float reduced = ri * pj.w / (ri + pj.w);
            emit_contact(out + count, i, j, n, gap, n * (ri + 0.5f * gap), -n * (pj.w + 0.5f * gap),
                         reduced, p, prev_offsets, prev, has_prev);
          }
          ++count;
        }
      }
    }
  }
  // static geometry (walls, ground, boxes) near the particle's column, in index order
  int column = ci.y * p.grid_nx + ci.x;
  int geom_end = fixed_i ? 0 : geom_column_start[column + 1];
  for (int k = fixed_i ? 0 : geom_column_start[column]; k < geom_end; ++k) {
    int g = geom_column_list[k];
    float3 n;
    float gap = sphere_geom(xi, ri, geoms + g, &n);
    if (gap >= contact_margin(ri, ri, dot(velocity[i].xyz, n), p)) continue;
    if (write && count >= limit) return count;
    if (write)
      emit_contact(out + count, i, TL_STATIC_BODY(g), n, gap, n * (ri + 0.5f * gap),
                   (float3)(0.0f), ri, p, prev_offsets, prev, has_prev);
    ++count;
  }
  return count;
}

__kernel void contact_count(__global const float4* position, __global const float4* velocity,
                            __global const int* cell_start, __global const int* cell_particles,
                            __global const TlGeom* geoms, __global const int* geom_column_start,
                            __global const int* geom_column_list, __global int* counts,
                            __global TlContact* unused_out, __global const int* prev_offsets,
                            __global const TlContact* prev, const TlStepParams p) {
  int i = get_global_id(0);
  if (i >= p.particles) return;
  counts[i] =
      visit_contacts(i, 0, 0, position, velocity, cell_start, cell_particles, geoms,
                     geom_column_start, geom_column_list, p, unused_out, prev_offsets, prev, 0);
}

__kernel void contact_write(__global const float4* position, __global const float4* velocity,
                            __global const int* cell_start, __global const int* cell_particles,
                            __global const TlGeom* geoms, __global const int* geom_column_start,
                            __global const int* geom_column_list, __global const int* offsets,
                            __global TlContact* contacts, __global const int* prev_offsets,
                            __global const TlContact* prev, const TlStepParams p, int has_prev) {
  int i = get_global_id(0);
  if (i >= p.particles) return;
  visit_contacts(i, 1, offsets[i + 1] - offsets[i], position, velocity, cell_start, cell_particles,
                 geoms, geom_column_start, geom_column_list, p, contacts + offsets[i], prev_offsets,
                 prev, has_prev);
}

// contacts per body (both sides), for the body -> contact adjacency
__kernel void adjacency_count(__global const TlContact* contacts, int n_contacts,
                              __global int* degree) {
  int c = get_global_id(0);
  if (c >= n_contacts) return;
  atomic_inc(&degree[contacts[c].a]);
  if (contacts[c].b >= 0) atomic_inc(&degree[contacts[c].b]);
}

__kernel void adjacency_fill(__global const TlContact* contacts, int n_contacts,
                             __global const int* adj_offsets, __global int* fill,
                             __global int* adjacency) {
  int c = get_global_id(0);
  if (c >= n_contacts) return;
  int a = contacts[c].a;
  adjacency[adj_offsets[a] + atomic_inc(&fill[a])] = c;
  int b = contacts[c].b;
  if (b >= 0) adjacency[adj_offsets[b] + atomic_inc(&fill[b])] = c;
}

// each body's contact list in index order, so gathers sum in a fixed order
__kernel void adjacency_sort(__global const int* adj_offsets, __global int* adjacency, int bodies) {
  int i = get_global_id(0);
  if (i >= bodies) return;
  int begin = adj_offsets[i];
  int end = adj_offsets[i + 1];
  for (int k = begin + 1; k < end; ++k) {
    int v = adjacency[k];
    int m = k - 1;
    while (m >= begin && adjacency[m] > v) {
      adjacency[m + 1] = adjacency[m];
      --m;
    }
    adjacency[m + 1] = v;
  }
}
