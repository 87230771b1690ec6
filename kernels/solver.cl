// Contact rows (SPOOK with Hertz compliance, Coulomb friction on the disc, rolling resistance)
// and the two sweep strategies over them: graph-coloured projected Gauss-Seidel and projected
// Jacobi with mass splitting. Every kernel has a double-precision twin in solvers/dem_reference.

// the row of a contact: effective masses, SPOOK right-hand side, warm-start impulses
__kernel void prepare_rows(__global const TlContact* contacts, __global const int* order,
                           int n_rows, __global const float4* velocity,
                           __global const float4* omega, __global TlParticleRow* rows,
                           __global TlImpulse* impulses, const TlStepParams p, int warm_start) {
  int k = get_global_id(0);
  if (k >= n_rows) return;
  int c = order[k];
  TlContact con = contacts[c];
  float h = p.dt;
  float3 n = con.normal.xyz;
  float gap = con.normal.w;
  float reduced = con.arm_a.w;
  float kn = con.arm_b.w;
  float4 va = velocity[con.a];
  float4 wa = omega[con.a];
  float4 vb = con.b >= 0 ? velocity[con.b] : (float4)(0.0f);
  float4 wb = con.b >= 0 ? omega[con.b] : (float4)(0.0f);

  // normal velocity before the step, and the overlap predicted at its end
  float un = dot(n, vb.xyz - va.xyz);
  float overlap = fmax(fmax(-gap, -gap - h * un), p.overlap_floor_rel * reduced);
  // secant Hertz compliance epsilon = 1 / (k_n sqrt(overlap)), SPOOK coefficients. The same
  // row serves speculative contacts (gap > 0): with damping (tau > 0) it brakes an approach
  // that would close more than about half the gap within the step, which loses impact energy
  // before touch; the gravel has zero restitution, and a rigid G v+ >= -g/h row instead would
  // stop every approach dead at touch (no elastic impact at all, see docs/dem.md)
  float compliance = 1.0f / (kn * sqrt(overlap));
  float upsilon = 1.0f / (1.0f + 4.0f * p.damping_tau / h);
  float sigma = 4.0f * compliance * upsilon / (h * h);
  float rhs = -(4.0f / h) * upsilon * gap + upsilon * un;

  // effective masses: lever arms lie along n (one signed length each), so normal rows see no
  // rotation and the friction row's arms add their squares
  float inv_m = va.w + vb.w;
  float arm_a = dot(con.arm_a.xyz, n);
  float arm_b = dot(con.arm_b.xyz, n);
  float d_t = inv_m + wa.w * (arm_a * arm_a) + wb.w * (arm_b * arm_b);
  float d_r = wa.w + wb.w;

  // cohesion: a particle pair closer than margin_rel R* (a liquid bridge's reach; half the narrow
  // phase's margin for equal spheres) holds a tensile impulse up to h F_c, F_c = cohesion R*^2.
  // A reach, not touch, since
  // the compliant row holds a pulled pair a hair apart (gap = eps F_c > 0). A speculative contact
  // further apart, or one with the ground, a wall or the bucket, holds none: a bond breaks when
  // the pair separates
  float cohesion = con.b >= 0 && gap <= p.margin_rel * reduced ? h * p.cohesion * reduced * reduced : 0.0f;
  // rolling resistance: between grains the gravel's, against static geometry the ground's
  float rolling = con.b >= 0 ? p.rolling : p.ground_rolling;

  // warm start: last step's impulses carried into the new frame, within the new cones
  float ln = 0.0f;
  float3 lt = (float3)(0.0f);
  float3 lr = (float3)(0.0f);
  if (warm_start) {
    ln = fmax(con.impulse_t.w, -cohesion);
    float3 old_t = con.impulse_t.xyz;
    float mag = length(old_t);
    float3 proj = old_t - dot(old_t, n) * n;
    float pm = length(proj);
    lt = pm > 0.0f ? proj * (fmin(mag, p.friction * (ln + cohesion)) / pm) : (float3)(0.0f);
    // rolling: the tangential part onto the new disc, the twist about the new normal clamped
    float3 old_r = con.impulse_r.xyz;
    float rmax = rolling * reduced * (ln + cohesion);
    float twist = clamp(dot(old_r, n), -rmax, rmax);
    float3 roll = old_r - dot(old_r, n) * n;
    float rm = length(roll);
    if (rm > rmax) roll *= rmax / rm;
    lr = roll + twist * n;
  }

  // the inverse effective masses times the relaxation: every projected step of the sweeps is
  // omega times Gauss-Seidel's (projected SOR; omega = 1 is PGS, the same bits as 1/D where the
  // division is correctly rounded, as on PoCL)
  float omega_sor = p.relaxation;
  TlParticleRow row;
  row.normal = (float4)(n, rhs);
  row.mass = (float4)(omega_sor / (inv_m + sigma), sigma, d_t > 0.0f ? omega_sor / d_t : 0.0f,
                      d_r > 0.0f ? omega_sor / d_r : 0.0f);
  row.law = (float4)(p.friction, rolling * reduced, cohesion, arm_a);
  row.arm_b = arm_b;
  row.a = con.a;
  row.b = con.b;
  row.contact = c;
  rows[k] = row;
  TlImpulse impulse;
  impulse.t = (float4)(lt, ln);
  impulse.r = (float4)(lr, 0.0f);
  impulses[k] = impulse;
}

