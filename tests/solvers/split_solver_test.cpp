// The coupled type-D step (solvers/split_solver): particles against the wheel loader's bucket.
// Each test measures a balance or a bound that a wrong coupling breaks.
#include "solvers/split_solver.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <memory>
#include <random>

#include "solvers/tolerance_schedule.hpp"
#include "terrain/bucket_fill.hpp"
#include "tests/solvers/dem_test_util.hpp"
#include "vehicle/data_file.hpp"

namespace talus {
namespace {

std::string machine_file() { return vehicle::find_data_file("wa320", "machines"); }

// particles on a jittered lattice at the given profile-frame points of the bucket (in the world)
Particles particles_in_bucket_frame(const BucketPose& pose, const Vec3& lo, const Vec3& hi, double d,
                                    unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.05 * d, 0.05 * d), size(0.9 * d, 1.1 * d);
  Particles p;
  const double spacing = 1.12 * d;
  for (double x = lo.x(); x <= hi.x(); x += spacing)
    for (double y = lo.y(); y <= hi.y(); y += spacing)
      for (double z = lo.z(); z <= hi.z(); z += spacing)
        p.add(pose.to_world(Vec3(x + jitter(rng), y + jitter(rng), z + jitter(rng))), 0.5 * size(rng), 2590.0);
  return p;
}

Bounds bounds_around(const Vec3& centre, double half) {
  Bounds b;
  b.lo = centre - Vec3::Constant(half);
  b.hi = centre + Vec3::Constant(half);
  return b;
}

// a standing machine on flat ground with a block of gravel (D 0.12 m) in its bucket, behind the
// cutting edge and ahead of the corner arc (so that every particle starts inside), between the
// heights z_lo and z_hi of the bucket's frame; the coupled step ready to run
struct LoadedBucket {
  vehicle::WheelLoader loader{machine_file()};
  Particles particles;
  std::unique_ptr<DemWorld> dem;
  std::unique_ptr<SplitSolver> split;

