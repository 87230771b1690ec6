// The fundamental earthmoving equation (FEE; Reece 1965, McKyes 1985; SPEC §2.5), stated once:
// the force a flat tool needs to fail a cohesionless soil ahead of it, and the failure plane it
// fails along. Two users: the quasi-static cutting test holds the type-D particles to it
// (terrain/cutting_test), and the type-G terrain takes its failure plane as the active zone's
// lower face (terrain/active_zone), so both families answer to one law.
//
// For a cohesionless soil: F / w = rho g d^2 N_gamma + q d N_q with
//   den = cos(alpha + delta) + sin(alpha + delta) cot(beta + phi)
//   N_gamma = (cot alpha + cot beta) / (2 den),  N_q = (cot alpha + cot beta) / den
// alpha the rake angle (between the tool and the horizontal behind its tip: 90 deg a vertical
// blade, less a tool leaning back over the soil it lifts), delta the soil-tool friction angle, phi
// the internal friction, beta the failure plane's angle from the horizontal ahead of the tip, the
// one that makes F smallest, and q = rho g h the surcharge of h of the same soil on the surface.
// The soil's force on the tool acts at delta from the tool's normal: its horizontal part is
// F sin(alpha + delta). Both terms scale with N_q, so beta depends on the angles alone.
#pragma once

namespace talus {

// N_q at the failure angle beta for rake, soil-tool friction and internal friction angles, all in
// [deg]; infinity where the wedge cannot fail along that plane (den <= 0)
double fee_n_q(double rake_deg, double tool_friction_deg, double internal_friction_deg,
               double beta_deg);

// the failure plane's angle beta [deg] for rake, soil-tool friction and internal friction angles
// [deg]: the minimum of N_q over beta, found on a 0.1 deg grid (its best point) and refined by
// golden sections to 1e-9 deg. Throws InputError naming the angles when no plane can fail (their
// sum reaches 180 deg)
double fee_failure_angle(double rake_deg, double tool_friction_deg, double internal_friction_deg);

// the FEE's horizontal force [N] on a tool of width `width` [m] at depth `depth` [m] in a
// cohesionless soil of bulk density `density` [kg/m^3] under a surcharge of `surcharge` [m] of the
// same soil; angles in degrees; `beta_deg` receives the failure angle
double fee_force(double density, double depth, double width, double rake_deg,
                 double tool_friction_deg, double internal_friction_deg, double surcharge = 0.0,
                 double* beta_deg = nullptr);

}  // namespace talus
