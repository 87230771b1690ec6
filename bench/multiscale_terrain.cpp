// The type-G terrain's soil side (issue 14, terrain/multiscale_terrain): the wall time of its step
// while a kinematic bucket digs into the default pile and lifts out, per level, and the real-time
// factor it allows (simulated over wall time). The same path as the test
// MultiscaleTerrain.AKinematicDigKeepsTheMassAndCarriesTheSoil: 1.5 s forward at 1 m/s 0.1 m above
// the ground, 2 s lifting at 0.5 m/s while curling back at 0.4 rad/s, 2 s still.
//   build/bench/multiscale_terrain --benchmark_repetitions=3
//   --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>

#include "terrain/multiscale_terrain.hpp"

namespace {

talus::Device& device() {
  static talus::Device dev;
  return dev;
}

void KinematicDig(benchmark::State& state, const std::string& level) {
  const talus::vehicle::BucketMesh mesh =
      talus::vehicle::make_bucket_mesh(talus::vehicle::BucketGeometry{});
  const talus::FidelityPreset& preset = *talus::find_multiscale_preset(level);
  const int steps = static_cast<int>(std::lround(5.5 / preset.dt));
  int most = 0;
  double wall = 0.0;  // [s] of the steps alone, over all iterations
  for (auto _ : state) {
    talus::KinematicBucket b;
    b.position = talus::Vec3(-0.3, 0.0, 0.1);
    talus::MultiscaleTerrain terrain(device(), talus::default_pile_profile(), preset, mesh, b);
    const auto start = std::chrono::steady_clock::now();
    for (int k = 0; k < steps; ++k) {
      const double t = k * preset.dt;
      b.velocity = t < 1.5   ? talus::Vec3(1.0, 0, 0)
                   : t < 3.5 ? talus::Vec3(0, 0, 0.5)
                             : talus::Vec3::Zero();
      b.omega = t >= 1.5 && t < 3.5 ? talus::Vec3(0, -0.4, 0) : talus::Vec3::Zero();
      terrain.step(b);
      b.position += preset.dt * b.velocity;
      if (b.omega.norm() > 0.0)
        b.orientation =
            (Eigen::AngleAxisd(preset.dt * b.omega.norm(), b.omega.normalized()) * b.orientation)
                .normalized();
      most = std::max(most, static_cast<int>(terrain.particle_masses().size()));
    }
    wall += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  // simulated seconds per wall second of the steps (the terrain's construction not counted), the
  // mean wall time of a step, and the largest particle count
  const double simulated = steps * preset.dt * static_cast<double>(state.iterations());
  state.counters["realtime_factor"] = simulated / wall;
  state.counters["ms_per_step"] = 1e3 * wall / (steps * static_cast<double>(state.iterations()));
  state.counters["particles"] = most;
}
BENCHMARK_CAPTURE(KinematicDig, G400, std::string("G400"))->Unit(benchmark::kSecond)->UseRealTime();
BENCHMARK_CAPTURE(KinematicDig, G200, std::string("G200"))->Unit(benchmark::kSecond)->UseRealTime();
BENCHMARK_CAPTURE(KinematicDig, G100, std::string("G100"))
    ->Unit(benchmark::kSecond)
    ->UseRealTime()
    ->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