  LoadedBucket(double z_lo, double z_hi, int iterations, double density_factor = 1.0,
               double tolerance = 0.0, BucketSweep bucket_sweep = BucketSweep::Serial) {
    const BucketPose pose = bucket_pose(loader);
    particles = particles_in_bucket_frame(pose, Vec3(-0.95, -1.15, z_lo), Vec3(-0.45, 1.15, z_hi), 0.12, 3);
    for (size_t i = 0; i < particles.size(); ++i) {
      particles.inv_mass[i] /= density_factor;
      particles.inv_inertia[i] /= density_factor;
    }
    DemSettings settings;
    settings.dt = 0.005;
    settings.iterations = iterations;
    settings.tolerance = tolerance;
    const std::vector<StaticGeom> ground = {StaticGeom::plane(Vec3::Zero(), Vec3::UnitZ())};
    dem = std::make_unique<DemWorld>(test::shared_device(), gravel(), settings, bounds_around(pose.position, 3.0),
                                     ground);
    dem->set_particles(particles);
    CouplingSettings coupling;
    coupling.bucket_sweep = bucket_sweep;
    split = std::make_unique<SplitSolver>(test::shared_device(), *dem, loader, coupling);
  }
};

// both ways of sweeping the bucket rows, for the tests that must hold for either
constexpr BucketSweep kBucketSweeps[] = {BucketSweep::Serial, BucketSweep::Coloured};

TEST(SplitSolver, ImpulsesOnTheBucketBalanceTheParticles) {
  // no gravity on the particles and no other geometry: every momentum change of the particles
  // comes from the bucket, so the wrench the vehicle receives must be minus their total momentum
  // change (linear, and angular about the bucket's centre of mass)
  const vehicle::WheelLoader standing(machine_file());
  const BucketPose pose = bucket_pose(standing);
  Particles p = particles_in_bucket_frame(pose, Vec3(-1.0, -1.0, 0.048), Vec3(-0.2, 1.0, 0.5), 0.1, 7);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (size_t i = 0; i < p.size(); ++i) {
    p.velocity[i] = pose.orientation * Vec3(-0.5 + 0.3 * u(rng), 0.3 * u(rng), -1.0 + 0.3 * u(rng));
    p.omega[i] = Vec3(u(rng), u(rng), u(rng));
  }
  DemSettings settings;
  settings.dt = 0.005;
  settings.iterations = 40;
  settings.gravity = Vec3::Zero();
  for (BucketSweep sweep : kBucketSweeps) {
    SCOPED_TRACE(bucket_sweep_name(sweep));
    vehicle::WheelLoader loader(machine_file());
    DemWorld dem(test::shared_device(), gravel(), settings, bounds_around(pose.position, 4.0), {});
    dem.set_particles(p);
    CouplingSettings coupling;
    coupling.bucket_sweep = sweep;
    SplitSolver split(test::shared_device(), dem, loader, coupling);
    const Vec3 com = loader.bodies()[loader.bucket_body()].position;

    const Particles before = dem.particles();
    split.step();
    const Particles after = dem.particles();
    Vec3 linear = Vec3::Zero(), angular = Vec3::Zero();
    for (size_t i = 0; i < before.size(); ++i) {
      const double m = before.mass(i);
      const Vec3 dp = m * (after.velocity[i] - before.velocity[i]);
      linear += dp;
      angular += (before.position[i] - com).cross(dp) +
                 (after.omega[i] - before.omega[i]) / before.inv_inertia[i];
    }
    const Vec6 on_bucket = split.stats().impulse;
    std::printf(
        "[ measured ] %s: %d bucket contacts; impulse on the bucket %.4f N s, %.4f N m s; "
        "imbalance %.2e N s, %.2e N m s\n",
        bucket_sweep_name(sweep), split.stats().bucket_contacts, on_bucket.head<3>().norm(),
        on_bucket.tail<3>().norm(), (linear + on_bucket.head<3>()).norm(),
        (angular + on_bucket.tail<3>()).norm());
    ASSERT_GT(split.stats().bucket_contacts, 50);
    ASSERT_GT(on_bucket.head<3>().norm(), 1.0);
    // float impulses summed over hundreds of rows: 1e-4 of the total
    EXPECT_LT((linear + on_bucket.head<3>()).norm(), 1e-4 * on_bucket.head<3>().norm());
    EXPECT_LT((angular + on_bucket.tail<3>()).norm(), 1e-4 * on_bucket.tail<3>().norm() + 1e-3);
  }
}

TEST(SplitSolver, ParticlesAtRestInTheBucketWeighTheirMass) {
  // a standing machine with gravel dropped into its bucket: once settled, the vertical force of the
  // particles on the bucket is their weight, and the lift cylinders carry the extra load
  for (BucketSweep sweep : kBucketSweeps) {
    SCOPED_TRACE(bucket_sweep_name(sweep));
    LoadedBucket b(0.08, 0.55, 40, 1.0, 0.0, sweep);
    vehicle::WheelLoader& loader = b.loader;
    SplitSolver& split = *b.split;
    const Particles& p = b.particles;
    const double dt = b.dem->settings().dt;
    double weight = 0.0;
    for (size_t i = 0; i < p.size(); ++i) weight += p.mass(i) * 9.81;

    // raise the boom for 0.4 s (the machine settles on its tyres and would put the bucket's
    // bottom below the ground: the vehicle has no bucket-ground contact) and curl the bucket for
    // 0.6 s so the gravel does not run out over the edge, then hold; 2 s in all, the force averaged
    // over the last 0.5 s (the machine still rocks a little on its tyres)
    loader.set_drive_speed(0.0);
    const int steps = static_cast<int>(2.0 / dt), window = static_cast<int>(0.5 / dt);
    Vec6 mean = Vec6::Zero();
    // the same window's force by the bucket's faces
    BucketFaceForces faces;
    int max_passes = 0;
    double max_residual = 0.0;
    for (int k = 0; k < steps; ++k) {
      const double t = k * dt;
      loader.set_lift_speed(t < 0.4 ? 0.1 : 0.0);
      loader.set_tilt_speed(t < 0.6 ? loader.tilt_spec().max_speed : 0.0);
      split.step();
      if (k >= steps - window) {
        mean += split.stats().wrench / window;
        faces.below += split.stats().faces.below / window;
        faces.inside += split.stats().faces.inside / window;
        faces.across += split.stats().faces.across / window;
        max_passes = std::max(max_passes, split.stats().passes);
        max_residual = std::max(max_residual, split.stats().residual);
      }
    }
    const double in_bucket =
        loaded_mass(b.dem->particles(), loader.bucket_mesh(), bucket_pose(loader));
    std::printf(
        "[ measured ] %s: %zu particles, %.1f kg; %.1f kg in the bucket, weighing %.1f N; "
        "vertical force on the bucket %.1f N (%+.2f%%); passes <= %d, coupling residual <= "
        "%.2e m/s\n",
        bucket_sweep_name(sweep), p.size(), weight / 9.81, in_bucket, in_bucket * 9.81, -mean.z(),
        100.0 * (-mean.z() - in_bucket * 9.81) / (in_bucket * 9.81), max_passes, max_residual);
    // nearly all the gravel stays in the curled bucket, and the bucket carries its weight
    EXPECT_GT(in_bucket * 9.81, 0.98 * weight);
    EXPECT_NEAR(-mean.z(), in_bucket * 9.81, 0.02 * in_bucket * 9.81);
    EXPECT_LT(std::abs(mean.x()), 0.05 * weight);
    EXPECT_LT(max_residual, CouplingSettings{}.tolerance);
    std::printf("[ measured ] by faces, vertical: below %.1f N, inside %.1f N, across %.1f N\n",
                faces.below.z(), faces.inside.z(), faces.across.z());
    // the held gravel presses on the bottom's inside and the curled bucket's back wall; nothing
    // lies under the raised bottom
    EXPECT_EQ(faces.below.norm(), 0.0);
    EXPECT_NEAR(-(faces.inside.z() + faces.across.z()), in_bucket * 9.81, 0.05 * in_bucket * 9.81);
    EXPECT_GT(-faces.inside.z(), 0.5 * in_bucket * 9.81);
  }
}

// the split by faces reads each contact's normal in the bucket's frame: a bucket turned about
// its width by a fresh angle, rows with normals at fresh angles from its bottom's normal and fresh
// friction impulses; and one row fixed at 40 deg from the bottom's normal in a bucket tilted by 20
// deg, which the world frame would put past 45 deg (a split read in the world fails there)
TEST(SplitSolver, TheBucketsFacesAreReadFromTheNormalInItsFrame) {
  const uint64_t seed = test::fresh_seed();
  SCOPED_TRACE(test::seed_note(seed));
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> tilt(-0.6, 0.6), within(0.0, 0.7), beyond(0.85, 1.5),
      impulse(0.1, 2.0);
  const double h = 0.005;
  constexpr double kDegree = M_PI / 180.0;
  for (const double turn : {tilt(rng), 20.0 * kDegree}) {
    const Eigen::Quaterniond orientation(Eigen::AngleAxisd(turn, Vec3::UnitY()));
    // a unit vector at angle a from the bucket's +z towards its +x (the excavation plane), world
    const auto normal = [&](double a) {
      return Vec3(orientation * Vec3(std::sin(a), 0.0, std::cos(a)));
    };
    std::vector<ContactRow> rows(6);
    rows[0].normal = normal(within(rng));                 // under the bottom
    rows[1].normal = normal(M_PI - within(rng));          // on the bottom's inside
    rows[2].normal = normal(M_PI / 2 + 0.1 * tilt(rng));  // the back wall, the edge's face
    rows[3].normal = normal(beyond(rng));                 // past 45 deg from +z towards +x: across
    rows[4].normal = orientation * Vec3::UnitY();         // a side plate: none of the three
    rows[5].normal = normal(40.0 * kDegree);              // under the bottom; 60 deg in the world
    Vec3 expect_below = Vec3::Zero(), expect_inside = Vec3::Zero(), expect_across = Vec3::Zero();
    for (size_t k = 0; k < rows.size(); ++k) {
      rows[k].impulse_n = impulse(rng);
      // friction along the contact's plane, its force in the part as well
      rows[k].impulse_t = impulse(rng) * rows[k].normal.cross(Vec3::UnitY() + 0.3 * Vec3::UnitX());
      const Vec3 f = (rows[k].impulse_n * rows[k].normal + rows[k].impulse_t) / h;
      if (k == 0 || k == 5) expect_below += f;
      if (k == 1) expect_inside += f;
      if (k == 2 || k == 3) expect_across += f;
    }
    const BucketFaceForces faces = bucket_face_forces(rows, orientation, h);
    EXPECT_LT((faces.below - expect_below).norm(), 1e-9 * expect_below.norm()) << turn;
    EXPECT_LT((faces.inside - expect_inside).norm(), 1e-9 * expect_inside.norm()) << turn;
    EXPECT_LT((faces.across - expect_across).norm(), 1e-9 * expect_across.norm()) << turn;
  }
}

// a tolerance on the particle rows' residual (DemSettings::tolerance) ends each pass's sweeps
// once it is met, at a look of solvers/tolerance_schedule (never before kFirstLookInterval
// sweeps): the gravel held in the standing bucket needs fewer than the 100 sweeps allowed, and
// still weighs its mass on it
TEST(SplitSolver, AToleranceEndsTheSweepsEarlyAndTheBucketStillWeighsItsLoad) {
  constexpr int kIterations = 100;
  constexpr double kTolerance = 1.0e-4;  // [m/s]
  LoadedBucket b(0.08, 0.55, kIterations, 1.0, kTolerance);
  vehicle::WheelLoader& loader = b.loader;
  SplitSolver& split = *b.split;
  const double dt = b.dem->settings().dt;
  loader.set_drive_speed(0.0);
  // the same motion as ParticlesAtRestInTheBucketWeighTheirMass, 2 s, the last 0.5 s averaged
  const int steps = static_cast<int>(2.0 / dt), window = static_cast<int>(0.5 / dt);
  Vec6 mean = Vec6::Zero();
  long sweeps = 0;
  int fewest = kIterations, most = 0;
  for (int k = 0; k < steps; ++k) {
    const double t = k * dt;
    loader.set_lift_speed(t < 0.4 ? 0.1 : 0.0);
    loader.set_tilt_speed(t < 0.6 ? loader.tilt_spec().max_speed : 0.0);
    split.step();
    const CouplingStats& s = split.stats();
    // a pass's sweeps end at a look (never before kFirstLookInterval sweeps) or at its own count
    if (s.passes == 1 && s.sweeps < kIterations) {
      EXPECT_GE(s.sweeps, kFirstLookInterval) << k;
    }
    EXPECT_LE(s.sweeps, kIterations * s.passes) << k;
    if (k >= steps - window) {
      mean += s.wrench / window;
      sweeps += s.sweeps;
      fewest = std::min(fewest, s.sweeps);
      most = std::max(most, s.sweeps);
    }
  }
  const double in_bucket =
      loaded_mass(b.dem->particles(), loader.bucket_mesh(), bucket_pose(loader));
  std::printf(
      "[ measured ] tolerance %.0e m/s: %.1f sweeps per step at rest (%d to %d of %d); vertical "
      "force "
      "on the bucket %.1f N against the load's weight %.1f N (%+.2f%%)\n",
      kTolerance, double(sweeps) / window, fewest, most, kIterations, -mean.z(), in_bucket * 9.81,
      100.0 * (-mean.z() - in_bucket * 9.81) / (in_bucket * 9.81));
  EXPECT_LT(double(sweeps) / window, 0.8 * kIterations);
  EXPECT_NEAR(-mean.z(), in_bucket * 9.81, 0.02 * in_bucket * 9.81);
}

TEST(SplitSolver, NoParticlePassesThroughTheBucketAtFullDriveSpeed) {
  // the machine drives at its top speed into a bed of gravel: the deepest overlap of a particle
  // with the bucket plates must stay far below the radius. A particle can only get through the
  // thin shell by first overlapping it by its whole radius (its centre on the plate, where the
  // closest-point normal flips), so a bound of half the radius shows that none passed
  vehicle::WheelLoader loader(machine_file());
  const Vec3 tip = loader.bucket_tip_world();
  const double d = 0.15;
  const double bed_start = tip.x() + 2.5;  // m of run-up to reach top speed
  Particles p;
  {
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> jitter(-0.05 * d, 0.05 * d), size(0.9 * d, 1.1 * d);
    for (double x = bed_start; x < bed_start + 1.2; x += 1.05 * d)
      for (double y = -1.5; y <= 1.5; y += 1.05 * d)
        for (double z = 0.5 * d + 0.005; z < 0.7; z += 1.05 * d)
          p.add(Vec3(x + jitter(rng), y + jitter(rng), z), 0.5 * size(rng), 2590.0);
  }
  DemSettings settings;
  settings.dt = 0.005;
  settings.iterations = 30;
  settings.max_speed = loader.top_speed();
  const std::vector<StaticGeom> ground = {StaticGeom::plane(Vec3::Zero(), Vec3::UnitZ())};
  Bounds bounds;
  bounds.lo = Vec3(tip.x() - 0.5, -3.0, -0.1);
  bounds.hi = Vec3(bed_start + 3.0, 3.0, 2.5);
  DemWorld dem(test::shared_device(), gravel(), settings, bounds, ground);
  dem.set_particles(p);
  SplitSolver split(test::shared_device(), dem, loader, CouplingSettings{});
  loader.set_lift_speed(0.0);
  loader.set_tilt_speed(0.0);
  loader.set_drive_speed(loader.top_speed());

  double deepest = 0.0, speed_at_bed = 0.0;
  int touching_steps = 0;
  const int steps = static_cast<int>(1.6 / settings.dt);
  for (int k = 0; k < steps; ++k) {
    split.step();
    deepest = std::max(deepest, split.stats().max_overlap_rel);
    if (split.stats().bucket_contacts > 0) {
      if (touching_steps++ == 0) speed_at_bed = loader.bodies()[loader.front_frame()].velocity.x();
    }
  }
  std::printf("[ measured ] %zu particles; bucket reached the bed at %.2f m/s (top %.2f m/s); %d steps in "
              "contact; deepest overlap %.1f%% of a radius\n", p.size(), speed_at_bed, loader.top_speed(),
              touching_steps, 100.0 * deepest);
  ASSERT_GT(touching_steps, 20);
  EXPECT_GT(speed_at_bed, 0.8 * loader.top_speed());
  EXPECT_LT(deepest, 0.5);
}

TEST(SplitSolver, OuterPassesRunWhenTheVehicleActiveSetChangesAndConverge) {
  // gravel eighty times too dense (some 55 t) falls into the bucket on the ground while the boom
  // lifts and the bucket curls at full speed: the machine's active set changes under the load
  // (the bucket's corners leave the ground, tyres unload, cylinders load up to 70-80 % of their
  // limits) between the warm-started solve and the final one. Outer passes must then run and bring
  // the bucket's twist in the sweeps and in the direct solve within the tolerance
  constexpr double kDenser = 80.0;
  LoadedBucket b(0.3, 0.8, 40, kDenser);
  vehicle::WheelLoader& loader = b.loader;
  SplitSolver& split = *b.split;
  const CouplingSettings coupling = split.settings();
  loader.set_lift_speed(loader.lift_spec().max_speed);
  loader.set_tilt_speed(loader.tilt_spec().max_speed);
  int multi = 0, capped = 0, steps = 0;
  double peak_lift = 0.0, peak_tilt = 0.0;
  for (int k = 0; k < 200; ++k) {
    split.step();
    peak_lift = std::max(peak_lift, loader.lift_cylinders()[0]->motor_force());
    peak_tilt = std::max(peak_tilt, loader.tilt_cylinder().motor_force());
    const CouplingStats& s = split.stats();
    if (s.bucket_contacts == 0) continue;
    ++steps;
    if (s.passes > 1) ++multi;
    if (s.passes == coupling.max_passes && s.residual >= coupling.tolerance) ++capped;
  }
  std::printf("[ measured ] %d steps with bucket contacts, %d needed more than one pass, %d ended at the "
              "pass limit above tolerance; peak cylinder force: lift %.0f kN (limit %.0f kN), tilt %.0f kN "
              "(limit %.0f kN)\n", steps, multi, capped, peak_lift / 1e3, loader.lift_spec().force_push / 1e3,
              peak_tilt / 1e3, loader.tilt_spec().force_push / 1e3);
  EXPECT_GT(multi, steps / 10);
  EXPECT_LE(capped, steps / 20);
}

TEST(SplitSolver, TwoRunsAreBitIdentical) {
  // same inputs, same device, same work-group sizes: the same particles and the same machine to
  // the last bit (no unordered float accumulation anywhere in the coupled step), for either
  // bucket sweep; and the two sweeps are not the same arithmetic (the coloured one is in use)
  auto run = [](BucketSweep sweep) {
    LoadedBucket b(0.08, 0.55, 20, 1.0, 0.0, sweep);
    b.loader.set_lift_speed(0.1);
    b.loader.set_tilt_speed(0.1);
    for (int k = 0; k < 60; ++k) b.split->step();
    return std::make_pair(b.dem->particles(), b.loader.bodies());
  };
  std::vector<Particles> last;
  for (BucketSweep sweep : kBucketSweeps) {
    SCOPED_TRACE(bucket_sweep_name(sweep));
    const auto a = run(sweep);
    const auto b = run(sweep);
    ASSERT_EQ(a.first.size(), b.first.size());
    for (size_t i = 0; i < a.first.size(); ++i) {
      EXPECT_EQ(a.first.position[i], b.first.position[i]) << i;
      EXPECT_EQ(a.first.velocity[i], b.first.velocity[i]) << i;
    }
    for (size_t i = 0; i < a.second.size(); ++i) {
      EXPECT_EQ(a.second[i].position, b.second[i].position) << a.second[i].name;
      EXPECT_EQ(a.second[i].velocity, b.second[i].velocity) << a.second[i].name;
    }
    last.push_back(a.first);
  }
  ASSERT_EQ(last.size(), 2u);
  size_t differ = 0;
  for (size_t i = 0; i < last[0].size(); ++i) differ += last[0].velocity[i] != last[1].velocity[i];
  std::printf(
      "[ measured ] %zu of %zu particle velocities differ between the serial and the "
      "coloured bucket sweep after 60 steps\n",
      differ, last[0].size());
  EXPECT_GT(differ, 0u);
}

}  // namespace
}  // namespace talus