// external forces: gravity on every dynamic particle
__kernel void apply_gravity(__global float4* velocity, const TlStepParams p) {
  int i = get_global_id(0);
  if (i >= p.particles) return;
  float4 v = velocity[i];
  if (v.w > 0.0f) velocity[i] = (float4)(v.xyz + p.dt * p.gravity.xyz, v.w);
}

// the lever arm of body `i` in a row: a's or b's length along the normal, times it
float3 row_arm_of(const TlParticleRow* row, int i) {
  return (row->a == i ? ROW_ARM_A(*row) : ROW_ARM_B(*row)) * row->normal.xyz;
}

// the impulse body `i` receives from a row: linear and angular (sign -1 for a, +1 for b)
void row_impulse_on(const TlParticleRow* row, const TlImpulse* impulse, int i, float3* lin,
                    float3* ang) {
  float s = row->a == i ? -1.0f : 1.0f;
  float3 P = impulse->t.w * row->normal.xyz + impulse->t.xyz;
  *lin = s * P;
  *ang = s * (cross(row_arm_of(row, i), P) + impulse->r.xyz);
}

// applies the rows' current impulses to each body (warm start), summing in contact order
__kernel void apply_row_impulses(__global const TlParticleRow* rows,
                                 __global const TlImpulse* impulses,
                                 __global const int* adj_offsets, __global const int* adjacency,
                                 __global const int* row_of_contact, __global float4* velocity,
                                 __global float4* omega, const TlStepParams p) {
  int i = get_global_id(0);
  if (i >= p.particles) return;
  float4 v = velocity[i];
  float4 w = omega[i];
  float3 dv = (float3)(0.0f);
  float3 dw = (float3)(0.0f);
  int end = adj_offsets[i + 1];
  for (int k = adj_offsets[i]; k < end; ++k) {
    int r = row_of_contact[adjacency[k]];
    TlParticleRow row = rows[r];
    TlImpulse impulse = impulses[r];
    float3 lin, ang;
    row_impulse_on(&row, &impulse, i, &lin, &ang);
    dv += lin;
    dw += ang;
  }
  velocity[i] = (float4)(v.xyz + v.w * dv, v.w);
  omega[i] = (float4)(w.xyz + w.w * dw, w.w);
}

