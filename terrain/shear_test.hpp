// The direct shear test of the gravel (SPEC §7, issue 11): the soil's peak and critical-state
// friction angles and its dilatancy, to compare with the type-G soil of the paper (internal
// friction 32 deg, dilatancy 8 deg) — the bulk numbers the paper's "32 deg" most likely names
// (docs/soil.md "What the paper's 32° and μ_r 0.02 are").
//
// The box, in particle diameters D: a sample 16 D long (x), 8 D wide, 10 D high, split at half
// height. The lower half sits in fixed walls on the floor; the upper half is held by a ring that
// a kinematic tool moves along x at a constant speed, and it is loaded by a platen: a rigid body
// free to move only up and down, pressing with its weight (solvers/tool_world, a loaded tool), so
// the sample may dilate and the platen's rise measures it. Walls are 4 D thick, so a grain on the
// shear plane always meets a face, never a gap, up to the test's 4 D of shear travel (25 % of
// the box). The sample is filled densely (terrain/soil_sample) before the platen goes on.
//
// Measured along the travel s, each averaged over samples of 0.1 D of travel:
//   tau   = -(F_x on ring + F_x on platen) / A  (what the drive must push; A = box area)
//   sigma = (F_z on the platen + F_z on the ring + weight of the grains whose centres lie above
//           the shear plane) / A  (the upper half's vertical balance: the ring's walls carry part
//           of its weight through wall friction)
//   phi_mobilised = atan(tau / sigma) over windows of 0.5 D; peak = its largest value, critical
//   state = the ratio over the last quarter of the travel; dilatancy psi = atan(dz/ds) of the
//   platen at its steepest over 0.5 D (the peak's dilation rate, Bolton 1986).
// Approximation: grains of the lower half that touch the ring's bottom faces push on the ring
// too, as the sample's own shear band does (the ring's wall thickness keeps that to the box's
// ends).
#pragma once
#include <vector>

#include "host/progress.hpp"
#include "solvers/dem_world.hpp"

namespace talus {

struct ShearOptions {
  double diameter = 0.2;       // mean D [m]
  double dt = 0.01;            // [s]
  int iterations = 500;        // PGS sweeps per step
  unsigned seed = 1;
  // normal stress of the platen's weight [Pa]: the overburden 1 m down in the 2 m pile
  // (1727 kg/m^3 x 9.81 m/s^2 x 1 m)
  double normal_stress = kFieldBulkDensity * 9.81 * 1.0;
  // shear speed [m/s]: quasi-static, inertial number I = (v / 10 D) D / sqrt(sigma / rho) ~ 0.01
  // for a shear band 10 D thick at sigma 17 kPa (MiDi 2004: rate effects below I ~ 1e-2 are small)
  double speed = 0.25;
  double travel_diameters = 4.0;  // shear travel in D
  double ring_friction = -1.0;    // grain-wall friction of the ring and platen; negative: the gravel's mu
};

struct ShearSample {
  double travel = 0.0;        // s [m]
  double shear_stress = 0.0;  // tau [Pa]
  double normal_stress = 0.0; // sigma on the shear plane [Pa]
  double platen_z = 0.0;      // platen height over its height at s = 0 [m]
};

struct ShearResult {
  double peak_friction_deg = 0.0;
  double critical_friction_deg = 0.0;
  double dilatancy_deg = 0.0;
  double peak_travel = 0.0;          // s at the peak [m]
  double bulk_density = 0.0;         // of the sample before shearing [kg/m^3]
  int particles = 0;
  double sim_time = 0.0;             // [s]
  std::vector<ShearSample> series;   // one sample per 0.1 D of travel
  Particles final_state;
};

ShearResult run_shear_test(Device& dev, const Material& material, const ShearOptions& options,
                           Progress* progress = nullptr);

// the three angles from a travel series (exposed so the rules can be tested on made-up curves):
// the peak and critical friction from tau/sigma, the dilatancy from the platen's steepest rise
// over a window of `window` [m] of travel
void shear_angles(const std::vector<ShearSample>& series, double window, ShearResult& result);

}  // namespace talus
