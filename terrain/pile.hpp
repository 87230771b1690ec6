// Piles of gravel in a container (SPEC §2.5): the profile is data (data/piles/*.json), so a
// scanned front surface can replace the default one. Particles are emitted on a jittered
// lattice under the (height-stretched) profile and settled under gravity.
#pragma once
#include <functional>
#include <string>
#include <vector>

#include "io/progress.hpp"
#include "solvers/dem_world.hpp"
#include "terrain/particles.hpp"

namespace talus {

// the pile's cross-section: height z(x) as a polyline from the toe to the rear wall
struct PileProfile {
  std::string name;
  std::string source;
  double width = 6.0;              // container width along y [m]
  std::vector<Vec3> points;        // (x, 0, z) polyline, x increasing
  double rear_wall_x = 0.0;        // [m]

  double height_at(double x) const;   // 0 outside [front toe, rear wall]
  double cross_section() const;       // [m^2]
  double volume() const { return cross_section() * width; }
};

// reads a profile file; InputError names the file and field on bad input
PileProfile load_pile_profile(const std::string& path);
// data/piles/default.json (looked up next to the sources or the working directory)
PileProfile default_pile_profile();

// the fidelity presets of paper Table 3 (type D)
struct FidelityPreset {
  std::string name;      // "D400", ...
  double diameter;       // D [m]
  double dt;             // [s]
  int iterations;        // N_it
  int paper_particles;   // N_p in paper Table 3
};
const std::vector<FidelityPreset>& fidelity_presets();
// throws InputError listing the known names
const FidelityPreset& fidelity_preset(const std::string& name);

// the container: ground, side walls, rear wall (open front)
std::vector<StaticGeom> pile_container(const PileProfile& profile);
Bounds pile_bounds(const PileProfile& profile, double diameter);

// particles with diameters uniform in D +- 0.1 D on a jittered lattice filling the profile
// stretched in height so the lattice holds as much solid as the settled bed will
// (settled_fraction: the solid fraction the bed is expected to settle to)
Particles emit_pile_particles(const PileProfile& profile, double diameter, const Material& material,
                              unsigned seed, double settled_fraction = 0.62);

// bulk density [kg/m^3] from particle positions: the solid volume of spheres whose centres lie
// in the box [lo, hi], over the box volume (a box well inside the bed, away from walls)
double bulk_density(const Particles& particles, const Bounds& box, double particle_density);

}  // namespace talus

namespace talus {

// a settled pile: emission, then settling with the preset's timestep
struct PileBuild {
  Particles particles;
  std::vector<StaticGeom> geoms;
  Bounds bounds;
  double settle_time = 0.0;   // simulated [s]
  bool at_rest = false;
  double rms_speed = 0.0;     // at the end [m/s]
  double bulk_density = 0.0;  // in the flat top's core [kg/m^3]
};

struct PileBuildOptions {
  unsigned seed = 1;
  // sweeps while settling: the preset's N_it capped here (settling needs no precise forces)
  int max_settle_iterations = 100;
  double min_time = 1.0;  // [s]
  double max_time = 4.0;  // [s]
};

PileBuild build_pile(Device& dev, const PileProfile& profile, const FidelityPreset& preset,
                     const Material& material, const PileBuildOptions& options, Progress* progress);

}  // namespace talus
