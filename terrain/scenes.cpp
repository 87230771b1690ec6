#include "terrain/scenes.hpp"

#include <cmath>
#include <random>

namespace talus {

Scene lattice_box_scene(const LatticeBox& l, const Material& material, const DemSettings& settings) {
  Scene s;
  s.material = material;
  s.settings = settings;
  // lattice origin half a spacing in from the corner, as LIGGGHTS's "origin 0.5 0.5 0.5"
  std::mt19937 rng(l.seed);
  std::uniform_real_distribution<double> jitter(-l.jitter, l.jitter);
  for (int k = 0; k < l.nz; ++k)
    for (int j = 0; j < l.ny; ++j)
      for (int i = 0; i < l.nx; ++i) {
        Vec3 x((i + 0.5) * l.spacing, (j + 0.5) * l.spacing, (k + 0.5) * l.spacing);
        s.particles.add(x + Vec3(jitter(rng), jitter(rng), jitter(rng)), 0.5 * l.diameter, material.density);
      }
  s.geoms = {StaticGeom::plane(Vec3::Zero(), Vec3::UnitZ()),
             StaticGeom::plane(Vec3::Zero(), Vec3::UnitX()),
             StaticGeom::plane(Vec3(l.box, 0, 0), -Vec3::UnitX()),
             StaticGeom::plane(Vec3::Zero(), Vec3::UnitY()),
             StaticGeom::plane(Vec3(0, l.box, 0), -Vec3::UnitY())};
  s.bounds = Bounds{Vec3::Zero(), Vec3(l.box, l.box, (l.nz + 1) * l.spacing)};
  return s;
}

Scene settle10k_scene(unsigned seed) {
  Material m;
  m.density = 2500.0;
  m.friction = 0.5;
  m.young = 1.0e8;
  m.poisson = 0.45;  // as the LIGGGHTS input
  // neither LIGGGHTS's input nor Bullet's has rolling resistance, on grains or walls: the
  // gravel-covered ground of the piles (Material::ground_rolling) is not this box's
  m.rolling = 0.0;
  m.ground_rolling = 0.0;
  LatticeBox layout;
  layout.seed = seed;
  DemSettings s;
  // the step and the speculative reach: the top grains land at up to the free-fall speed from the
  // lattice's top, sqrt(2 g z_top) = 1.70 m/s, which at 4 ms (this case's step until 2026-11-27)
  // carried a grain 1.4 diameters a step: falling grains passed 15-91 % of d into the ones below
  // before a contact was found, and the final overlap, 0.85-5.3 % of d over eight lattice seeds,
  // was the luck of the seed (bench/RESULTS.md "settle10k tunnelled"). At 0.5 ms with contacts
  // speculated 2 h v_max ahead (1.7 mm, a third of d) no grain passes more than 0.93 % of d into
  // another during the fall, and 10 sweeps settle the bed (0.28-0.31 % of d at 0.5 s; 20 sweeps at
  // 1 ms cost more, and 2 ms speculates so far that the colouring runs out of colours)
  const double top = (layout.nz - 0.5) * layout.spacing + layout.jitter;  // [m]
  s.max_speed = std::sqrt(2.0 * -s.gravity.z() * top);
  s.dt = kSettle10kDt;
  s.iterations = kSettle10kSweeps;
  return lattice_box_scene(layout, m, s);
}

}  // namespace talus
