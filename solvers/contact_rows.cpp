#include "solvers/contact_rows.hpp"

#include <cmath>

namespace talus {

Vec3 xyz(const cl_float4& f) { return Vec3(f.s[0], f.s[1], f.s[2]); }

cl_float4 to_float4(const Vec3& v, double w) {
  cl_float4 f;
  f.s[0] = static_cast<float>(v.x());
  f.s[1] = static_cast<float>(v.y());
  f.s[2] = static_cast<float>(v.z());
  f.s[3] = static_cast<float>(w);
  return f;
}

StepParams from_device(const TlStepParams& p) {
  StepParams out;
  out.gravity = xyz(p.gravity);
  out.grid_origin = xyz(p.grid_origin);
  out.cell_size = p.cell_size;
  out.grid_nx = p.grid_nx;
  out.grid_ny = p.grid_ny;
  out.grid_nz = p.grid_nz;
  out.grid_i0 = p.grid_i0;
  out.grid_j0 = p.grid_j0;
  out.grid_k0 = p.grid_k0;
  out.dt = p.dt;
  out.young = p.young;
  out.poisson = p.poisson;
  out.friction = p.friction;
  out.rolling = p.rolling;
  out.damping_tau = p.damping_tau;
  out.margin_rel = p.margin_rel;
  out.overlap_floor_rel = p.overlap_floor_rel;
  out.speculative = p.speculative;
  out.pair_reach = p.pair_reach != 0;
  out.cohesion = p.cohesion;
  out.ground_rolling = p.ground_rolling;
  out.relaxation = p.relaxation;
  out.particles = p.particles;
  out.geoms = p.geoms;
  return out;
}

ContactRow from_device(const TlRow& r) {
  ContactRow out;
  out.normal = xyz(r.normal);
  out.rhs = r.normal.s[3];
  out.arm_a = xyz(r.arm_a);
  out.inv_dn = r.arm_a.s[3];
  out.arm_b = xyz(r.arm_b);
  out.sigma = r.arm_b.s[3];
  out.impulse_t = xyz(r.impulse_t);
  out.impulse_n = r.impulse_t.s[3];
  out.impulse_r = xyz(r.impulse_r);
  out.inv_dt = r.impulse_r.s[3];
  out.friction = r.coef.s[0];
  out.rolling_limit = r.coef.s[1];
  out.inv_dr = r.coef.s[2];
  out.cohesion = r.coef.s[3];
  out.a = r.a;
  out.b = r.b;
  out.contact = r.contact;
  return out;
}

// the particle row is one cache line, and its impulses half of one (kernels/dem_types.h)
static_assert(sizeof(TlParticleRow) == 64,
              "TlParticleRow must stay 64 bytes, as the kernels' layout");
static_assert(sizeof(TlImpulse) == 32, "TlImpulse must stay 32 bytes, as the kernels' layout");

ContactRow from_device(const TlParticleRow& r, const TlImpulse& impulse) {
  ContactRow out;
  out.normal = xyz(r.normal);
  out.rhs = r.normal.s[3];
  out.inv_dn = r.mass.s[0];
  out.sigma = r.mass.s[1];
  out.inv_dt = r.mass.s[2];
  out.inv_dr = r.mass.s[3];
  out.friction = r.law.s[0];
  out.rolling_limit = r.law.s[1];
  out.cohesion = r.law.s[2];
  out.arm_a = double(r.law.s[3]) * out.normal;
  out.arm_b = double(r.arm_b) * out.normal;
  out.impulse_t = xyz(impulse.t);
  out.impulse_n = impulse.t.s[3];
  out.impulse_r = xyz(impulse.r);
  out.a = r.a;
  out.b = r.b;
  out.contact = r.contact;
  return out;
}

TlRow to_device(const ContactRow& r) {
  TlRow d{};
  d.normal = to_float4(r.normal, r.rhs);
  d.arm_a = to_float4(r.arm_a, r.inv_dn);
  d.arm_b = to_float4(r.arm_b, r.sigma);
  d.impulse_t = to_float4(r.impulse_t, r.impulse_n);
  d.impulse_r = to_float4(r.impulse_r, r.inv_dt);
  d.coef = to_float4(Vec3(r.friction, r.rolling_limit, r.inv_dr), r.cohesion);
  d.a = r.a;
  d.b = r.b;
  d.contact = r.contact;
  return d;
}

Particles particles_from_device(const std::vector<cl_float4>& position,
                                const std::vector<cl_float4>& velocity,
                                const std::vector<cl_float4>& omega,
                                const std::vector<cl_float4>& rotation) {
  Particles out;
  for (size_t i = 0; i < position.size(); ++i) {
    out.position.push_back(xyz(position[i]));
    out.radius.push_back(position[i].s[3]);
    out.velocity.push_back(xyz(velocity[i]));
    out.inv_mass.push_back(velocity[i].s[3]);
    out.omega.push_back(xyz(omega[i]));
    out.inv_inertia.push_back(omega[i].s[3]);
    const cl_float4& q = rotation[i];
    out.rotation.emplace_back(q.s[0], q.s[1], q.s[2], q.s[3]);
  }
  return out;
}

double hertz_stiffness(double reduced_radius, const StepParams& p) {
  double e_star = p.young / (2.0 * (1.0 - p.poisson * p.poisson));
  return (4.0 / 3.0) * e_star * std::sqrt(reduced_radius);
}

}  // namespace talus
