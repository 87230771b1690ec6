// solvers/kinematic_tool_rows: the rows of kinematic tools walked a particle at a time
// (kernels/bucket.cl kinematic_tool_warm_start, kinematic_tool_sweep) against their double twins
// (the serial walk of reference::bucket_warm_start and bucket_sweep with W = 0) and against the
// device's serial walk (BucketRowBlock, tool after tool), on fresh random inputs; a tool that
// moves is refused.
#include "solvers/kinematic_tool_rows.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <random>

#include "host/error.hpp"
#include "tests/solvers/bucket_test_util.hpp"
#include "tests/solvers/dem_test_util.hpp"

namespace talus {
namespace {

using test::Tally;

// two kinematic tools touching random particles: radius 0.05-0.2 m, up to three contacts with
// each tool (some particles touch neither, one tool or both), normals of all directions, gaps
// from -10 % to +5 % of r, half the contacts warm-started, each tool with its own twist
struct RandomCase {
  Particles particles;
  std::vector<BucketBody> tools;
  // each tool's rows, as the device holds them (float) and back in double for the reference
  std::vector<std::vector<TlRow>> device_rows;
  std::vector<std::vector<reference::Row>> rows;
};

RandomCase random_case(std::mt19937_64& rng, int n_particles, int n_tools) {
  test::Draws d{rng};
  RandomCase c;
  for (int i = 0; i < n_particles; ++i) test::add_random_particle(c.particles, d, Vec3(0, 0, 1));
  const reference::StepParams params = test::bucket_test_params();
  for (int t = 0; t < n_tools; ++t) {
    BucketBody tool;
    tool.velocity = test::as_float(Vec3(d.sym(1), d.sym(1), d.sym(1)));
    tool.omega = test::as_float(Vec3(d.sym(0.5), d.sym(0.5), d.sym(0.5)));
    const Vec3 origin = test::as_float(Vec3(d.sym(2.0), d.sym(2.0), 1.0 + d.uniform()));
    std::vector<BucketContact> contacts;
    std::vector<BucketImpulse> previous;
    for (int i = 0; i < n_particles; ++i) {
      const int k = static_cast<int>(d.uniform() * 4);  // 0 to 3 contacts
      for (int j = 0; j < k; ++j) {
        contacts.push_back(test::random_contact(c.particles, i, d));
        if (d.uniform() < 0.5) {
          BucketImpulse b;
          b.particle = i;
          b.normal = contacts.back().normal;
          b.impulse_n = 5.0 * d.uniform();
          b.impulse_t = 0.5 * Vec3(d.uniform(), d.uniform(), d.uniform());
          b.impulse_r = 0.05 * Vec3(d.uniform(), d.uniform(), d.uniform());
          previous.push_back(b);
        }
      }
    }
    const auto match = match_bucket_contacts(contacts, previous);
    std::vector<TlRow> device;
    std::vector<reference::Row> rows;
    for (const auto& r : make_bucket_rows(contacts, c.particles, tool, origin, params,
                                          BucketMaterial{}, previous, match)) {
      device.push_back(to_device(r));
      rows.push_back(reference::from_device(device.back()));
    }
    c.tools.push_back(tool);
    c.device_rows.push_back(device);
    c.rows.push_back(rows);
  }
  return c;
}

// the particles' velocities and omegas on the device
struct DeviceState {
  Buffer<cl_float4> velocity, omega;
  DeviceState(Device& dev, const Particles& p) : velocity(dev, p.size()), omega(dev, p.size()) {
    std::vector<cl_float4> v, w;
    for (size_t i = 0; i < p.size(); ++i) {
      v.push_back(to_float4(p.velocity[i], p.inv_mass[i]));
      w.push_back(to_float4(p.omega[i], p.inv_inertia[i]));
    }
    velocity.upload(v);
    omega.upload(w);
  }
};

constexpr int kSweeps = 5;

TEST(KinematicToolRows, KernelsMatchDoubleReferenceOnRandomContacts) {
  const uint64_t seed = test::fresh_seed();
  SCOPED_TRACE(test::seed_note(seed));
  std::mt19937_64 rng(seed);
  RandomCase c = random_case(rng, 200, 2);
  Device& dev = test::shared_device();

  // the reference: the serial walk, tool after tool, in double
  Particles ref = c.particles;
  for (const auto& rows : c.rows) reference::bucket_warm_start(rows, ref);
  for (int s = 0; s < kSweeps; ++s)
    for (size_t t = 0; t < c.tools.size(); ++t) reference::bucket_sweep(c.rows[t], ref, c.tools[t]);

  // the device: a work-item per particle
  DeviceState state(dev, c.particles);
  KinematicToolRows tools(dev);
  tools.set(c.device_rows, c.tools);
  tools.warm_start(state.velocity, state.omega);
  for (int s = 0; s < kSweeps; ++s) tools.sweep(state.velocity, state.omega);
  const auto v = state.velocity.download(c.particles.size());
  const auto w = state.omega.download(c.particles.size());
  const auto solved = tools.solved();

  // float rounding over five sweeps of a particle's few rows: relative 1e-4 of the values' scale
  Tally velocity("kinematic_tool_sweep velocities"), impulses("kinematic_tool_sweep impulses");
  for (size_t i = 0; i < ref.size(); ++i) {
    velocity.vector(xyz(v[i]), ref.velocity[i], 1e-4, 1e-6, "particle " + std::to_string(i));
    velocity.vector(xyz(w[i]), ref.omega[i], 1e-4, 1e-5, "omega " + std::to_string(i));
  }
  double scale = 0.0;
  for (const auto& rows : c.rows)
    for (const auto& r : rows) scale = std::max(scale, r.impulse_n);
  ASSERT_EQ(solved.size(), c.rows.size());
  for (size_t t = 0; t < c.rows.size(); ++t) {
    ASSERT_EQ(solved[t].size(), c.rows[t].size());
    for (size_t k = 0; k < c.rows[t].size(); ++k) {
      const reference::Row g = reference::from_device(solved[t][k]);
      const reference::Row& e = c.rows[t][k];
      const std::string at = "tool " + std::to_string(t) + " row " + std::to_string(k);
      impulses.scalar(g.impulse_n, e.impulse_n, 1e-4, 2e-6 * scale, "lambda_n " + at);
      impulses.vector(g.impulse_t, e.impulse_t, 1e-4, 2e-6 * scale, "lambda_t " + at);
      impulses.vector(g.impulse_r, e.impulse_r, 1e-4, 2e-6 * 0.2 * scale, "lambda_r " + at);
    }
  }
  velocity.expect_within();
  impulses.expect_within();
  EXPECT_GT(scale, 0.0);  // the rows pushed
  std::printf("[ measured ] %d rows of %d particles, 2 tools, %d sweeps\n", tools.rows(),
              tools.groups(), kSweeps);
}

// every float of two devices' results equal (== : the walks may differ in the sign of a zero)
void expect_equal_floats(const std::vector<cl_float4>& a, const std::vector<cl_float4>& b,
                         const char* what) {
  ASSERT_EQ(a.size(), b.size());
  int differ = 0;
  for (size_t i = 0; i < a.size(); ++i)
    for (int k = 0; k < 4; ++k) differ += a[i].s[k] == b[i].s[k] ? 0 : 1;
  EXPECT_EQ(differ, 0) << what;
}

TEST(KinematicToolRows, AWorkItemPerParticleGivesTheSerialWalk) {
  const uint64_t seed = test::fresh_seed();
  SCOPED_TRACE(test::seed_note(seed));
  std::mt19937_64 rng(seed);
  const RandomCase c = random_case(rng, 150, 3);
  Device& dev = test::shared_device();

  // the serial walk: a chain per tool, tool after tool, each sweep
  DeviceState serial(dev, c.particles);
  std::vector<std::unique_ptr<BucketRowBlock>> blocks;
  for (size_t t = 0; t < c.tools.size(); ++t) {
    blocks.push_back(std::make_unique<BucketRowBlock>(dev));
    blocks.back()->set_rows(c.device_rows[t]);
    blocks.back()->set_bucket(c.tools[t]);
  }
  for (auto& b : blocks) b->warm_start(serial.velocity, serial.omega);
  for (int s = 0; s < kSweeps; ++s)
    for (auto& b : blocks) b->sweep(serial.velocity, serial.omega);

  // a work-item per particle
  DeviceState grouped(dev, c.particles);
  KinematicToolRows tools(dev);
  tools.set(c.device_rows, c.tools);
  tools.warm_start(grouped.velocity, grouped.omega);
  for (int s = 0; s < kSweeps; ++s) tools.sweep(grouped.velocity, grouped.omega);

  const size_t n = c.particles.size();
  expect_equal_floats(grouped.velocity.download(n), serial.velocity.download(n), "velocity");
  expect_equal_floats(grouped.omega.download(n), serial.omega.download(n), "omega");
  const auto solved = tools.solved();
  for (size_t t = 0; t < c.tools.size(); ++t) {
    std::vector<cl_float4> a, b;
    for (const TlRow& r : solved[t]) {
      a.push_back(r.impulse_t);
      a.push_back(r.impulse_r);
    }
    for (const TlRow& r : blocks[t]->rows()) {
      b.push_back(r.impulse_t);
      b.push_back(r.impulse_r);
    }
    expect_equal_floats(a, b, "impulses");
  }
  // the sweeps did something: the particles' velocities changed
  const auto v0 = DeviceState(dev, c.particles).velocity.download(n);
  const auto v = grouped.velocity.download(n);
  int moved = 0;
  for (size_t i = 0; i < n; ++i) moved += v[i].s[0] != v0[i].s[0] ? 1 : 0;
  EXPECT_GT(moved, 0);
  std::printf(
      "[ measured ] %d rows of %d particles, 3 tools, %d sweeps: the serial walk's values\n",
      tools.rows(), tools.groups(), kSweeps);
}

TEST(KinematicToolRows, AToolThatMovesIsRefused) {
  std::mt19937_64 rng(3);
  RandomCase c = random_case(rng, 10, 2);
  c.tools[1].mobility(0, 0) = 1e-3;  // a loaded tool: its rows would move it
  KinematicToolRows tools(test::shared_device());
  EXPECT_THROW(tools.set(c.device_rows, c.tools), InputError);
  // and the lists must be one per tool
  c.tools[1].mobility.setZero();
  c.device_rows.pop_back();
  EXPECT_THROW(tools.set(c.device_rows, c.tools), InputError);
}

}  // namespace
}  // namespace talus