// one contact's rows solved in sequence (normal, friction, rolling; the law in contact_law.cl)
// against local copies of the two bodies' velocities, updating its impulses. inv_ma/inv_ia/
// inv_mb/inv_ib are the (possibly split) inverse masses; d_n, d_t, d_r the matching inverse
// effective masses. Returns the impulse changes.
TL_INLINE void solve_contact(const TlParticleRow* row, TlImpulse* impulse, float3* va, float3* wa,
                             float3* vb, float3* wb, float inv_ma, float inv_ia, float inv_mb,
                             float inv_ib, float inv_dn, float inv_dt, float inv_dr, float3* d_lin,
                             float3* d_ang) {
  float3 n = row->normal.xyz;
  float arm_a = ROW_ARM_A(*row);
  float arm_b = ROW_ARM_B(*row);
  float ln = impulse->t.w;

  // normal: SPOOK row with compliance, lambda_n >= -h F_c (0 without cohesion)
  float cohesion = ROW_COHESION(*row);
  float un = dot(n, *vb - *va);
  float ln_new = normal_impulse(ln, ROW_RHS(*row), un, ROW_SIGMA(*row), inv_dn, -cohesion);
  float dln = ln_new - ln;
  *va -= inv_ma * dln * n;
  *vb += inv_mb * dln * n;
  ln = ln_new;

  // a contact that carries no load (ln + h F_c = 0: separated, or pulled to its cohesion limit)
  // and holds no friction or rolling impulse keeps them at zero: both are projected onto discs
  // of radius mu_r ... (ln + h F_c) = 0, which gives zero from zero, so the rest of the contact is
  // skipped with bit-identical velocities. Separated speculative contacts skip two thirds of the
  // work this way
  float3 lt = impulse->t.xyz;
  float3 lr = impulse->r.xyz;
  if (ln + cohesion == 0.0f && all(lt == (float3)(0.0f)) && all(lr == (float3)(0.0f))) {
    impulse->t.w = ln;
    *d_lin = dln * n;
    *d_ang = (float3)(0.0f);
    return;
  }

  // friction: tangential relative velocity at the contact point, impulse on the disc
  // mu (lambda_n + h F_c): cohesion adds to the normal load friction sees (Mohr-Coulomb). With
  // the arms along n, w_b x (arm_b n) - w_a x (arm_a n) = (arm_b w_b - arm_a w_a) x n, and each
  // body's angular impulse is its arm times n x dlt: one cross product each way
  float3 u = (*vb - *va) + cross(arm_b * *wb - arm_a * *wa, n);
  float3 ut = u - dot(u, n) * n;
  float3 lt_new = friction_impulse(lt, ut, inv_dt, ROW_FRICTION(*row) * (ln + cohesion));
  float3 dlt = lt_new - lt;
  float3 n_dlt = cross(n, dlt);
  *va -= inv_ma * dlt;
  *wa -= (inv_ia * arm_a) * n_dlt;
  *vb += inv_mb * dlt;
  *wb += (inv_ib * arm_b) * n_dlt;

  // rolling (tangential, on the disc) and twisting (about n), both bounded by
  // mu_r R* (lambda_n + h F_c)
  float3 wrel = *wb - *wa;
  float3 lr_new = rolling_impulse(lr, wrel, n, inv_dr, ROW_ROLLING_LIMIT(*row) * (ln + cohesion));
  float3 dlr = lr_new - lr;
  *wa -= inv_ia * dlr;
  *wb += inv_ib * dlr;

  impulse->t = (float4)(lt_new, ln);
  impulse->r = (float4)(lr_new, 0.0f);
  *d_lin = dln * n + dlt;
  *d_ang = dlr;
}

// the velocity and angular velocity (w: inverse mass / inertia) of a row's two bodies;
// static geometry (b < 0) reads as zero velocity with zero inverse mass
void load_bodies(const TlParticleRow* row, __global const float4* velocity,
                 __global const float4* omega, float4* va, float4* wa, float4* vb, float4* wb) {
  *va = velocity[row->a];
  *wa = omega[row->a];
  *vb = row->b >= 0 ? velocity[row->b] : (float4)(0.0f);
  *wb = row->b >= 0 ? omega[row->b] : (float4)(0.0f);
}

