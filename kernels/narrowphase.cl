// Narrow phase: sphere-sphere and sphere-static contacts, grouped by owner particle a
// (the lower index of a pair), written at offsets from a prefix sum of per-particle counts.
// Enumeration order (27 cells in z,y,x order, particles in index order, then static
// geometry in index order) is fixed, so the contact list is deterministic.
// Static geometry comes from the list of the particle's (x, y) column of the grid (DemWorld's
// geometry bins): every geometry within a cell of the column, in index order, so the contacts
// are those of a loop over all of them, without testing the hundreds of voxel columns of the
// multiscale terrain (issue 14) against every particle.
// The count pass keeps each particle's first `slots` partners (the other particle, or the static
// geometry as TL_STATIC_BODY) in its slots of `partners`; the write pass then writes a particle
// whose contacts all fit from that list alone, recomputing each contact with the same functions
// (the same bits), and visits the cells and the geometry again only for a particle with more
// (slots = 0: every particle with a contact visited twice, as before). At the type-G levels the
// second visit was half of the narrow phase (issue 14).

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

// the gap of particles at xi (radius ri) and pj (radius pj.w) and the normal from i to j
float pair_gap(float3 xi, float ri, float4 pj, float3* n) {
  float3 d = pj.xyz - xi;
  float dist = length(d);
  *n = dist > 0.0f ? d / dist : (float3)(0.0f, 0.0f, 1.0f);
  return dist - ri - pj.w;
}

// writes the contact of particles i and j (j > i)
void emit_pair(__global TlContact* out, int i, int j, float ri, float rj, float3 n, float gap,
               const TlStepParams p, __global const int* prev_offsets,
               __global const TlContact* prev, int has_prev) {
  float reduced = ri * rj / (ri + rj);
  emit_contact(out, i, j, n, gap, n * (ri + 0.5f * gap), -n * (rj + 0.5f * gap), reduced, p,
               prev_offsets, prev, has_prev);
}

// writes the contact of particle i with static geometry g
void emit_static(__global TlContact* out, int i, int g, float ri, float3 n, float gap,
                 const TlStepParams p, __global const int* prev_offsets,
                 __global const TlContact* prev, int has_prev) {
  emit_contact(out, i, TL_STATIC_BODY(g), n, gap, n * (ri + 0.5f * gap), (float3)(0.0f), ri, p,
               prev_offsets, prev, has_prev);
}

// visits particle i's contacts; writes them when `write` is set, returns their number
// write mode stops at `limit` contacts (the count pass's number), so a pair that rounds
// differently between the passes can never write into the next particle's slots; count mode
// keeps the first `slots` partners in `partners`
int visit_contacts(int i, int write, int limit, __global const float4* position,
                   __global const float4* velocity, __global const int* cell_start,
                   __global const int* cell_particles, __global const TlGeom* geoms,
                   __global const int* geom_column_start, __global const int* geom_column_list,
                   const TlStepParams p, __global TlContact* out, __global const int* prev_offsets,
                   __global const TlContact* prev, int has_prev, __global int* partners,
                   int slots) {
  float4 pi = position[i];
  float3 xi = pi.xyz;
  float ri = pi.w;
  int3 ci = cell_of(xi, p);
  // fixed particles (zero inverse mass) need no rows among themselves or with static geometry
  int fixed_i = velocity[i].w == 0.0f;
  int count = 0;
  // particle pairs (i, j) with j > i in the 27 surrounding cells. The cells are numbered x
  // fastest and their particles stored in cell order, so a row's three cells x-1, x, x+1 (those
  // inside the grid) are one run of cell_particles: nine runs, visited in the order of the 27
  // cells (z, y, x, then index), so the contacts and their order are the same
  int x_first = max(ci.x - 1, 0);
  int x_last = min(ci.x + 1, p.grid_nx - 1);
  for (int dz = -1; dz <= 1; ++dz) {
    int z = ci.z + dz;
    if (z < 0 || z >= p.grid_nz) continue;
    for (int dy = -1; dy <= 1; ++dy) {
      int y = ci.y + dy;
      if (y < 0 || y >= p.grid_ny) continue;
      int end = cell_start[cell_index((int3)(x_last, y, z), p) + 1];
      for (int k = cell_start[cell_index((int3)(x_first, y, z), p)]; k < end; ++k) {
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
        float3 n;
        float gap = pair_gap(xi, ri, pj, &n);
        float closing = dot(velocity[i].xyz - velocity[j].xyz, n);
        if (gap >= contact_margin(ri, pj.w, closing, p)) continue;
        if (write && count >= limit) return count;
        if (write)
          emit_pair(out + count, i, j, ri, pj.w, n, gap, p, prev_offsets, prev, has_prev);
        else if (count < slots)
          partners[count] = j;
        ++count;
      }
    }
  }
  // static geometry (walls, ground, boxes) near the particle's column, in index order
  int column = ci.y * p.grid_nx + ci.x;
  int geom_end = fixed_i ? 0 : geom_column_start[column + 1];
  // the widest margin a static contact can have (contact_margin's, with the full speculative
  // reach): a box beyond it (with sphere_geom_within's slack) is rejected before its normal, and
  // its INFINITY alone is told apart here, so every other box meets contact_margin as before
  float static_reach = p.margin_rel * ri + p.speculative;
  for (int k = fixed_i ? 0 : geom_column_start[column]; k < geom_end; ++k) {
    int g = geom_column_list[k];
    float3 n;
    float gap = sphere_geom_within(xi, ri, geoms + g, static_reach, &n);
    if (isinf(gap) || gap >= contact_margin(ri, ri, dot(velocity[i].xyz, n), p)) continue;
    if (write && count >= limit) return count;
    if (write)
      emit_static(out + count, i, g, ri, n, gap, p, prev_offsets, prev, has_prev);
    else if (count < slots)
      partners[count] = TL_STATIC_BODY(g);
    ++count;
  }
  return count;
}

