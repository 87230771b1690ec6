// The contact law in double precision: the twin of kernels/contact_law.cl, the one statement of
// one projected step of a contact's normal, friction and rolling impulses that the reference
// sweeps and residual (solvers/dem_reference) and the bucket sweep's reference
// (solvers/bucket_rows) use. Changing friction or cohesion is an edit there and here.
#pragma once
#include <algorithm>

#include "solvers/particles.hpp"

namespace talus::contact_law {

// the normal impulse after one projected SPOOK step, held at or above `lower` (-h F_c, or 0)
inline double normal_impulse(double ln, double rhs, double un, double sigma, double inv_dn, double lower) {
  return std::max(lower, ln + (rhs - un - sigma * ln) * inv_dn);
}

// `impulse` scaled onto the disc of radius `limit` when it lies outside
inline void clamp_to_disc(Vec3& impulse, double limit) {
  const double magnitude = impulse.norm();
  if (magnitude > limit) impulse *= magnitude > 0.0 ? limit / magnitude : 0.0;
}

// the friction impulse after one step against the tangential slip ut, projected on the disc of
// radius tmax = mu (lambda_n + h F_c)
inline Vec3 friction_impulse(const Vec3& lt, const Vec3& ut, double inv_dt, double tmax) {
  Vec3 lt_new = lt - ut * inv_dt;
  clamp_to_disc(lt_new, tmax);
  return lt_new;
}

// the rolling and twisting impulse after one step against the relative spin wrel: its part
// tangent to n projected on the disc of radius rmax = mu_r R* (lambda_n + h F_c), its twist
// about n clamped to +-rmax
inline Vec3 rolling_impulse(const Vec3& lr, const Vec3& wrel, const Vec3& n, double inv_dr, double rmax) {
  Vec3 lr_t_new = (lr - lr.dot(n) * n) - (wrel - wrel.dot(n) * n) * inv_dr;
  clamp_to_disc(lr_t_new, rmax);
  const double twist = std::clamp(lr.dot(n) - wrel.dot(n) * inv_dr, -rmax, rmax);
  return lr_t_new + twist * n;
}

}  // namespace talus::contact_law
