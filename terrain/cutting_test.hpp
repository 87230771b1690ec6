// The quasi-static cutting test (SPEC §2.5 and §7, issue 11): a flat vertical blade pushed at
// constant depth and slow speed through a level bed of gravel; its mean horizontal force against
// the fundamental earthmoving equation (FEE) of Reece 1965 / McKyes 1985 for the same depth,
// width and soil. Built once for type D (particles) and, later, type G (issue 14).
//
// The bin: a bed of the level's particles as wide as the blade (between frictional side walls,
// so the failure is planar as the FEE assumes), on a rough base, filled densely
// (terrain/soil_sample). The blade is a kinematic tool (solvers/tool_world) 0.5 D thick with the
// bucket-soil friction of the paper (0.2), its bottom `depth` below the bed's mean surface,
// reaching 3 D above it; a wall under the blade's path holds the bed's face below the cut.
//
// The FEE itself is terrain/earthmoving_equation. The soil the blade pushes heaps up in front of it
// (the side walls keep it from spilling sideways), and that heap is a surcharge q on the failure
// wedge: q = rho g h with h the heap's mean height above the original surface over the wedge's
// length at the surface, d cot beta, measured from the particles in every window. The equation's
// force is evaluated with the measured q window by window, so blade and equation are compared on
// the same soil state. Steady part: from one wedge length of travel to the end.
#pragma once
#include <vector>

#include "host/progress.hpp"
#include "solvers/dem_world.hpp"
#include "terrain/active_zone.hpp"
#include "terrain/earthmoving_equation.hpp"
#include "terrain/pile.hpp"

namespace talus {

struct CuttingOptions {
  double diameter = 0.2;        // mean D [m]
  double dt = 0.01;             // [s]
  int iterations = 500;         // PGS sweeps per step
  unsigned seed = 1;
  double depth = 0.3;           // cutting depth below the bed's mean surface [m]
  double speed = 0.2;           // blade speed [m/s], quasi-static
  double travel = 1.5;          // blade travel [m]
  double blade_friction = 0.2;  // bucket-soil friction, paper §4.4
  double internal_friction_deg = 32.0;  // phi of the FEE: the type-G soil of the paper (SPEC §2.5)
  // type G, a study: the aggregate's interfaces' damping time [s]; 0: two steps
  // (AggregateParameters::damping_time; talus run --interface-damping-time on a dig)
  double interface_damping_time = 0.0;
};

struct CuttingSample {
  double travel = 0.0;      // [m]
  double force_x = 0.0;     // horizontal force the blade needs against the soil [N]
  double force_z = 0.0;     // vertical force of the soil on the blade [N] (up positive)
  double surcharge = 0.0;   // height of the heap over the wedge, above the original surface [m]
  double fee_force = 0.0;   // the equation's horizontal force with that surcharge [N]
};

struct CuttingResult {
  double force = 0.0;           // mean horizontal force over the steady part [N]
  double force_spread = 0.0;    // standard deviation of the window means over the steady part [N]
  double fee_force = 0.0;       // the FEE's value, mean over the steady part [N]
  double fee_force_level = 0.0; // the FEE's value for the level bed, no surcharge [N]
  double fee_failure_angle_deg = 0.0;  // its beta
  // type G: the cutting edge's penetration resistance, mean over the steady part [N]; `force` is
  // what the soil's wedge needs beside it (the motor's force less this), as the FEE knows no edge
  double edge_force = 0.0;
  double steady_from = 0.0;     // start of the steady part [m of travel]
  double width = 0.0;           // blade (and bed) width [m]
  double bed_density = 0.0;     // bulk density of the bed [kg/m^3]
  int particles = 0;
  double sim_time = 0.0;
  std::vector<CuttingSample> series;  // window means, one per D / 4 of travel
  Particles final_state;
};

// throws InputError naming the option when the test cannot be run with these options (depth
// outside half a particle .. 2 m, non-positive sizes, no failure plane for the friction angles)
void check_cutting_options(const CuttingOptions& options);

CuttingResult run_cutting_test(Device& dev, const Material& material, const CuttingOptions& options,
                               Progress* progress = nullptr);

// the same test on the type-G terrain (issue 14) at a multiscale level: a level bed of voxels at
// bank density, the blade a body of a multibody system driven along x at the test's speed by a
// prismatic joint's motor, the soil it fails reaching it through the aggregate body (terrain/
// aggregate). The force is the motor's less the cutting edge's penetration resistance (which the
// FEE, for an ideally sharp blade, does not know; reported as edge_force); the equation's is
// evaluated window by window for the load the aggregate carries (its mass as the wedge plus a
// surcharge q over the wedge's top), with the soil's effective internal friction phi + psi (40
// deg), as the zone and interface B use. `options.diameter`, `dt` and `iterations` are taken from
// the level
CuttingResult run_multiscale_cutting_test(Device& dev, const FidelityPreset& level,
                                          const CuttingOptions& options, const BulkSoil& soil = {},
                                          Progress* progress = nullptr);

}  // namespace talus
