#include "solvers/dem_settings.hpp"

#include "host/error.hpp"

namespace talus {

const char* sweep_name(SweepKind kind) { return kind == SweepKind::Pgs ? "pgs" : "jacobi"; }

SweepKind parse_sweep(const std::string& text, const std::string& field) {
  if (text == "pgs") return SweepKind::Pgs;
  if (text == "jacobi") return SweepKind::Jacobi;
  throw InputError(field + ": unknown sweep '" + text + "'; use 'pgs' or 'jacobi'");
}

}  // namespace talus
