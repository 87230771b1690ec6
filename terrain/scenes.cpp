#include "terrain/scenes.hpp"

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

Scene settle10k_scene() {
  Material m;
  m.density = 2500.0;
  m.friction = 0.5;
  m.young = 1.0e8;
  m.poisson = 0.45;  // as the LIGGGHTS input
  // neither LIGGGHTS's input nor Bullet's has rolling resistance, on grains or walls: the
  // gravel-covered ground of the piles (Material::ground_rolling) is not this box's
  m.rolling = 0.0;
  m.ground_rolling = 0.0;
  DemSettings s;
  s.dt = 4.0e-3;
  s.iterations = 30;
  return lattice_box_scene(LatticeBox{}, m, s);
}

}  // namespace talus
