// Rows between particles and the bucket (SPEC §1 steps 3-6). The rows are made on the host from
// Embree's closest points (solvers/bucket_rows.cpp) and solved here inside every sweep, right
// after the particle rows. All bucket rows share one body, so they are solved one after another
// by a single work-item: the bucket's twist changes with every row through its articulated 6x6
// mobility W (the vehicle seen from the bucket), which is what makes the coupling strong.
// Double-precision twins: solvers/bucket_rows.cpp (reference namespace).

// the bucket's twist change from an impulse wrench [p; l] about its centre of mass: W [p; l]
void bucket_twist_change(const float* W, float3 p, float3 l, float3* dv, float3* dw) {
  float x[6] = {p.x, p.y, p.z, l.x, l.y, l.z};
  float y[6];
  for (int i = 0; i < 6; ++i) {
    float s = 0.0f;
    for (int j = 0; j < 6; ++j) s += W[6 * i + j] * x[j];
    y[i] = s;
  }
  *dv += (float3)(y[0], y[1], y[2]);
  *dw += (float3)(y[3], y[4], y[5]);
}

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

// warm start: each particle receives the impulses its bucket rows start from (the bucket's
// share is already in its twist: the vehicle was solved with their wrench). Serial: a particle
// may touch the bucket more than once.
__kernel void bucket_warm_start(__global const TlRow* rows, int n_rows, __global float4* velocity,
                                __global float4* omega) {
  if (get_global_id(0) != 0) return;
  for (int k = 0; k < n_rows; ++k) {
    TlRow row = rows[k];
    int a = row.a;
    float3 P = ROW_IMPULSE_N(row) * row.normal.xyz + row.impulse_t.xyz;
    float4 va = velocity[a];
    float4 wa = omega[a];
    velocity[a] = (float4)(va.xyz - va.w * P, va.w);
    omega[a] = (float4)(wa.xyz - wa.w * (cross(row.arm_a.xyz, P) + row.impulse_r.xyz), wa.w);
  }
}

// one sweep over the bucket rows in order: per contact normal, friction, then rolling, as
// kernels/solver.cl solve_contact, with the bucket's side through W instead of a diagonal mass
__kernel void bucket_sweep(__global TlRow* rows, int n_rows, __global float4* velocity,
                           __global float4* omega, __global TlBucketBody* bucket) {
  if (get_global_id(0) != 0) return;
  float W[36];
  for (int i = 0; i < 36; ++i) W[i] = bucket->mobility[i];
  float3 vb = bucket->velocity.xyz;
  float3 wb = bucket->omega.xyz;
  for (int k = 0; k < n_rows; ++k) {
    TlRow row = rows[k];
    int a = row.a;
    float4 va4 = velocity[a];
    float4 wa4 = omega[a];
    float3 va = va4.xyz, wa = wa4.xyz;
    float ima = va4.w, iia = wa4.w;
    float3 n = row.normal.xyz;
    float3 arm_a = row.arm_a.xyz;
    float3 arm_b = row.arm_b.xyz;
    float ln = ROW_IMPULSE_N(row);

    // normal: the bucket's point velocity against the particle's (its arm is along n); the
    // bucket holds no tensile impulse
    float un = dot(n, vb + cross(wb, arm_b) - va);
    float ln_new = normal_impulse(ln, ROW_RHS(row), un, ROW_SIGMA(row), ROW_INV_DN(row), 0.0f);
    float3 dp = (ln_new - ln) * n;
    va -= ima * dp;
    bucket_twist_change(W, dp, cross(arm_b, dp), &vb, &wb);
    ln = ln_new;

    // friction on the disc mu lambda_n
    float3 u = (vb + cross(wb, arm_b)) - (va + cross(wa, arm_a));
    float3 ut = u - dot(u, n) * n;
    float3 lt = row.impulse_t.xyz;
    float3 lt_new = friction_impulse(lt, ut, ROW_INV_DT(row), ROW_FRICTION(row) * ln);
    float3 dlt = lt_new - lt;
    va -= ima * dlt;
    wa -= iia * cross(arm_a, dlt);
    bucket_twist_change(W, dlt, cross(arm_b, dlt), &vb, &wb);

    // rolling (on the disc) and twist (about n), both bounded by mu_r R* lambda_n
    float3 wrel = wb - wa;
    float3 lr = row.impulse_r.xyz;
    float3 lr_new = rolling_impulse(lr, wrel, n, ROW_INV_DR(row), ROW_ROLLING_LIMIT(row) * ln);
    float3 dlr = lr_new - lr;
    wa -= iia * dlr;
    bucket_twist_change(W, (float3)(0.0f), dlr, &vb, &wb);

    rows[k].impulse_t = (float4)(lt_new, ln);
    rows[k].impulse_r = (float4)(lr_new, ROW_INV_DT(row));
    velocity[a] = (float4)(va, ima);
    omega[a] = (float4)(wa, iia);
  }
  bucket->velocity = (float4)(vb, 0.0f);
  bucket->omega = (float4)(wb, 0.0f);
}