// one PGS row update: the row's contact solved against its bodies' velocities, which it writes
// back with the row's impulses
void pgs_row(__global const TlParticleRow* rows, __global TlImpulse* impulses, int k,
             __global float4* velocity, __global float4* omega) {
  TlParticleRow row = rows[k];
  TlImpulse impulse = impulses[k];
  int a = row.a;
  int b = row.b;
  // the bodies are loaded inline rather than through load_bodies: on PoCL the helper's
  // out-pointers cost this hottest kernel ~10% (settle10k 8.9 vs 10.0 wall s per sim s)
  float4 va4 = velocity[a];
  float4 wa4 = omega[a];
  float4 vb4 = b >= 0 ? velocity[b] : (float4)(0.0f);
  float4 wb4 = b >= 0 ? omega[b] : (float4)(0.0f);
  float3 va = va4.xyz, wa = wa4.xyz, vb = vb4.xyz, wb = wb4.xyz;
  float3 d_lin, d_ang;
  solve_contact(&row, &impulse, &va, &wa, &vb, &wb, va4.w, wa4.w, vb4.w, wb4.w, ROW_INV_DN(row),
                ROW_INV_DT(row), ROW_INV_DR(row), &d_lin, &d_ang);
  impulses[k] = impulse;
  velocity[a] = (float4)(va, va4.w);
  omega[a] = (float4)(wa, wa4.w);
  if (b >= 0) {
    velocity[b] = (float4)(vb, vb4.w);
    omega[b] = (float4)(wb, wb4.w);
  }
}

// projected Gauss-Seidel over one colour: rows [begin, end) share no dynamic body
__kernel void pgs_colour(__global const TlParticleRow* rows, __global TlImpulse* impulses,
                         int begin, int end, __global float4* velocity, __global float4* omega) {
  int k = begin + get_global_id(0);
  if (k >= end) return;
  pgs_row(rows, impulses, k, velocity, omega);
}

// The rows a walk asks for ahead of the one it solves (TL_PREFETCH): 8 rows are about 250 ns at
// this VM's ~30 ns an update, twice a miss to memory. A large system's rows stream from memory (a
// D50 fill's 1.2 M rows are 120 MB with their impulses), and with the hardware prefetcher alone the
// walk waited on each row: a quarter of pgs_row's samples on its first load, the fill's sweeps 1.5
// times as fast with the hint (bench/RESULTS.md 2026-12-02, "a walk's rows prefetched")
#define TL_RUN_PREFETCH_ROWS 8

// projected Gauss-Seidel over runs of rows that share no dynamic body (one level's runs of a large
// system on a CPU device: kernels/colouring.cl contact_part): the one work-item of work-group g
// walks run `first + g`, rows [run_start[first + g], run_start[first + g + 1]) in order. The runs
// of one launch run side by side on the cores without a race; the next level's come in a launch
// of their own after them (solvers/pgs_sweep.cpp)
__kernel void pgs_runs(__global const TlParticleRow* rows, __global TlImpulse* impulses,
                       __global const int* run_start, int first, __global float4* velocity,
                       __global float4* omega) {
  int k = first + get_group_id(0);
  int end = run_start[k + 1];
  // a run's rows share bodies: one work-item walks them (work-groups of one item), asking for the
  // row and impulse it will reach TL_RUN_PREFETCH_ROWS rows on
  for (int r = run_start[k]; r < end; ++r) {
    if (r + TL_RUN_PREFETCH_ROWS < end) {
      TL_PREFETCH(rows + r + TL_RUN_PREFETCH_ROWS);
      TL_PREFETCH(impulses + r + TL_RUN_PREFETCH_ROWS);
    }
    pgs_row(rows, impulses, r, velocity, omega);
  }
}

