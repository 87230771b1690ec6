// Projected Jacobi with mass splitting (Tonge, Benevolenski, Voroshilov 2012): every row is
// solved against the same velocities with each body's mass split evenly among its contacts,
// then each body gathers its rows' impulse changes in contact order (no float atomics, so
// results are bit-identical run to run). Converges more slowly than PGS: see docs/dem.md.
#include "solvers/contact_sweep.hpp"

namespace talus {

namespace {

class JacobiSweep : public ContactSweep {
 public:
  JacobiSweep(Device& dev, int particles) : dev_(dev), particles_(particles) {
    const cl::Program& program = dev.program(kSolverProgram);
    rows_kernel_ = dev.kernel(program, "jacobi_rows");
    bodies_kernel_ = dev.kernel(program, "jacobi_bodies");
  }
  const char* name() const override { return "jacobi"; }

  void iterate(DemBuffers& b, int iterations) override {
    int n = b.n_contacts;
    b.delta_lin.resize(n);
    b.delta_ang.resize(n);
    for (int it = 0; it < iterations; ++it) {
      // every row against the velocities of the previous sweep
      set_args(rows_kernel_, b.rows, b.impulses, n, b.velocity, b.omega, b.adjacency_offsets,
               b.delta_lin, b.delta_ang);
      launch(dev_, rows_kernel_, static_cast<size_t>(n), "jacobi_rows");
      // each body sums its impulse changes
      set_args(bodies_kernel_, b.rows, b.delta_lin, b.delta_ang, b.adjacency_offsets, b.adjacency,
               b.row_of_contact, b.velocity, b.omega, particles_);
      launch(dev_, bodies_kernel_, static_cast<size_t>(particles_), "jacobi_bodies");
    }
  }

 private:
  Device& dev_;
  int particles_;
  cl::Kernel rows_kernel_, bodies_kernel_;
};

}  // namespace

std::unique_ptr<ContactSweep> make_jacobi_sweep(Device& dev, int particles) {
  return std::make_unique<JacobiSweep>(dev, particles);
}

}  // namespace talus
