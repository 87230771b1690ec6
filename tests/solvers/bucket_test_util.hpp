// Random particles and contacts for the tests of the rows against the bucket and tools
// (bucket_rows_test, kinematic_tool_rows_test): one recipe, so both draw the same kind of case.
#pragma once
#include <random>

#include "solvers/bucket_contacts.hpp"
#include "solvers/dem_reference.hpp"
#include "tests/solvers/dem_test_util.hpp"

namespace talus::test {

// uniform draws from one generator: in [0, 1), in [-a, a), and unit vectors of all directions
struct Draws {
  std::mt19937_64& rng;
  std::uniform_real_distribution<double> u{0.0, 1.0};
  double uniform() { return u(rng); }
  double sym(double a) { return a * (2.0 * u(rng) - 1.0); }
  Vec3 unit() {
    Vec3 v(sym(1), sym(1), sym(1));
    while (v.norm() < 0.1) v = Vec3(sym(1), sym(1), sym(1));
    return v.normalized();
  }
};

// a gravel particle of radius 0.05-0.2 m within (1.5, 1.5, 1) m of `centre`, with a velocity of
// up to 2 m/s and an angular velocity of up to 5 1/s per axis, all as the device holds them
inline void add_random_particle(Particles& p, Draws& d, const Vec3& centre) {
  const double r = as_float(0.05 + 0.15 * d.uniform());
  p.add(as_float(centre + Vec3(d.sym(1.5), d.sym(1.5), d.sym(1.0))), r, 2590.0);
  p.velocity.back() = as_float(Vec3(d.sym(2), d.sym(2), d.sym(2)));
  p.omega.back() = as_float(Vec3(d.sym(5), d.sym(5), d.sym(5)));
  p.inv_mass.back() = as_float(p.inv_mass.back());
  p.inv_inertia.back() = as_float(p.inv_inertia.back());
}

// a contact of particle i with the bucket or a tool: a normal of any direction and a gap from
// -10 % to +5 % of the radius, the contact point halfway into the overlap
inline BucketContact random_contact(const Particles& p, int i, Draws& d) {
  const double r = p.radius[i];
  BucketContact c;
  c.particle = i;
  c.normal = d.unit();
  c.gap = r * (-0.10 + 0.15 * d.uniform());
  c.point = p.position[i] + c.normal * (r + 0.5 * c.gap);
  c.arm_particle = c.point - p.position[i];
  return c;
}

// the step of the rows' tests: 5 ms, a stiff gravel (E 100 MPa), damping over two steps
inline reference::StepParams bucket_test_params() {
  reference::StepParams params;
  params.dt = as_float(0.005);
  params.young = 1.0e8;
  params.poisson = as_float(0.3);
  params.damping_tau = as_float(0.01);
  params.overlap_floor_rel = as_float(1e-4);
  return params;
}

}  // namespace talus::test
