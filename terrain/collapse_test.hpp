// The planar granular column collapse (SPEC §7, issue 11): a column of gravel L0 long and H0 high
// stands in a channel against a back wall, held by a gate; the gate is removed at once and the
// column spreads along the channel. Its run-out against the laboratory law of Lube et al. 2005
// and Lajeunesse et al. 2005 for planar collapses: (L_inf - L0) / L0 = lambda a with a = H0 / L0,
// lambda ~ 1.2 for a below about 2-3 (SPEC gives lambda 1.2-1.8).
//
// The channel, in particle diameters D: L0 = 12 D, width 6 D between two frictional side walls,
// a rough base of fixed spheres; H0 from the aspect ratio asked for, the column filled densely
// (terrain/soil_sample) before the gravel's friction goes on. The measured aspect ratio is the
// settled column's top over L0. The run-out front is the farthest grain still connected to the
// deposit: grains are taken in order of x, and the front moves on to a grain's far side as long
// as its near side lies within one D of the front so far (a stray grain that bounced ahead does
// not count, as in the experiments' photographs).
#pragma once
#include "host/progress.hpp"
#include "solvers/dem_world.hpp"

namespace talus {

struct CollapseOptions {
  double diameter = 0.2;   // mean D [m]
  double dt = 0.01;        // [s]
  int iterations = 500;    // PGS sweeps per step
  unsigned seed = 1;
  double aspect = 1.0;     // H0 / L0 asked for (the settled column's is measured)
  double max_time = 8.0;   // after the gate is removed [s]
};

struct CollapseResult {
  double aspect_ratio = 0.0;   // H0 / L0 of the settled column
  double runout_ratio = 0.0;   // (L_inf - L0) / L0
  double initial_length = 0.0; // L0 [m]
  double initial_height = 0.0; // H0 [m]
  double final_length = 0.0;   // L_inf [m], from the back wall
  double final_height = 0.0;   // deposit's highest top [m]
  int particles = 0;           // free particles
  double sim_time = 0.0;       // [s]
  Particles final_state;       // base included
};

CollapseResult run_collapse_test(Device& dev, const Material& material, const CollapseOptions& options,
                                 Progress* progress = nullptr);

// the run-out front [m] of the free particles, as the file comment defines it, starting from
// x = `back`; `gap` is the largest distance between connected grains [m]
double runout_front(const Particles& particles, double back, double gap);

}  // namespace talus
