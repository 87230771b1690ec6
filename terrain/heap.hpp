// The heap test of the gravel (SPEC §7): a square column of particles is settled inside four
// walls on a rough base, the walls are removed ("lifted"), and the particles run out into a
// heap whose flank angle is the angle of repose. Nothing imposes the heap's shape.
#pragma once
#include "host/progress.hpp"
#include "solvers/dem_world.hpp"

namespace talus {

struct HeapOptions {
  double diameter = 0.1;   // mean D [m]; diameters uniform in D +- 0.1 D
  int columns = 12;        // column width in lattice sites
  int layers = 22;         // column height in lattice sites
  double dt = 0.005;       // [s] (paper's D100 timestep)
  int iterations = 100;    // PGS sweeps per step (paper's D100)
  unsigned seed = 1;
  double max_fill_time = 2.0;      // settling inside the walls [s]
  double max_runout_time = 5.0;    // after the walls are removed [s]
  // fill the column with friction and rolling resistance off (a dense fill, like gravel
  // compacted by dumping), then switch them on before the walls go: see docs/dem.md
  bool dense_fill = true;
  // the walls retreat outward at this speed before they are removed, so the column fails
  // slowly into a heap instead of collapsing (0: removed at once) [m/s]
  double wall_speed = 0.2;
  double wall_travel = 1.0;  // how far each wall retreats before removal [m]
};

struct HeapResult {
  double repose_angle_deg = 0.0;     // mean over azimuthal sectors
  double repose_spread_deg = 0.0;    // standard deviation over sectors
  int sectors = 0;                   // sectors with a usable flank
  double bulk_density = 0.0;         // in the settled column, away from walls [kg/m^3]
  double heap_height = 0.0;          // [m]
  double sim_time = 0.0;             // [s]
  int particles = 0;                 // free particles (the rough base excluded)
  Particles final_state;             // all particles at the end, base included
  std::vector<StaticGeom> geoms;     // the ground
};

HeapResult run_heap_test(Device& dev, const Material& material, const HeapOptions& options,
                         Progress* progress = nullptr);

// the flank angle of a heap centred on the z axis: per azimuthal sector, the upper envelope
// of particle tops in radial bins, and a least-squares line through the part between 20% and
// 80% of the heap height. Returns {mean degrees, spread degrees, sectors used}.
struct FlankFit {
  double angle_deg = 0.0;
  double spread_deg = 0.0;
  int sectors = 0;
  double height = 0.0;
};
FlankFit measure_flank_angle(const Particles& particles, double bin_width, int sectors = 8);

}  // namespace talus