// one PGS sweep over every colour by one work-group, a barrier between colours: a colour's rows
// share no dynamic body and each is solved by pgs_row, so the result is that of pgs_colour's
// launches bit for bit, whichever work-item takes a row
void pgs_colours_in_group(__global const TlParticleRow* rows, __global TlImpulse* impulses,
                          __global const int* colour_start, int colours, __global float4* velocity,
                          __global float4* omega) {
  int lid = get_local_id(0);
  int size = get_local_size(0);
  for (int k = 0; k < colours; ++k) {
    int end = colour_start[k + 1];
    for (int r = colour_start[k] + lid; r < end; r += size)
      pgs_row(rows, impulses, r, velocity, omega);
    // the colour's velocities seen by the whole group before the next colour reads them
    barrier(CLK_GLOBAL_MEM_FENCE);
  }
}

// `iterations` PGS sweeps in one work-group: for a system whose colours are too small to fill
// the device, where a launch per colour costs more than its rows (the type-G zone, D400;
// solvers/pgs_sweep.cpp). kernels/bucket.cl pgs_sweeps_one_group_tools adds kinematic tools' rows
__kernel void pgs_sweeps_one_group(__global const TlParticleRow* rows, __global TlImpulse* impulses,
                                   __global const int* colour_start, int colours, int iterations,
                                   __global float4* velocity, __global float4* omega) {
  for (int it = 0; it < iterations; ++it)
    pgs_colours_in_group(rows, impulses, colour_start, colours, velocity, omega);
}

// projected Jacobi with mass splitting (Tonge 2012): every row against the same velocities,
// each body's mass split evenly among its contacts; the impulse changes are gathered per body
__kernel void jacobi_rows(__global const TlParticleRow* rows, __global TlImpulse* impulses,
                          int n_rows, __global const float4* velocity, __global const float4* omega,
                          __global const int* adj_offsets, __global float4* delta_lin,
                          __global float4* delta_ang) {
  int k = get_global_id(0);
  if (k >= n_rows) return;
  TlParticleRow row = rows[k];
  TlImpulse impulse = impulses[k];
  int a = row.a;
  int b = row.b;
  float4 va4, wa4, vb4, wb4;
  load_bodies(&row, velocity, omega, &va4, &wa4, &vb4, &wb4);
  // split inverse masses: n_body copies, each with 1/n_body of the mass
  float na = (float)(adj_offsets[a + 1] - adj_offsets[a]);
  float nb = b >= 0 ? (float)(adj_offsets[b + 1] - adj_offsets[b]) : 0.0f;
  float ima = na * va4.w, iia = na * wa4.w, imb = nb * vb4.w, iib = nb * wb4.w;
  float arm_a = ROW_ARM_A(row), arm_b = ROW_ARM_B(row);
  float inv_dn = 1.0f / (ima + imb + ROW_SIGMA(row));
  float dt_ = ima + iia * (arm_a * arm_a) + imb + iib * (arm_b * arm_b);
  float dr_ = iia + iib;
  float3 va = va4.xyz, wa = wa4.xyz, vb = vb4.xyz, wb = wb4.xyz;
  float3 d_lin, d_ang;
  solve_contact(&row, &impulse, &va, &wa, &vb, &wb, ima, iia, imb, iib, inv_dn,
                dt_ > 0.0f ? 1.0f / dt_ : 0.0f, dr_ > 0.0f ? 1.0f / dr_ : 0.0f, &d_lin, &d_ang);
  impulses[k] = impulse;
  delta_lin[k] = (float4)(d_lin, 0.0f);
  delta_ang[k] = (float4)(d_ang, 0.0f);
}

