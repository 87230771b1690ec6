// Contact rows and step parameters in double precision, and their conversions to and from the
// device layouts (kernels/dem_types.h). Production builds rows on the host (the bucket's, a
// tool's) and reads solved rows back; the double-precision reference (solvers/dem_reference)
// works on the same types, so the oracle depends on production and never the other way.
#pragma once
#include <vector>

#include "kernels/common.h"
#include "kernels/dem_types.h"
#include "solvers/particles.hpp"

namespace talus {

// the step parameters of kernels/dem_types.h TlStepParams, in double
struct StepParams {
  Vec3 gravity = Vec3::Zero();
  Vec3 grid_origin = Vec3::Zero();
  double cell_size = 0.0;
  int grid_nx = 1, grid_ny = 1, grid_nz = 1;
  int grid_i0 = 0, grid_j0 = 0, grid_k0 = 0;  // the grid's first cell on the lattice
  double dt = 0.0;
  double young = 0.0;
  double poisson = 0.0;
  double friction = 0.0;
  double rolling = 0.0;
  double damping_tau = 0.0;
  double margin_rel = 0.0;
  double overlap_floor_rel = 0.0;
  double speculative = 0.0;  // extra contact distance 2 h v_max [m]
  bool pair_reach =
      false;  // each pair's own reach, at most `speculative` (DemSettings::pair_reach)
  double cohesion = 0.0;     // a touching particle pair's tensile force per R*^2 [N/m^2]
  double ground_rolling = 0.0;  // rolling resistance against static geometry
  double relaxation = 1.0;      // PGS relaxation omega (DemSettings::relaxation)
  int particles = 0;
  int geoms = 0;

  int cells() const { return grid_nx * grid_ny * grid_nz; }
};

// one contact's rows in double (kernels/dem_types.h TlRow, or a particle row TlParticleRow and
// its impulses TlImpulse): what the host builds for the bucket and the tools, and what it reads
// back from the device
struct ContactRow {
  Vec3 normal = Vec3::Zero();
  double rhs = 0.0;               // SPOOK right-hand side of the normal row B_n [m/s]
  Vec3 arm_a = Vec3::Zero();
  double inv_dn = 0.0;            // 1/D_n of the normal row (compliance included)
  Vec3 arm_b = Vec3::Zero();
  double sigma = 0.0;             // SPOOK compliance term Sigma_n [m/(N s)]
  double impulse_n = 0.0;
  Vec3 impulse_t = Vec3::Zero();
  Vec3 impulse_r = Vec3::Zero();
  double inv_dt = 0.0;            // friction effective mass 1/D_t
  double friction = 0.0;          // mu
  double rolling_limit = 0.0;     // mu_r R* [m]
  double inv_dr = 0.0;            // rolling effective mass 1/D_r
  double cohesion = 0.0;          // tensile impulse the contact holds, h F_c [N s]
  int a = 0, b = 0;
  int contact = 0;                // the contact this row was made from
};

// a float4's xyz, and a vector with a w lane as a float4 (float to double is exact)
Vec3 xyz(const cl_float4& f);
cl_float4 to_float4(const Vec3& v, double w);

// the layouts both ways
StepParams from_device(const TlStepParams& p);
ContactRow from_device(const TlRow& r);
TlRow to_device(const ContactRow& r);
// a particle row and its impulses: the arms are their lengths along the normal times it, and the
// row's relaxation stays in its inverse effective masses
ContactRow from_device(const TlParticleRow& r, const TlImpulse& impulse);
// particles from the device's float4 arrays (position.w = radius, velocity.w = 1/m, ...)
Particles particles_from_device(const std::vector<cl_float4>& position,
                                const std::vector<cl_float4>& velocity,
                                const std::vector<cl_float4>& omega,
                                const std::vector<cl_float4>& rotation);

// Hertz normal stiffness k_n = 4/3 E* sqrt(R*) with 1/E* = 2 (1 - nu^2) / E (one material;
// kernels/dem_common.cl hertz_stiffness)
double hertz_stiffness(double reduced_radius, const StepParams& p);

}  // namespace talus
