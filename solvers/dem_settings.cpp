#include "solvers/dem_settings.hpp"

#include "host/error.hpp"

namespace talus {

const char* sweep_name(SweepKind kind) { return kind == SweepKind::Pgs ? "pgs" : "jacobi"; }

SweepKind parse_sweep(const std::string& text, const std::string& field) {
  if (text == "pgs") return SweepKind::Pgs;
  if (text == "jacobi") return SweepKind::Jacobi;
  throw InputError(field + ": unknown sweep '" + text + "'; use 'pgs' or 'jacobi'");
}

bool relaxation_in_range(double omega) {
  // projected SOR converges for 0 < omega < 2 on a symmetric positive definite system (the
  // normal rows'); outside it the sweeps diverge or stand still. Judged as the float the kernels
  // get: 1.99999999 is 2.0f
  return omega >= kMinRelaxation && static_cast<float>(omega) < 2.0f;
}

void check_relaxation(double omega, SweepKind sweep, const std::string& field) {
  if (!relaxation_in_range(omega))
    throw InputError(field + ": the relaxation " + message_number(omega) + " is outside [" +
                     message_number(kMinRelaxation) +
                     ", 2); use 1 for plain projected Gauss-Seidel");
  if (sweep == SweepKind::Jacobi && omega != 1.0)
    throw InputError(field +
                     ": the Jacobi sweep does not use a relaxation (its split masses are its "
                     "own); use 1, or the PGS sweep");
}

}  // namespace talus