__kernel void contact_count(__global const float4* position, __global const float4* velocity,
                            __global const int* cell_start, __global const int* cell_particles,
                            __global const TlGeom* geoms, __global const int* geom_column_start,
                            __global const int* geom_column_list, __global int* counts,
                            __global TlContact* unused_out, __global const int* prev_offsets,
                            __global const TlContact* prev, const TlStepParams p,
                            __global int* partners, int slots) {
  int i = get_global_id(0);
  if (i >= p.particles) return;
  counts[i] = visit_contacts(i, 0, 0, position, velocity, cell_start, cell_particles, geoms,
                             geom_column_start, geom_column_list, p, unused_out, prev_offsets, prev,
                             0, partners + (size_t)i * slots, slots);
}

__kernel void contact_write(__global const float4* position, __global const float4* velocity,
                            __global const int* cell_start, __global const int* cell_particles,
                            __global const TlGeom* geoms, __global const int* geom_column_start,
                            __global const int* geom_column_list, __global const int* offsets,
                            __global TlContact* contacts, __global const int* prev_offsets,
                            __global const TlContact* prev, const TlStepParams p, int has_prev,
                            __global const int* partners, int slots) {
  int i = get_global_id(0);
  if (i >= p.particles) return;
  int count = offsets[i + 1] - offsets[i];
  __global TlContact* out = contacts + offsets[i];
  // more contacts than slots: visit the cells and the geometry again
  if (count > slots) {
    visit_contacts(i, 1, count, position, velocity, cell_start, cell_particles, geoms,
                   geom_column_start, geom_column_list, p, out, prev_offsets, prev, has_prev, 0, 0);
    return;
  }
  // every partner is in the slots, in the visit's order: each contact recomputed as it found it
  float4 pi = position[i];
  __global const int* mine = partners + (size_t)i * slots;
  for (int k = 0; k < count; ++k) {
    int b = mine[k];
    float3 n;
    if (b >= 0) {
      float4 pj = position[b];
      float gap = pair_gap(pi.xyz, pi.w, pj, &n);
      emit_pair(out + k, i, b, pi.w, pj.w, n, gap, p, prev_offsets, prev, has_prev);
    } else {
      int g = TL_STATIC_BODY(b);  // the map is its own inverse: the geometry's index
      float gap = sphere_geom(pi.xyz, pi.w, geoms + g, &n);
      emit_static(out + k, i, g, pi.w, n, gap, p, prev_offsets, prev, has_prev);
    }
  }
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
