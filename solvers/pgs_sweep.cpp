// Graph-coloured projected Gauss-Seidel: the colours are solved one after another, the rows of
// one colour in parallel (they share no dynamic body, so the updates never race). Within a
// contact the normal row goes first, then friction, then rolling (kernels/solver.cl).
#include "solvers/contact_sweep.hpp"

namespace talus {

namespace {

class PgsSweep : public ContactSweep {
 public:
  explicit PgsSweep(Device& dev) : dev_(dev) {
    kernel_ = dev.kernel(dev.program(kSolverProgram), "pgs_colour");
  }
  const char* name() const override { return "pgs"; }

  void iterate(DemBuffers& b, int iterations) override {
    // one launch per colour and sweep, all on the in-order queue without host waits
    int colours = static_cast<int>(b.colour_start.size()) - 1;
    for (int it = 0; it < iterations; ++it) {
      for (int k = 0; k < colours; ++k) {
        int begin = b.colour_start[k];
        int end = b.colour_start[k + 1];
        if (end == begin) continue;
        set_args(kernel_, b.rows, begin, end, b.velocity, b.omega);
        launch(dev_, kernel_, static_cast<size_t>(end - begin), "pgs_colour");
      }
    }
  }

 private:
  Device& dev_;
  cl::Kernel kernel_;
};

}  // namespace

std::unique_ptr<ContactSweep> make_pgs_sweep(Device& dev) { return std::make_unique<PgsSweep>(dev); }

std::unique_ptr<ContactSweep> make_sweep(SweepKind kind, Device& dev, int particles) {
  if (kind == SweepKind::Pgs) return make_pgs_sweep(dev);
  return make_jacobi_sweep(dev, particles);
}

}  // namespace talus
