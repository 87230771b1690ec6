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
// steps; LIGGGHTS needs its soft 5 MPa for a 2e-5 s step), dt 4 ms, 30 PGS sweeps (chosen in
// bench/RESULTS.md: the cheapest setting measured with max overlap below 1% of d).
Scene settle10k_scene();

}  // namespace talus
