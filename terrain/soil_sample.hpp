// Samples of the gravel for the soil tests of issue 11 (terrain/shear_test, collapse_test,
// cutting_test; the heap test in terrain/heap): a box of particles D +- 10 % on a jittered
// lattice, a rough base of fixed spheres, and the dense preparation every test shares.
//
// Dense preparation (docs/dem.md "Preparing dense gravel"): the sample is filled with friction
// and rolling resistance off, so it packs to the field's bulk density, and only then gets the
// gravel's own material; the piles of the digging scenarios are made the same way, so the tests
// measure the soil the bucket meets.
#pragma once
#include <memory>
#include <vector>

#include "host/progress.hpp"
#include "solvers/dem_world.hpp"
#include "solvers/particles.hpp"
#include "terrain/pile.hpp"

namespace talus {

// spacing of the emission lattice: the largest diameter (1.1 D) plus 2 %, so no spheres overlap
inline double lattice_spacing(double diameter) { return 1.1 * diameter * 1.02; }

// a soil test's options (ShearOptions, CollapseOptions, CuttingOptions) at a fidelity level: its
// particle size, timestep and sweeps
template <class Options>
Options at_level(const FidelityPreset& level, Options options = {}) {
  options.diameter = level.diameter;
  options.dt = level.dt;
  options.iterations = level.iterations;
  return options;
}

// the least-squares slope of y against x (0 when x does not vary)
double least_squares_slope(const std::vector<double>& x, const std::vector<double>& y);

// particles with diameters uniform in D +- 0.1 D on a jittered lattice inside [lo, hi], layer by
// layer from lo.z up until their solid volume reaches `solid_volume` [m^3] or the box is full
Particles emit_box_particles(const Vec3& lo, const Vec3& hi, double diameter, double density,
                             double solid_volume, unsigned seed);

// appends fixed spheres of diameter D on a square grid of pitch D resting on z = 0 over
// [x0, x1] x [y0, y1]: a rough base, so grains cannot slide on a smooth floor
void add_rough_base(Particles& particles, double x0, double x1, double y0, double y1, double diameter,
                    double density);

// the material of a soil test: the gravel, with the box's walls and floor as smooth as a
// laboratory's (grains roll on them with their own mu_r, not with the gravel-covered ground's
// Material::ground_rolling); where a test needs a rough floor it lays fixed grains (add_rough_base)
inline Material lab_walls(Material material) {
  material.ground_rolling = material.rolling;
  return material;
}

// a soil test's sample: a particle world of `particles` in `geoms` with the test's material on
// laboratory walls (lab_walls), the level's timestep and sweeps, filled densely (settle_dense)
std::unique_ptr<DemWorld> dense_sample(Device& dev, const Material& material, double dt, int iterations,
                                       const Bounds& bounds, std::vector<StaticGeom> geoms,
                                       const Particles& particles, Progress* progress);

// settles `world` with friction and rolling resistance off (a dense fill), then gives it
// `material`; returns the simulated settling time [s]
double settle_dense(DemWorld& world, const Material& material, double max_time, Progress* progress);

// the mean height of the surface over [x0, x1] x [y0, y1]: the highest top (z + r) of the free
// particles in each of the cells of about D x D that tile the box (0 where a cell is empty),
// averaged over the cells; a lone grain adds only its share of one cell
double mean_surface(const Particles& particles, double x0, double x1, double y0, double y1, double diameter);

// the highest top (z + r) of the free particles whose centres lie over [x0, x1] x [y0, y1]
// (0 when there are none)
double top_surface(const Particles& particles, double x0, double x1, double y0, double y1);

}  // namespace talus
