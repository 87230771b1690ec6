// Rows between particles and the bucket (SPEC §1 steps 3-6). The rows are made on the host from
// Embree's closest points (solvers/bucket_rows.cpp) and solved here inside every sweep, right
// after the particle rows. All bucket rows share one body, so they are solved one after another
// (one chain, walked by one work-item of a work-group that loads and stores it in chunks, below):
// the bucket's twist changes with every row through its articulated 6x6 mobility W (the vehicle
// seen from the bucket), which is what makes the coupling strong.
// Double-precision twins: solvers/bucket_rows.cpp (reference namespace).
// Built after solver.cl in one program (solvers/contact_sweep.hpp kSolverProgram): the fused sweep
// of kinematic tools at the end calls its pgs_colours_in_group.

// the candidates' state before the step, for the host's rows: centre and radius, velocity and
// inverse mass, angular velocity and inverse inertia
__kernel void bucket_gather(__global const int* index, int n, __global const float4* position,
                            __global const float4* velocity, __global const float4* omega,
                            __global float4* out_position, __global float4* out_velocity,
                            __global float4* out_omega) {
  int k = get_global_id(0);
  if (k >= n) return;
  int i = index[k];
  out_position[k] = position[i];
  out_velocity[k] = velocity[i];
  out_omega[k] = omega[i];
}

// The rows of one step are one chain: a row reads the bucket twist and the particle velocity the
// rows before it left. Walked by one work-item straight from global memory, every row waits for
// two dependent loads (the row, then its particle), about 1 us a row on a GPU, where that walk
// was 44 % of a D50 step (bench/RESULTS.md "GPU"). So the chain is walked in chunks: the
// work-group loads a chunk of rows and their particles' state into local memory together, one
// work-item walks the chunk there in order, and the work-group writes it back. A particle with
// several rows in a chunk is loaded once, into the slot of its first row there, and every later
// row of it uses that slot, so it sees what the earlier rows did, exactly as in the serial walk:
// the arithmetic and its order are the serial walk's, and the result does not depend on the chunk
// (the work-group size; tests/solvers/bucket_rows_test.cpp holds chunks of 1, 7 and 64 to it).

// the chunk of rows [base, base + count): rows, their particles' state, and each row's slot
// (the chunk position of its particle's first row in the chunk)
void bucket_chunk_load(__global const TlRow* rows, int base, int count,
                       __global const float4* velocity, __global const float4* omega,
                       __local TlRow* chunk_rows, __local float4* chunk_velocity,
                       __local float4* chunk_omega, __local int* chunk_particle,
                       __local int* chunk_slot) {
  int k = get_local_id(0);
  if (k < count) {
    TlRow row = rows[base + k];
    chunk_rows[k] = row;
    chunk_particle[k] = row.a;
    chunk_velocity[k] = velocity[row.a];
    chunk_omega[k] = omega[row.a];
  }
  barrier(CLK_LOCAL_MEM_FENCE);
  if (k < count) {
    int a = chunk_particle[k];
    int slot = k;
    for (int j = 0; j < k; ++j) {
      if (chunk_particle[j] == a) {
        slot = j;
        break;
      }
    }
    chunk_slot[k] = slot;
  }
  barrier(CLK_LOCAL_MEM_FENCE);
}

// each particle of the chunk written back once, from its slot; the barrier makes the writes
// visible to the next chunk's loads (one work-group: a global fence suffices)
void bucket_chunk_store_particles(int count, __global float4* velocity, __global float4* omega,
                                  __local const float4* chunk_velocity,
                                  __local const float4* chunk_omega,
                                  __local const int* chunk_particle,
                                  __local const int* chunk_slot) {
  int k = get_local_id(0);
  if (k < count && chunk_slot[k] == k) {
    velocity[chunk_particle[k]] = chunk_velocity[k];
    omega[chunk_particle[k]] = chunk_omega[k];
  }
  barrier(CLK_GLOBAL_MEM_FENCE | CLK_LOCAL_MEM_FENCE);
}