// sums each body's impulse changes in contact order: v += M^-1 sum(G^T d_lambda)
__kernel void jacobi_bodies(__global const TlParticleRow* rows, __global const float4* delta_lin,
                            __global const float4* delta_ang, __global const int* adj_offsets,
                            __global const int* adjacency, __global const int* row_of_contact,
                            __global float4* velocity, __global float4* omega, int particles) {
  int i = get_global_id(0);
  if (i >= particles) return;
  float3 dv = (float3)(0.0f);
  float3 dw = (float3)(0.0f);
  int end = adj_offsets[i + 1];
  for (int k = adj_offsets[i]; k < end; ++k) {
    int r = row_of_contact[adjacency[k]];
    TlParticleRow row = rows[r];
    float s = row.a == i ? -1.0f : 1.0f;
    float3 arm = row_arm_of(&row, i);
    float3 P = delta_lin[r].xyz;
    dv += s * P;
    dw += s * (cross(arm, P) + delta_ang[r].xyz);
  }
  float4 v = velocity[i];
  float4 w = omega[i];
  velocity[i] = (float4)(v.xyz + v.w * dv, v.w);
  omega[i] = (float4)(w.xyz + w.w * dw, w.w);
}

// a row's entry in the residual buffer: the squared residual r2 of a row that acts (it holds a
// normal impulse ln or the step would move it), -1 for one that does not, so sum_residual_blocks
// need not read the rows. A NaN residual stays in (and makes the RMS NaN: no early stop on a bad
// state)
float residual_entry(float r2, float ln) { return r2 != 0.0f || ln != 0.0f ? r2 : -1.0f; }

// the natural-map residual of each contact (velocity units): how far one more projection step
// would move the normal, friction and rolling impulses, times their effective masses (rolling
// times the lever arm's length); zero at the exact solution. The step is plain Gauss-Seidel's
// whatever the sweeps' relaxation (the rows' inverse masses divided by it), so a tolerance means
// the same for every omega
__kernel void row_residual(__global const TlParticleRow* rows, __global const TlImpulse* impulses,
                           int n_rows, __global const float4* velocity,
                           __global const float4* omega, float relaxation,
                           __global float* residual) {
  int k = get_global_id(0);
  if (k >= n_rows) return;
  TlParticleRow row = rows[k];
  TlImpulse impulse = impulses[k];
  // the bodies loaded inline, as in pgs_row (load_bodies' out-pointers cost PoCL)
  int a = row.a;
  int b = row.b;
  float4 va4 = velocity[a];
  float4 wa4 = omega[a];
  float4 vb4 = b >= 0 ? velocity[b] : (float4)(0.0f);
  float4 wb4 = b >= 0 ? omega[b] : (float4)(0.0f);
  float3 n = row.normal.xyz;
  float ln = impulse.t.w;
  float un = dot(n, vb4.xyz - va4.xyz);
  float cohesion = ROW_COHESION(row);
  float inv_dn = ROW_INV_DN(row) / relaxation;
  float inv_dt = ROW_INV_DT(row) / relaxation;
  float inv_dr = ROW_INV_DR(row) / relaxation;
  float rn =
      (normal_impulse(ln, ROW_RHS(row), un, ROW_SIGMA(row), inv_dn, -cohesion) - ln) / inv_dn;
  // a row that carries no load and holds no friction or rolling impulse: their discs have radius
  // zero and project zero onto zero (solve_contact's skip), so its residual is the normal one's,
  // bit for bit, without the friction and rolling work (speculative rows whose pairs stay apart)
  if (ln + cohesion == 0.0f && all(impulse.t.xyz == (float3)(0.0f)) &&
      all(impulse.r.xyz == (float3)(0.0f))) {
    residual[k] = residual_entry(rn * rn, ln);
    return;
  }
  // the slip at the contact point, as in solve_contact (arms along n)
  float arm_a = ROW_ARM_A(row);
  float3 u = (vb4.xyz - va4.xyz) + cross(ROW_ARM_B(row) * wb4.xyz - arm_a * wa4.xyz, n);
  float3 ut = u - dot(u, n) * n;
  float rt = 0.0f;
  if (inv_dt > 0.0f) {
    float3 lt = impulse.t.xyz;
    float3 lt_new = friction_impulse(lt, ut, inv_dt, ROW_FRICTION(row) * (ln + cohesion));
    rt = length(lt_new - lt) / inv_dt;
  }
  // rolling and twist: the same, turned into a velocity by the lever arm's length
  float rr = 0.0f;
  if (inv_dr > 0.0f) {
    float3 wrel = wb4.xyz - wa4.xyz;
    float3 lr = impulse.r.xyz;
    float3 lr_new = rolling_impulse(lr, wrel, n, inv_dr, ROW_ROLLING_LIMIT(row) * (ln + cohesion));
    rr = length(lr_new - lr) / inv_dr * fabs(arm_a);
  }
  residual[k] = residual_entry(rn * rn + rt * rt + rr * rr, ln);
}

