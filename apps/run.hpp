// The scenario run behind `talus run`, shared with `talus synth` (which runs a scenario, then
// turns its output into a measured-run directory).
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "digging/digging.hpp"
#include "terrain/pile.hpp"
#include "vehicle/scenario.hpp"

namespace talus::app {

struct RunOptions {
  std::string scenario;
  std::string fidelity = "D400";
  std::string out;
  std::string json;
  std::string command_line;  // as typed, recorded in summary.json with the version and commit
  std::string sweep = "pgs";
  std::string bucket_sweep = "serial";  // CouplingSettings::bucket_sweep: serial or coloured
  double snapshot_interval = 1.0;  // s; 0: no snapshots
  unsigned seed = 1;
  bool quiet = false;
  // studies of the soil model and of convergence (issue 11): overrides of the gravel's rolling
  // resistance and of the level's timestep and sweeps (negative / 0: the preset's), and the
  // particle rows' residual recorded at the end of every step
  double rolling = -1.0;
  double dt = 0.0;
  int iterations = 0;
  // the SPOOK damping time of the dig's contact rows [s] instead of two steps of its timestep
  // (Material::damping_steps); 0: the default. The pile keeps the level's, as with dt
  double damping_time = 0.0;
  // end a step's sweeps once the particle rows' RMS residual is below this [m/s]; 0: N_it always
  double sweep_tolerance = kDigSweepTolerance;
  // each particle pair's own speculative reach (DemSettings::pair_reach; --reach), the digs'
  // default (DiggingOptions::pair_reach)
  bool pair_reach = DiggingOptions{}.pair_reach;
  // the relaxation of the particle rows' PGS sweeps (DemSettings::relaxation; study)
  double relaxation = 1.0;
  // type G: the zone particles' seed diameter, a fraction of their full one (study;
  // --seed-diameter)
  double seed_diameter = kSeedDiameter;
  // type G, a study: a factor on the cutting edge's penetration resistance (--edge-resistance)
  double edge_resistance = 1.0;
  // type G, a study: how far ahead of the cutting edge the zone's soil turns dynamic [m]; 0: the
  // whole wedge (--excavation-reach)
  double excavation_reach = 0.0;
  // type G, a study: a zone particle slower than this may merge back into the voxels [m/s]
  // (--merge-speed)
  double merge_speed = kMergeSpeed;
  // type G: the bucket's resting load rides with it, out of the DEM (the default);
  // --no-rest-in-bucket: every particle in the DEM (a study)
  bool rest_in_bucket = true;
  // type G, a study: the aggregate's interfaces' damping time [s]; 0: two of the level's steps
  // (--interface-damping-time)
  double interface_damping_time = 0.0;
  // type G: the bucket's soil as a body welded to it (the default); --no-content-inertia: its
  // weight alone (a study)
  bool content_inertia = true;
  // type G: the resting soil holds the bucket's bottom up (the default); --no-bucket-support: the
  // soil under the bucket gives way to any force (a study)
  bool bucket_support = true;
  // type G: the zone's particles stand on its failure plane (the default);
  // --no-failure-plane-floor: on its excavated columns' staircase (a study)
  bool failure_plane_floor = true;
  // type G, a study: the voxel surface's angle of repose [deg] and its avalanche's decay rate
  // [1/s] (--repose-angle, --avalanche-rate; DiggingOptions::avalanche)
  double repose_angle = AvalancheOptions{}.repose_deg;
  double avalanche_rate = AvalancheOptions{}.rate;
  bool residuals = false;
  // settled piles read from and saved to the pile cache (terrain/pile_cache.hpp; --no-pile-cache)
  bool pile_cache = true;
  double form_speed = -1.0;  // the pile's formwork withdrawal speed [m/s]; negative: PileBuildOptions' default
  bool hold_face =
      PileBuildOptions{}.hold_face;  // the face held while the pile settles (--free-face: not)
  std::vector<std::string> effects;         // NAME:key=value,...
  std::vector<std::string> effect_plugins;  // shared libraries
  // when set, this scenario instead of loading `scenario` (talus synth's varied operator inputs)
  std::shared_ptr<const vehicle::Scenario> scenario_data;
};

// runs the scenario and writes its outputs into o.out (apps/cmd_run.cpp)
void run_scenario(const RunOptions& o);

}  // namespace talus::app
