// The penetration resistance of the bucket's cutting edge in the type-G terrain (issue 14; paper
// §4.4: "a penetration constraint (C) that hinders the motion of the bucket in its cutting
// direction unless the penetration resistance force exceeds a critical value which is a function
// of the bucket geometry and the soil-bucket surface friction coefficient"). The paper gives the
// edge's geometry (radius 10 mm at most, 2.5 mm at least, an equivalent tooth length of 10 mm) but
// not the law; the reference engine's manual gives the ramp (10 % of the force at the surface, all
// of it from 0.5 m of depth, SPEC §2.5) and names cavity expansion. talus takes the bearing
// capacity of a strip footing as wide as the edge is thick (Terzaghi 1943 with Vesić's 1973
// factors), the classical law for a blunt edge pushed into a cohesionless soil at depth d:
//   q = rho g (d N_q + B N_gamma / 2),  N_q = e^(pi tan phi) tan^2(45 deg + phi / 2),
//   N_gamma = 2 (N_q + 1) tan phi,  B = 2 r_max (the edge's thickness)
// on the edge's cross-section B w, and the tapered edge's faces, at theta = atan((r_max - r_min) /
// L) to the cutting direction, add their friction: F = q B w (1 + mu cot theta) times the ramp.
// With the paper's soil (phi + psi = 40 deg dense soil under stress, 1727 kg/m^3, mu 0.2) and a
// 2.685 m edge: 7.4 kN at 0.2 m, 38 kN at 0.5 m.
#pragma once
#include "terrain/active_zone.hpp"

namespace talus {

struct PenetrationParameters {
  double edge_max_radius = 0.010;   // [m] paper §4.4
  double edge_min_radius = 0.0025;  // [m] paper §4.4
  double tooth_length = 0.010;      // [m] paper §4.4, the equivalent tooth length
  double ramp_start = 0.1;          // share of the force at the surface (SPEC §2.5)
  double full_depth = 0.5;          // [m] depth from which the whole force acts (SPEC §2.5)
};

// the force [N] an edge `width` wide [m] needs to advance at `depth` [m] under the soil's surface
// (0 above it), in the soil's effective friction phi + psi and bank density
double penetration_resistance(double depth, double width, const BulkSoil& soil,
                              const PenetrationParameters& edge = {},
                              double density = kFieldBulkDensity);

}  // namespace talus