// each block of `block` consecutive rows: the sum of their squared residuals and the number of
// rows that act (a normal impulse, or a residual: a step of the projection would move them; the
// rows that do not are -1 in `residual`, residual_entry, so the rows are not read again), one
// work-item a block, in index order. The RMS divides by the rows that act, not by every row: a
// speculative row whose pair stays apart holds no impulse and has no residual, and counted it
// would make the same tolerance looser the more such rows a step has (the fastest grain's reach
// against each pair's own, docs/dem.md). The host reads two floats per block instead of one per row
// (at D50 the download of 1.9 M residuals and their sum on the host were 17 % of a GPU step,
// bench/RESULTS.md). A plain loop and no work-group reduction: the order of the sum is fixed by
// `block` alone, whatever the device, and PoCL pays for barriers (a local-memory tree cost the CPU
// a third more than this)
__kernel void sum_residual_blocks(__global const float* residual, int n, int block,
                                  __global float2* sums) {
  int g = get_global_id(0);
  int begin = g * block;
  if (begin >= n) return;
  int end = min(begin + block, n);
  float s = 0.0f;
  float acting = 0.0f;
  for (int i = begin; i < end; ++i) {
    float r = residual[i];
    if (r != -1.0f) {
      s += r;
      acting += 1.0f;
    }
  }
  sums[g] = (float2)(s, acting);
}

// copies the solved impulses back to the contacts for the next step's warm start
__kernel void store_impulses(__global const TlParticleRow* rows, __global const TlImpulse* impulses,
                             int n_rows, __global TlContact* contacts) {
  int k = get_global_id(0);
  if (k >= n_rows) return;
  int c = rows[k].contact;
  contacts[c].impulse_t = impulses[k].t;
  contacts[c].impulse_r = (float4)(impulses[k].r.xyz, 0.0f);
}

// SPOOK position update: x += h v, q += h/2 (omega, 0) q, renormalised
__kernel void integrate(__global float4* position, __global const float4* velocity,
                        __global const float4* omega, __global float4* rotation,
                        const TlStepParams p) {
  int i = get_global_id(0);
  if (i >= p.particles) return;
  float4 v = velocity[i];
  if (v.w <= 0.0f) return;
  float4 x = position[i];
  position[i] = (float4)(x.xyz + p.dt * v.xyz, x.w);
  float3 w = omega[i].xyz;
  float4 q = rotation[i];
  float half_h = 0.5f * p.dt;
  float4 dq = (float4)(w.x * q.w + w.y * q.z - w.z * q.y, -w.x * q.z + w.y * q.w + w.z * q.x,
                       w.x * q.y - w.y * q.x + w.z * q.w, -w.x * q.x - w.y * q.y - w.z * q.z);
  q += half_h * dq;
  rotation[i] = q / length(q);
}

// the lowest index of a particle whose position (with its radius), velocity or angular velocity
// is not finite, into *first_bad (the host sets it to INT_MAX first): a blow-up or a NaN from the
// input stops the run with a message (solvers/dem_world.cpp) instead of feeding garbage to the
// contact search, whose colouring could then spin without end
__kernel void first_non_finite(__global const float4* position, __global const float4* velocity,
                               __global const float4* omega, int n, __global int* first_bad) {
  int i = get_global_id(0);
  if (i >= n) return;
  float4 x = position[i];
  float4 v = velocity[i];
  float4 w = omega[i];
  if (!(all(isfinite(x)) && all(isfinite(v)) && all(isfinite(w)))) atomic_min(first_bad, i);
}
