// Ready-made granular scenes used by tests, benchmarks and the CLI.
#pragma once
#include <vector>

#include "solvers/dem_settings.hpp"
#include "solvers/particles.hpp"

namespace talus {

struct Scene {
  Particles particles;
  std::vector<StaticGeom> geoms;
  Bounds bounds;
  Material material;
  DemSettings settings;
};

// spheres on a jittered simple-cubic lattice settling in an open box (floor and four walls)
struct LatticeBox {
  int nx = 20, ny = 20, nz = 25;   // lattice sites
  double spacing = 0.006;          // [m]
  double jitter = 0.0004;          // uniform +- [m]
  double diameter = 0.005;         // [m]
  double box = 0.12;               // box edge [m]
  unsigned seed = 15485863;
};
Scene lattice_box_scene(const LatticeBox& layout, const Material& material, const DemSettings& settings);

// the 10k settling case that LIGGGHTS and Bullet were run on (shared/peers/README.md):
// 20x20x25 lattice, spacing 6 mm, jitter +-0.4 mm, d 5 mm, rho 2500 kg/m^3, mu 0.5, a
// 0.12 x 0.12 m box. talus's own choices: E = 1e8 Pa (nonsmooth DEM: stiff contacts, large
// steps; LIGGGHTS needs its soft 5 MPa for a 2e-5 s step), dt 0.5 ms, 10 PGS sweeps, contacts
// speculated for the free-fall speed from the lattice's top (terrain/scenes.cpp says why; the
// 4 ms and 30 sweeps before let falling grains tunnel). `seed`: the lattice jitter's (the peers'
// inputs are the default's)
Scene settle10k_scene(unsigned seed = LatticeBox{}.seed);
// its step [s] and sweeps per step (terrain/scenes.cpp says why)
inline constexpr double kSettle10kDt = 5.0e-4;
inline constexpr int kSettle10kSweeps = 10;

}  // namespace talus
