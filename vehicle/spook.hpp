// SPOOK row coefficients (Lacoursière 2007; SPEC §2.1). One constraint row with compliance ε and
// damping time τ, stepped with timestep h, becomes
//   G v⁺ + Σ λ = -(4/h) Υ g + Υ G v        (holonomic row, λ the impulse over the step)
//   G v⁺ + Σ λ = u                         (velocity row: motor, friction; u the target speed)
// with Υ = 1/(1 + 4τ/h) and Σ = 4ε/(h²(1 + 4τ/h)) for holonomic rows, and Σ = ε_v/h for velocity
// rows whose compliance ε_v [m/(N s)] is the inverse of a viscous coefficient.
// Same scheme as cannon.js / p2.js Equation.js with d = τ/h.
#pragma once

namespace talus::spook {

// coefficients of one holonomic row
struct RowCoefficients {
  double upsilon = 1.0;  // Υ, dimensionless
  double sigma = 0.0;    // Σ, regularisation on the diagonal of the Schur complement
};

// Υ and Σ for a holonomic row; throws talus::Error for h <= 0, ε < 0 or τ < 0
RowCoefficients holonomic_row(double h, double compliance, double damping_time);

// Σ for a velocity row with viscous compliance ε_v [m/(N s)] (ε_v = 0: an ideal velocity constraint)
double velocity_row_sigma(double h, double viscous_compliance);

// right-hand side of a holonomic row: -(4/h) Υ g + Υ G v
double holonomic_rhs(double h, const RowCoefficients& c, double violation, double row_velocity);

}  // namespace talus::spook
