// solvers/pgs_sweep: a small system's sweeps in one work-group (kernels/solver.cl
// pgs_sweeps_one_group) give the bits of a launch per colour (pgs_colour), on fresh random scenes.
#include <gtest/gtest.h>

#include <climits>
#include <cstdio>
#include <cstring>
#include <memory>
#include <random>
#include <string>

#include "host/error.hpp"
#include "solvers/contact_sweep.hpp"
#include "solvers/dem_world.hpp"
#include "tests/solvers/dem_test_util.hpp"

namespace talus {
namespace {

// the bytes of a buffer's first n elements
template <class T>
std::vector<char> bytes_of(const Buffer<T>& b, size_t n) {
  const std::vector<T> v = b.download(n);
  std::vector<char> out(n * sizeof(T));
  if (n > 0) std::memcpy(out.data(), v.data(), out.size());
  return out;
}

// the bytes of host vectors (positions, velocities)
std::vector<char> vec3_bytes(const std::vector<Vec3>& v) {
  const auto* bytes = reinterpret_cast<const char*>(v.data());
  return std::vector<char>(bytes, bytes + v.size() * sizeof(Vec3));
}

// the two paths' bytes agree, and differ from the start's (whose bytes open both)
void expect_the_same_changed_bytes(const std::vector<char>& per_colour,
                                   const std::vector<char>& one_group,
                                   const std::vector<char>& start) {
  ASSERT_EQ(per_colour.size(), one_group.size());
  ASSERT_LE(start.size(), one_group.size());
  EXPECT_EQ(0, std::memcmp(per_colour.data(), one_group.data(), per_colour.size()));
  EXPECT_NE(0, std::memcmp(start.data(), one_group.data(), start.size()));
}

// a world of a random scene from `seed` with PGS (one_group_rows and sweep_parts as given), `steps`
// full steps in, then the next step up to its sweeps: contacts found and laid out, rows made,
// gravity and warm start applied
std::unique_ptr<DemWorld> world_at_its_sweeps(uint64_t seed, int one_group_rows, int sweep_parts,
                                              int steps) {
  std::mt19937_64 rng(seed);
  test::Scene s = test::random_scene(rng);
  s.settings.sweep = SweepKind::Pgs;
  s.settings.one_group_rows = one_group_rows;
  s.settings.sweep_parts = sweep_parts;
  auto world =
      std::make_unique<DemWorld>(test::shared_device(), s.material, s.settings, s.bounds, s.geoms);
  world->set_particles(s.particles);
  for (int i = 0; i < steps; ++i) world->step();
  world->begin_step();
  world->apply_gravity();
  world->warm_start();
  return world;
}

// a sweep made for `one_group_rows` refuses the world's rows, laid out for another walk, with an
// Error saying `why`
void expect_layout_refused(DemWorld& world, int one_group_rows, const std::string& why) {
  try {
    make_pgs_sweep(world.device(), one_group_rows)->iterate(world.buffers(), 1);
    FAIL() << "expected an Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
  }
}

// a random scene's rows and bodies at the start of its sweeps (contacts found, coloured, rows
// made, gravity and warm start applied), then swept by each path from that same state: the
// velocities, angular velocities and row impulses must agree bit for bit. Coloured
// (serial_lanes 0): a CPU device otherwise lays such a system out for one work-item
TEST(PgsSweep, OneGroupGivesTheBitsOfALaunchPerColour) {
  const uint64_t seed = test::fresh_seed();
  SCOPED_TRACE(test::seed_note(seed));
  std::mt19937_64 rng(seed);
  test::Scene s = test::random_scene(rng);
  s.settings.sweep = SweepKind::Pgs;
  s.settings.serial_lanes = 0;
  DemWorld world(test::shared_device(), s.material, s.settings, s.bounds, s.geoms);
  world.set_particles(s.particles);
  // one full step first, so that the second starts warm and carries its colours
  world.step();
  world.begin_step();
  world.apply_gravity();
  world.warm_start();
  DemBuffers& b = world.buffers();
  const size_t n = world.size();
  const size_t rows = static_cast<size_t>(b.n_contacts);
  const int colours = static_cast<int>(b.colour_start.size()) - 1;
  ASSERT_GT(rows, 0u);
  ASSERT_GT(colours, 1);
  const auto v0 = b.velocity.download(n);
  const auto w0 = b.omega.download(n);
  const auto r0 = b.impulses.download(rows);

  const int sweeps = 7;
  auto run = [&](int one_group_rows) {
    b.velocity.upload(v0);
    b.omega.upload(w0);
    b.impulses.upload(r0);
    make_pgs_sweep(world.device(), one_group_rows)->iterate(b, sweeps);
    std::vector<char> out = bytes_of(b.velocity, n);
    for (const auto& part : {bytes_of(b.omega, n), bytes_of(b.impulses, rows)})
      out.insert(out.end(), part.begin(), part.end());
    return out;
  };
  // the sweeps did change the state (a comparison of two untouched copies proves nothing)
  std::vector<char> untouched(v0.size() * sizeof(v0[0]));
  std::memcpy(untouched.data(), v0.data(), untouched.size());
  expect_the_same_changed_bytes(run(0), run(INT_MAX), untouched);
  std::printf("[ measured ] %zu particles, %zu rows in %d colours, %d sweeps: bit-identical\n", n,
              rows, colours, sweeps);
}

// runs walked level by level, a level's runs side by side on the cores, give the bits of one
// work-item walking all their rows in turn: a random scene laid out in runs (one_group_rows 0,
// 5 parts: 3 levels), swept from one state by the runs' sweep and by the one-item sweep over the
// same rows as one range (as an interleaved system is walked)
TEST(PgsSweep, RunsGiveTheBitsOfOneWalkOverAllTheirRows) {
  const uint64_t seed = test::fresh_seed();
  SCOPED_TRACE(test::seed_note(seed));
  const auto made = world_at_its_sweeps(seed, /*one_group_rows=*/0, /*sweep_parts=*/5, 1);
  DemWorld& world = *made;
  if (!world.one_item_sweeps()) GTEST_SKIP() << "this device sweeps in several work-items";
  DemBuffers& b = world.buffers();
  ASSERT_TRUE(b.row_layout == RowLayout::Runs);
  const size_t n = world.size();
  const int rows = b.n_contacts;
  ASSERT_GT(rows, 0);
  ASSERT_GT(world.stats().boundary_rows, 0) << "no contact across parts: the levels untested";
  const auto v0 = b.velocity.download(n);
  const auto w0 = b.omega.download(n);
  const auto r0 = b.impulses.download(rows);
  const std::vector<int> runs = b.colour_start;

  const int sweeps = 7;
  auto state = [&] {
    std::vector<char> out = bytes_of(b.velocity, n);
    for (const auto& part : {bytes_of(b.omega, n), bytes_of(b.impulses, rows)})
      out.insert(out.end(), part.begin(), part.end());
    return out;
  };
  // the runs' sweep
  make_pgs_sweep(world.device(), 0)->iterate(b, sweeps);
  const std::vector<char> in_runs = state();
  // the same rows from the same state as one range that one work-item walks
  b.velocity.upload(v0);
  b.omega.upload(w0);
  b.impulses.upload(r0);
  b.colour_start = {0, rows};
  b.colour_start_dev.upload(b.colour_start);
  b.row_layout = RowLayout::Interleaved;
  make_pgs_sweep(world.device(), rows)->iterate(b, sweeps);
  std::vector<char> untouched(v0.size() * sizeof(v0[0]));
  std::memcpy(untouched.data(), v0.data(), untouched.size());
  expect_the_same_changed_bytes(in_runs, state(), untouched);
  std::printf(
      "[ measured ] %zu particles, %d rows in %zu runs (%d across parts), %d sweeps: "
      "bit-identical\n",
      n, rows, runs.size() - 1, world.stats().boundary_rows, sweeps);
}

// with colours (serial_lanes 0) DemSettings::one_group_rows only picks the path: a world stepped
// with every system in one work-group and one stepped with a launch per colour end in the same
// bits after many steps (warm starts, carried colours and speculative rows included)
TEST(PgsSweep, OneGroupRowsSettingChangesNoBitOfAWorld) {
  const uint64_t seed = test::fresh_seed();
  SCOPED_TRACE(test::seed_note(seed));
  std::mt19937_64 rng(seed);
  const test::Scene s = test::random_scene(rng);
  const int steps = 20;
  auto run = [&](int one_group_rows) {
    DemSettings settings = s.settings;
    settings.sweep = SweepKind::Pgs;
    settings.one_group_rows = one_group_rows;
    settings.serial_lanes = 0;
    DemWorld world(test::shared_device(), s.material, settings, s.bounds, s.geoms);
    world.set_particles(s.particles);
    for (int k = 0; k < steps; ++k) world.step();
    const Particles p = world.particles();
    std::vector<char> out = vec3_bytes(p.position);
    for (const auto& part : {vec3_bytes(p.velocity), vec3_bytes(p.omega)})
      out.insert(out.end(), part.begin(), part.end());
    return out;
  };
  // and the particles moved (two copies of the start state would agree too)
  expect_the_same_changed_bytes(run(0), run(INT_MAX), vec3_bytes(s.particles.position));
  std::printf("[ measured ] %zu particles, %d steps: bit-identical\n", s.particles.size(), steps);
}

// rows laid out interleaved for one work-item share bodies within their one "colour": a sweep
// that would run them in parallel (a per-colour launch) refuses them instead of racing, and the
// one-item sweep that they were laid out for takes them
TEST(PgsSweep, InterleavedRowsAreRefusedByAParallelSweep) {
  const uint64_t seed = test::fresh_seed();
  SCOPED_TRACE(test::seed_note(seed));
  const auto made = world_at_its_sweeps(seed, kPgsOneGroupRows, 0, 0);
  DemWorld& world = *made;
  if (!world.one_item_sweeps()) GTEST_SKIP() << "this device sweeps in several work-items";
  DemBuffers& b = world.buffers();
  ASSERT_GT(b.n_contacts, 0);
  ASSERT_TRUE(b.row_layout == RowLayout::Interleaved);
  expect_layout_refused(world, 0, "laid out for one work-item");
  EXPECT_NO_THROW(make_pgs_sweep(world.device(), b.n_contacts)->iterate(b, 1));
}

// rows laid out in runs (a system above the one-group threshold on a CPU device) share bodies
// within each run: a sweep that would take them as one work-group's colours (a threshold above
// their count) refuses them, and the sweep that walks runs takes them
TEST(PgsSweep, RunsAreRefusedByASweepThatDoesNotWalkThem) {
  const uint64_t seed = test::fresh_seed();
  SCOPED_TRACE(test::seed_note(seed));
  const auto made = world_at_its_sweeps(seed, /*one_group_rows=*/0, /*sweep_parts=*/2, 0);
  DemWorld& world = *made;
  if (!world.one_item_sweeps()) GTEST_SKIP() << "this device sweeps in several work-items";
  DemBuffers& b = world.buffers();
  ASSERT_GT(b.n_contacts, 0);
  ASSERT_TRUE(b.row_layout == RowLayout::Runs);
  ASSERT_EQ(b.colour_start.size(), 4u);
  expect_layout_refused(world, b.n_contacts, "laid out in runs");
  EXPECT_NO_THROW(make_pgs_sweep(world.device(), 0)->iterate(b, 1));
}

}  // namespace
}  // namespace talus
