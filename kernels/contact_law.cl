// The contact law, stated once for every sweep: one projected step of a contact's normal,
// friction and rolling impulses (SPOOK normal row with compliance, Coulomb friction on the disc
// mu (lambda_n + h F_c), rolling and twisting resistance within mu_r R* (lambda_n + h F_c)).
// The PGS and Jacobi sweeps and the residual (solver.cl) and the bucket sweep (bucket.cl) call
// these; changing friction or cohesion is an edit here and in the double twin,
// solvers/contact_law.hpp. The callers pass the cones' radii, since the bucket's rows hold no
// cohesion. The functions keep the statements the particle sweeps had inline, so the PGS and
// Jacobi sweeps stayed bit for bit; the bucket sweep had written the rolling projection as one
// expression (which the compiler fused into a multiply-add) and the residual divided by 1/D where
// it now multiplies by D^-1, so those two changed at float rounding when the law was written once
// (docs/dem.md).

// the normal impulse after one projected step, held at or above `lower` (-h F_c, or 0)
TL_INLINE float normal_impulse(float ln, float rhs, float un, float sigma, float inv_dn,
                               float lower) {
  return fmax(lower, ln + (rhs - un - sigma * ln) * inv_dn);
}

// the friction impulse after one step against the tangential slip ut, projected on the disc of
// radius tmax
TL_INLINE float3 friction_impulse(float3 lt, float3 ut, float inv_dt, float tmax) {
  float3 lt_new = lt - ut * inv_dt;
  float tm = length(lt_new);
  if (tm > tmax) lt_new *= tm > 0.0f ? tmax / tm : 0.0f;
  return lt_new;
}

// the rolling and twisting impulse after one step against the relative spin wrel: its part
// tangent to n projected on the disc of radius rmax, its twist about n clamped to +-rmax
TL_INLINE float3 rolling_impulse(float3 lr, float3 wrel, float3 n, float inv_dr, float rmax) {
  float3 lr_n = dot(lr, n) * n;
  float3 lr_t = lr - lr_n;
  float3 lr_t_new = lr_t - (wrel - dot(wrel, n) * n) * inv_dr;
  float rm = length(lr_t_new);
  if (rm > rmax) lr_t_new *= rm > 0.0f ? rmax / rm : 0.0f;
  float twist = clamp(dot(lr, n) - dot(wrel, n) * inv_dr, -rmax, rmax);
  return lr_t_new + twist * n;
}