// one row's starting impulses on its particle (w: inverse mass and inertia)
void bucket_row_warm_start(TlRow row, float4* velocity, float4* omega) {
  float3 P = TOOL_ROW_IMPULSE_N(row) * row.normal.xyz + row.impulse_t.xyz;
  float4 va = *velocity;
  float4 wa = *omega;
  *velocity = (float4)(va.xyz - va.w * P, va.w);
  *omega = (float4)(wa.xyz - wa.w * (cross(row.arm_a.xyz, P) + row.impulse_r.xyz), wa.w);
}

// warm start: each particle receives the impulses its bucket rows start from (the bucket's
// share is already in its twist: the vehicle was solved with their wrench). A chain: a particle
// may touch the bucket more than once. Launched as one work-group.
__kernel void bucket_warm_start(__global const TlRow* rows, int n_rows, __global float4* velocity,
                                __global float4* omega, __local TlRow* chunk_rows,
                                __local float4* chunk_velocity, __local float4* chunk_omega,
                                __local int* chunk_particle, __local int* chunk_slot) {
  int chunk = get_local_size(0);
  for (int base = 0; base < n_rows; base += chunk) {
    int count = min(chunk, n_rows - base);
    bucket_chunk_load(rows, base, count, velocity, omega, chunk_rows, chunk_velocity, chunk_omega,
                      chunk_particle, chunk_slot);
    // one work-item applies the chunk's rows in order
    if (get_local_id(0) == 0) {
      for (int k = 0; k < count; ++k) {
        int s = chunk_slot[k];
        float4 va = chunk_velocity[s];
        float4 wa = chunk_omega[s];
        bucket_row_warm_start(chunk_rows[k], &va, &wa);
        chunk_velocity[s] = va;
        chunk_omega[s] = wa;
      }
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    bucket_chunk_store_particles(count, velocity, omega, chunk_velocity, chunk_omega,
                                 chunk_particle, chunk_slot);
  }
}

// The chain's latency is what a GPU pays for (one work-item, each row waiting for the last):
// every bucket impulse moved the twist by W [p; arm_b x p], a cross product then a 6x6 product,
// three times a row. The row's own part of that does not depend on the chain: G = W J_b^T, the
// twist change per unit impulse at the row's contact point (6x3, J_b^T = [I; [arm_b]x]), and
// G n for its normal. So the work-group forms them for the whole chunk in parallel while loading
// it (bucket_chunk_coupling), and the chain is left with 6 products for the normal, 6 dot
// products of 3 for friction and for rolling (the last three columns of W). Each row's G is the
// same whatever the chunk, so the walk stays independent of the work-group size.
#define TL_COUPLING_FLOATS 24  // G row-major (18 floats), then G n (6)

// G = W J_b^T and G n of a row at lever arm b with normal n (W row-major, 36 floats)
void bucket_coupling(const float* W, float3 b, float3 n, float* g) {
  // column c of J_b^T: [e_c; arm_b x e_c]
  float3 r[3] = {(float3)(0.0f, b.z, -b.y), (float3)(-b.z, 0.0f, b.x), (float3)(b.y, -b.x, 0.0f)};
  for (int i = 0; i < 6; ++i) {
    float3 w_lin = (float3)(W[6 * i], W[6 * i + 1], W[6 * i + 2]);
    float3 w_ang = (float3)(W[6 * i + 3], W[6 * i + 4], W[6 * i + 5]);
    float3 gi = w_lin + (float3)(dot(w_ang, r[0]), dot(w_ang, r[1]), dot(w_ang, r[2]));
    g[3 * i] = gi.x;
    g[3 * i + 1] = gi.y;
    g[3 * i + 2] = gi.z;
    g[18 + i] = dot(gi, n);
  }
}

// G = W J_b^T and G n of each row of the chunk, one work-item a row
void bucket_chunk_coupling(int count, __global const TlBucketBody* bucket,
                           __local const TlRow* chunk_rows, __local float* chunk_coupling) {
  int k = get_local_id(0);
  if (k < count) {
    float W[36];
    for (int i = 0; i < 36; ++i) W[i] = bucket->mobility[i];
    float g[TL_COUPLING_FLOATS];
    bucket_coupling(W, chunk_rows[k].arm_b.xyz, chunk_rows[k].normal.xyz, g);
    for (int i = 0; i < TL_COUPLING_FLOATS; ++i) chunk_coupling[TL_COUPLING_FLOATS * k + i] = g[i];
  }
  barrier(CLK_LOCAL_MEM_FENCE);
}

// the twist change of the 6x3 matrix M (row-major, rows `stride` floats apart) times x
void bucket_twist_change3(const float* M, int stride, float3 x, float3* dv, float3* dw) {
  float y[6];
  for (int i = 0; i < 6; ++i)
    y[i] = M[stride * i] * x.x + M[stride * i + 1] * x.y + M[stride * i + 2] * x.z;
  *dv += (float3)(y[0], y[1], y[2]);
  *dw += (float3)(y[3], y[4], y[5]);
}

// one row against the bucket: normal, friction, then rolling, as kernels/solver.cl
// solve_contact, with the bucket's side through W instead of a diagonal mass (G and G n of the
// row above, the rolling part through W's last three columns). The row's impulses, the
// particle's velocity and omega (w: inverse mass and inertia) and the bucket's twist are
// updated in place. A kinematic tool (`moves` 0, a literal where it is inlined) skips the
// twist's updates, which for W = 0 add zero products: W and G are not read (may be null) and
// the twist stays as given, up to the sign of a zero (issue 14: a fifth of the type-G sweeps'
// time went to those products and to zeroing W and G for every particle and sweep)
TL_INLINE void tool_row_solve(TlRow* row, float4* velocity, float4* omega, const float* W,
                              const float* G, float3* vb, float3* wb, int moves) {
  float3 va = velocity->xyz, wa = omega->xyz;
  float ima = velocity->w, iia = omega->w;
  float3 n = row->normal.xyz;
  float3 arm_a = row->arm_a.xyz;
  float3 arm_b = row->arm_b.xyz;
  float ln = TOOL_ROW_IMPULSE_N(*row);

  // normal: the bucket's point velocity against the particle's (its arm is along n); the
  // bucket holds no tensile impulse
  float un = dot(n, *vb + cross(*wb, arm_b) - va);
  float ln_new =
      normal_impulse(ln, TOOL_ROW_RHS(*row), un, TOOL_ROW_SIGMA(*row), TOOL_ROW_INV_DN(*row), 0.0f);
  float dln = ln_new - ln;
  va -= ima * dln * n;
  if (moves) {
    *vb += dln * (float3)(G[18], G[19], G[20]);
    *wb += dln * (float3)(G[21], G[22], G[23]);
  }
  ln = ln_new;

  // friction on the disc mu lambda_n
  float3 u = (*vb + cross(*wb, arm_b)) - (va + cross(wa, arm_a));
  float3 ut = u - dot(u, n) * n;
  float3 lt = row->impulse_t.xyz;
  float3 lt_new = friction_impulse(lt, ut, TOOL_ROW_INV_DT(*row), TOOL_ROW_FRICTION(*row) * ln);
  float3 dlt = lt_new - lt;
  va -= ima * dlt;
  wa -= iia * cross(arm_a, dlt);
  if (moves) bucket_twist_change3(G, 3, dlt, vb, wb);

  // rolling (on the disc) and twist (about n), both bounded by mu_r R* lambda_n
  float3 wrel = *wb - wa;
  float3 lr = row->impulse_r.xyz;
  float3 lr_new =
      rolling_impulse(lr, wrel, n, TOOL_ROW_INV_DR(*row), TOOL_ROW_ROLLING_LIMIT(*row) * ln);
  float3 dlr = lr_new - lr;
  wa -= iia * dlr;
  if (moves) bucket_twist_change3(W + 3, 6, dlr, vb, wb);

  row->impulse_t = (float4)(lt_new, ln);
  row->impulse_r = (float4)(lr_new, TOOL_ROW_INV_DT(*row));
  *velocity = (float4)(va, ima);
  *omega = (float4)(wa, iia);
}

// one row against the loaded bucket (its mobility W, the row's coupling G)
void bucket_row_solve(TlRow* row, float4* velocity, float4* omega, const float* W, const float* G,
                      float3* vb, float3* wb) {
  tool_row_solve(row, velocity, omega, W, G, vb, wb, 1);
}

// one sweep over the bucket rows in order (bucket_row_solve each), chunk by chunk as above.
// Launched as one work-group; the bucket's twist lives in work-item 0 for the whole sweep.
__kernel void bucket_sweep(__global TlRow* rows, int n_rows, __global float4* velocity,
                           __global float4* omega, __global TlBucketBody* bucket,
                           __local TlRow* chunk_rows, __local float4* chunk_velocity,
                           __local float4* chunk_omega, __local int* chunk_particle,
                           __local int* chunk_slot, __local float* chunk_coupling) {
  int chunk = get_local_size(0);
  int k = get_local_id(0);
  float W[36];
  float3 vb = (float3)(0.0f), wb = (float3)(0.0f);
  if (k == 0) {
    for (int i = 0; i < 36; ++i) W[i] = bucket->mobility[i];
    vb = bucket->velocity.xyz;
    wb = bucket->omega.xyz;
  }
  for (int base = 0; base < n_rows; base += chunk) {
    int count = min(chunk, n_rows - base);
    bucket_chunk_load(rows, base, count, velocity, omega, chunk_rows, chunk_velocity, chunk_omega,
                      chunk_particle, chunk_slot);
    bucket_chunk_coupling(count, bucket, chunk_rows, chunk_coupling);
    // one work-item walks the chunk's rows in order
    if (k == 0) {
      for (int j = 0; j < count; ++j) {
        TlRow row = chunk_rows[j];
        int s = chunk_slot[j];
        float4 va = chunk_velocity[s];
        float4 wa = chunk_omega[s];
        float G[TL_COUPLING_FLOATS];
        for (int i = 0; i < TL_COUPLING_FLOATS; ++i)
          G[i] = chunk_coupling[TL_COUPLING_FLOATS * j + i];
        bucket_row_solve(&row, &va, &wa, W, G, &vb, &wb);
        chunk_rows[j].impulse_t = row.impulse_t;
        chunk_rows[j].impulse_r = row.impulse_r;
        chunk_velocity[s] = va;
        chunk_omega[s] = wa;
      }
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    // the rows' impulses and the particles back to global memory
    if (k < count) {
      rows[base + k].impulse_t = chunk_rows[k].impulse_t;
      rows[base + k].impulse_r = chunk_rows[k].impulse_r;
    }
    bucket_chunk_store_particles(count, velocity, omega, chunk_velocity, chunk_omega,
                                 chunk_particle, chunk_slot);
  }
  if (k == 0) {
    bucket->velocity = (float4)(vb, 0.0f);
    bucket->omega = (float4)(wb, 0.0f);
  }
}

// The coloured walk (CouplingSettings::bucket_sweep Coloured, issue 13): the same rows without a
// chain of all of them. Colour c holds each particle's c-th row (solvers/bucket_rows
// colour_bucket_rows), so the rows of a colour share no particle and can be solved at once, one
// work-item a row, against the twist the colour started from. They all push the bucket, so each
// sees it split among the colour's s rows (mass splitting, Tonge et al. 2012): a row solves
// against its own copy of the bucket with mobility s W (its effective masses were made with s W on
// the host), and the bucket moves by the mean of the copies' changes, (1/s) sum of s W J^T dlambda
// = W times the colour's total impulse, so the twist still follows W exactly as the direct solve
// does. Colours run one after another (Gauss-Seidel between them); the copies' changes are summed
// chunk by chunk by a tree in local memory, in an order fixed by the work-group size alone, so a
// device and work-group size give the same bits on every run. Launched as one work-group whose
// size is a power of two.

// the sum of `sums`' first 6 x size floats into its first 6 (work-item k's 6 at 6 k), a tree of
// halvings: the same additions in the same order whatever the timing
void bucket_twist_sum(__local float* sums) {
  int k = get_local_id(0);
  for (int span = get_local_size(0) / 2; span > 0; span /= 2) {
    barrier(CLK_LOCAL_MEM_FENCE);
    if (k < span)
      for (int i = 0; i < 6; ++i) sums[6 * k + i] += sums[6 * (k + span) + i];
  }
  barrier(CLK_LOCAL_MEM_FENCE);
}

// the warm start, colour by colour: a colour's rows touch distinct particles
__kernel void bucket_warm_start_coloured(__global const TlRow* rows,
                                         __global const int* colour_start, int colours,
                                         __global float4* velocity, __global float4* omega) {
  int size = get_local_size(0);
  for (int c = 0; c < colours; ++c) {
    int end = colour_start[c + 1];
    for (int r = colour_start[c] + get_local_id(0); r < end; r += size) {
      TlRow row = rows[r];
      float4 va = velocity[row.a];
      float4 wa = omega[row.a];
      bucket_row_warm_start(row, &va, &wa);
      velocity[row.a] = va;
      omega[row.a] = wa;
    }
    // the colour's particles seen by the next colour's rows
    barrier(CLK_GLOBAL_MEM_FENCE);
  }
}

// one sweep over the rows colour by colour, each colour's rows at once against split copies of
// the bucket; `sums` holds 6 floats a work-item
__kernel void bucket_sweep_coloured(__global TlRow* rows, __global const int* colour_start,
                                    int colours, __global float4* velocity, __global float4* omega,
                                    __global TlBucketBody* bucket, __local float* sums) {
  int k = get_local_id(0);
  int size = get_local_size(0);
  // every work-item holds the twist and does the same additions to it: the same bits in all
  float3 vb = bucket->velocity.xyz, wb = bucket->omega.xyz;
  for (int c = 0; c < colours; ++c) {
    int begin = colour_start[c];
    int end = colour_start[c + 1];
    // the split: the colour's rows share the bucket, each sees its mobility s W
    float s = (float)(end - begin);
    float W[36];
    for (int i = 0; i < 36; ++i) W[i] = s * bucket->mobility[i];
    float3 dv = (float3)(0.0f), dw = (float3)(0.0f);
    for (int base = begin; base < end; base += size) {
      int r = base + k;
      float d[6] = {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f};
      if (r < end) {
        TlRow row = rows[r];
        float4 va = velocity[row.a];
        float4 wa = omega[row.a];
        // the copy's coupling s G
        float G[TL_COUPLING_FLOATS];
        bucket_coupling(W, row.arm_b.xyz, row.normal.xyz, G);
        float3 vk = vb, wk = wb;
        bucket_row_solve(&row, &va, &wa, W, G, &vk, &wk);
        rows[r].impulse_t = row.impulse_t;
        rows[r].impulse_r = row.impulse_r;
        velocity[row.a] = va;
        omega[row.a] = wa;
        // the copy's change, shared out: the bucket's is the mean over the colour
        float3 ev = (vk - vb) / s, ew = (wk - wb) / s;
        d[0] = ev.x;
        d[1] = ev.y;
        d[2] = ev.z;
        d[3] = ew.x;
        d[4] = ew.y;
        d[5] = ew.z;
      }
      for (int i = 0; i < 6; ++i) sums[6 * k + i] = d[i];
      bucket_twist_sum(sums);
      dv += (float3)(sums[0], sums[1], sums[2]);
      dw += (float3)(sums[3], sums[4], sums[5]);
      // every work-item has read the chunk's sum before the next chunk writes its own
      barrier(CLK_LOCAL_MEM_FENCE);
    }
    vb += dv;
    wb += dw;
    // the colour's particles seen by the next colour's rows
    barrier(CLK_GLOBAL_MEM_FENCE);
  }
  if (k == 0) {
    bucket->velocity = (float4)(vb, 0.0f);
    bucket->omega = (float4)(wb, 0.0f);
  }
}

// Kinematic tools (mobility W = 0: the type-G bucket, the cutting blade, the shear ring): the
// particles cannot move the tool, so a row changes its particle alone and the rows of different
// particles do not depend on one another. The serial walk above is then only a walk per particle:
// each particle's rows (of every kinematic tool, in the walk's order: tool by tool, row by row)
// are a group, and a work-item per group walks them with tool_row_solve, W and G not read and the
// tool's twist as given (the serial walk adds W's zero products to it). The particle's arithmetic
// is the serial walk's, so the results are its bits (up to the sign of a zero velocity), with as
// many work-items as particles touch a tool (solvers/kinematic_tool_rows).
//   rows: grouped by particle, group g is [group_start[g], group_start[g + 1]);
//   row_tool: each row's tool, an index into tools (their twists; their mobility is not read)

// walks group g: its particle's state in registers, each row against its tool's twist
void kinematic_group_sweep(int g, __global TlRow* rows, __global const int* group_start,
                           __global const int* row_tool, __global const TlBucketBody* tools,
                           __global float4* velocity, __global float4* omega) {
  int begin = group_start[g];
  int end = group_start[g + 1];
  int a = rows[begin].a;
  float4 va = velocity[a];
  float4 wa = omega[a];
  for (int r = begin; r < end; ++r) {
    TlRow row = rows[r];
    float3 vb = tools[row_tool[r]].velocity.xyz;
    float3 wb = tools[row_tool[r]].omega.xyz;
    // a kinematic tool: no mobility, no coupling, the twist as given
    tool_row_solve(&row, &va, &wa, 0, 0, &vb, &wb, 0);
    rows[r].impulse_t = row.impulse_t;
    rows[r].impulse_r = row.impulse_r;
  }
  velocity[a] = va;
  omega[a] = wa;
}

// the warm start of the kinematic tools' rows, a work-item per particle
__kernel void kinematic_tool_warm_start(__global const TlRow* rows, __global const int* group_start,
                                        int groups, __global float4* velocity,
                                        __global float4* omega) {
  int g = get_global_id(0);
  if (g >= groups) return;
  int begin = group_start[g];
  int end = group_start[g + 1];
  int a = rows[begin].a;
  float4 va = velocity[a];
  float4 wa = omega[a];
  for (int r = begin; r < end; ++r) bucket_row_warm_start(rows[r], &va, &wa);
  velocity[a] = va;
  omega[a] = wa;
}

// one sweep over the kinematic tools' rows, a work-item per particle
__kernel void kinematic_tool_sweep(__global TlRow* rows, __global const int* group_start,
                                   int groups, __global const int* row_tool,
                                   __global const TlBucketBody* tools, __global float4* velocity,
                                   __global float4* omega) {
  int g = get_global_id(0);
  if (g >= groups) return;
  kinematic_group_sweep(g, rows, group_start, row_tool, tools, velocity, omega);
}

// `iterations` sweeps of a small system in one work-group, each over the particle rows' colours
// (kernels/solver.cl pgs_sweeps_one_group) and then the kinematic tools' rows: the bits of a
// launch per colour and a kinematic_tool_sweep launch per sweep, in one launch instead of
// (colours + 1) x iterations (the type-G step: 2 x iterations launches before, issue 14)
__kernel void pgs_sweeps_one_group_tools(
    __global const TlParticleRow* rows, __global TlImpulse* impulses,
    __global const int* colour_start, int colours, int iterations, __global float4* velocity,
    __global float4* omega, __global TlRow* tool_rows, __global const int* group_start, int groups,
    __global const int* row_tool, __global const TlBucketBody* tools) {
  int lid = get_local_id(0);
  int size = get_local_size(0);
  for (int it = 0; it < iterations; ++it) {
    pgs_colours_in_group(rows, impulses, colour_start, colours, velocity, omega);
    for (int g = lid; g < groups; g += size)
      kinematic_group_sweep(g, tool_rows, group_start, row_tool, tools, velocity, omega);
    // the tools' changes seen by the whole group before the next sweep's colours
    barrier(CLK_GLOBAL_MEM_FENCE);
  }
}
