// A program that embeds talus (docs/embedding.md): it builds a scenario's pile, drives the wheel
// loader into it with its own target speeds instead of the scenario's (the bucket reaches HD27's
// pile after about 1 s; it lifts where the particles say the pile is), and prints a few sensor
// channels, the loaded mass and the pile's top.
//
//     talus_embed_example [SCENARIO [LEVEL [SECONDS]]]      (default: hd27 D400 3)
//
// Build against an installed talus (examples/embed/CMakeLists.txt, find_package(talus)):
//     cmake -S examples/embed -B build-example -DCMAKE_PREFIX_PATH=PREFIX
//     cmake --build build-example
// or with pkg-config, telling the facade where the data is (CMake's package does that itself), as
// one command line:
//     c++ -std=c++17 main.cpp $(pkg-config --cflags --libs talus)
//         -DTALUS_INSTALL_DATA_DIR="\"$(pkg-config --variable=datadir talus)\""
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include <talus/talus.hpp>

namespace {

// the operator of this example: drive at a steady speed and, once the bucket tip is well into the
// pile, raise the boom and curl the bucket a little until the end (SPEC §2.4's signs: positive
// strokes lift and curl). Without a pile it only drives
constexpr double kDriveSpeed = 1.2;  // m/s, HD27's approach speed (data/scenarios/hd27.json)
constexpr double kLiftSpeed = 0.15;  // m/s of lift stroke
constexpr double kTiltSpeed = 0.05;  // m/s of tilt stroke
constexpr double kPenetration =
    1.0;  // m of the bucket tip past the pile's toe: this example's choice
constexpr double kToeQuantile = 0.01;  // the toe: the front 1 % of the particles, not a stray grain
constexpr double kReportInterval = 0.25;  // s between printed lines

// the pile's toe [m]: the x below which lie the front kToeQuantile of the particle centres
double pile_toe(const talus::ParticleState& particles) {
  std::vector<double> x;
  for (std::size_t i = 0; i < particles.size(); ++i) x.push_back(particles.position[3 * i]);
  const auto nth = x.begin() + static_cast<std::ptrdiff_t>(kToeQuantile * x.size());
  std::nth_element(x.begin(), nth, x.end());
  return *nth;
}

class Operator {
 public:
  // lifts once the bucket tip passes lift_from_x [m]; infinity: never
  explicit Operator(double lift_from_x) : lift_from_x_(lift_from_x) {}
  talus::Targets targets(const talus::SensorReading& now) const {
    talus::Targets t;
    t.drive = kDriveSpeed;
    if (now.bucket_tip_x > lift_from_x_) {
      t.lift = kLiftSpeed;
      t.tilt = kTiltSpeed;
    }
    return t;
  }

 private:
  double lift_from_x_;
};

}  // namespace

int main(int argc, char** argv) {
  talus::SimulationOptions options;
  if (argc > 1) options.scenario = argv[1];
  if (argc > 2) options.level = argv[2];
  const double seconds = argc > 3 ? std::atof(argv[3]) : 3.0;
  try {
    talus::Simulation sim(options);
    std::printf("%s at %s: %zu particles, timestep %.3f s\n", sim.scenario_name().c_str(),
                sim.level().c_str(), sim.particle_count(), sim.timestep());
    const double d_lift_start = sim.sensors().d_lift;
    // where to lift, from the settled pile's particles
    const Operator driver(sim.has_particles() ? pile_toe(sim.particles()) + kPenetration
                                              : std::numeric_limits<double>::infinity());
    if (sim.has_particles()) std::printf("pile toe at x = %.2f m\n", pile_toe(sim.particles()));
    std::printf("%8s %10s %10s %10s %12s %12s\n", "t [s]", "v_drive", "f_traction", "d_lift",
                "bucket_tip_x", "loaded [kg]");
    // steps are counted, so the report instants fall on whole steps
    const long steps = std::lround(seconds / sim.timestep());
    const long report_every = std::max(1L, std::lround(kReportInterval / sim.timestep()));
    for (long k = 1; k <= steps; ++k) {
      sim.step(driver.targets(sim.sensors()));
      if (k % report_every == 0 || k == steps) {
        const std::map<std::string, double> c = sim.channels();
        std::printf("%8.2f %10.3f %10.0f %10.4f %12.3f %12.1f\n", c.at("t"), c.at("v_drive"),
                    c.at("f_traction"), c.at("d_lift"), c.at("bucket_tip_x"), sim.loaded_mass());
      }
    }
    const talus::ParticleState particles = sim.particles();
    double highest = 0.0;
    for (std::size_t i = 0; i < particles.size(); ++i)
      highest = std::max(highest, particles.position[3 * i + 2] + particles.radius[i]);
    std::printf(
        "final: t=%.2f s, loaded mass %.1f kg, lift stroke %.4f m (from %.4f m), %zu particles",
        sim.time(), sim.loaded_mass(), sim.sensors().d_lift, d_lift_start, particles.size());
    if (particles.size() > 0) std::printf(", pile top %.2f m", highest);
    std::printf("\n");
  } catch (const talus::InputError& e) {
    // bad options or data files: the message names the option or file and field, and the fix
    std::fprintf(stderr, "talus_embed_example: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "talus_embed_example: %s\n", e.what());
    return 1;
  }
  return 0;
}
