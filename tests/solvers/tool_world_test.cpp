// solvers/tool_world: rigid tools that touch the particles through a mesh. A kinematic plate
// carries the weight of the grains on it, a loaded platen comes to rest on a bed with its weight
// balanced by the grains, a tool that would turn is refused, a kinematic one turns as prescribed,
// and two runs are bit-identical (also with the particles renumbered in place halfway), and a
// kinematic tool's rows give the same bits whichever launches solve them. Fixed particles get no
// rows with a tool.
#include "solvers/tool_world.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <limits>

#include "host/error.hpp"
#include "terrain/soil_sample.hpp"

namespace talus {
namespace {

constexpr double kD = 0.1;  // particle diameter of these tests [m]

// a bed of 0.1 m grains, 8 x 8 D, about 5 D deep, settled densely between four walls on a floor at z0
struct Bed {
  std::unique_ptr<DemWorld> dem;
  double mass = 0.0;
};

Bed make_bed(Device& dev, double z0, unsigned seed) {
  const double half = 4.0 * kD;
  Particles p = emit_box_particles(Vec3(-half, -half, z0), Vec3(half, half, z0 + 12.0 * kD), kD, 2590.0,
                                   0.6 * 64.0 * 5.0 * kD * kD * kD, seed);
  std::vector<StaticGeom> walls = {StaticGeom::plane(Vec3(-half, 0, 0), Vec3::UnitX()),
                                   StaticGeom::plane(Vec3(half, 0, 0), -Vec3::UnitX()),
                                   StaticGeom::plane(Vec3(0, -half, 0), Vec3::UnitY()),
                                   StaticGeom::plane(Vec3(0, half, 0), -Vec3::UnitY())};
  DemSettings s;
  s.dt = 0.005;
  s.iterations = 50;
  Bed b;
  b.dem = std::make_unique<DemWorld>(dev, gravel(), s, Bounds{Vec3(-half - kD, -half - kD, z0 - 2 * kD),
                                                               Vec3(half + kD, half + kD, z0 + 20 * kD)}, walls);
  b.dem->set_particles(p);
  for (size_t i = 0; i < p.size(); ++i) b.mass += p.mass(i);
  return b;
}

// the bed's walls with a floor at z = 0 under it
void add_floor(Bed& b) {
  std::vector<StaticGeom> geoms = b.dem->geoms();
  geoms.push_back(StaticGeom::plane(Vec3::Zero(), Vec3::UnitZ()));
  b.dem->set_geoms(geoms);
}

// a kinematic blade 0.04 m thick across the bed, 0.6 m high, pushed along x at 0.5 m/s from its
// -x side
Tool blade() {
  Tool t;
  add_box(t.mesh, Vec3(0, 0, 0.3), Vec3(0.02, 0.35, 0.3));
  t.position = Vec3(-0.35, 0, 0.1);
  t.velocity = Vec3(0.5, 0, 0);
  return t;
}

// every float of the particles' velocities (inverse masses included), as the device holds them
std::vector<float> velocity_floats(DemWorld& dem) {
  std::vector<float> out;
  for (const cl_float4& v : dem.buffers().velocity.download(dem.size()))
    for (int c = 0; c < 4; ++c) out.push_back(v.s[c]);
  return out;
}

// the default layout and, on a CPU device, runs: the bed above the one-group threshold
// (one_group_rows 0) in 3 parts, its sweeps and the tools' rows launched per sweep
// (ContactSweep::iterate_with_tools), the parts' walks side by side
class ToolWorldLayouts : public ::testing::TestWithParam<int> {};

TEST_P(ToolWorldLayouts, AKinematicPlateCarriesTheWeightOfTheGrainsOnIt) {
  // the floor is a tool (a box whose top face is at z = 0), so all the weight goes through it
  Device dev;
  Bed b = make_bed(dev, 0.0, 3);
  b.dem->settings().one_group_rows = GetParam();
  b.dem->settings().sweep_parts = 3;
  Tool floor;
  add_box(floor.mesh, Vec3(0, 0, -0.5 * kD), Vec3(6 * kD, 6 * kD, 0.5 * kD));
  floor.material.rolling = gravel().ground_rolling;  // a gravel-covered floor, as the ground
  ToolWorld tools(dev, *b.dem, {floor});
  Vec3 mean = Vec3::Zero();
  int n = 0;
  // (no horizontal balance is asserted: the walls may hold locked-in friction the floor answers;
  // vertically they hold a little of the weight or press a little onto the floor, by the packing's
  // history: -0.3 to +1.9 % of it over seven row orders, DemSettings::serial_lanes 0, 1, 2, 4, 8,
  // 16 and 64, measured 2026-12-02; -1.2 % in runs of 3 parts)
  for (int k = 0; k < 400; ++k) {
    tools.step();
    if (k >= 300) {
      mean += tools.load(0).wrench.head<3>();
      ++n;
    }
  }
  mean /= n;
  const double weight = b.mass * 9.81;
  std::printf("[ measured ] plate carries %.1f N of %.1f N weight (%+.2f %%), %d contacts\n", -mean.z(), weight,
              100.0 * (-mean.z() / weight - 1.0), tools.load(0).contacts);
  EXPECT_NEAR(-mean.z(), weight, 0.025 * weight);
  EXPECT_DOUBLE_EQ(tools.tool(0).position.z(), 0.0);  // kinematic at rest: it never moves
}

TEST(ToolWorld, FixedParticlesGetNoRowsWithATool) {
  // the bed settled on a kinematic plate, then its lower half fixed (zero inverse mass, as the
  // type-G bucket's riding load): the plate meets only the grains that can still move
  Device dev;
  Bed b = make_bed(dev, 0.0, 3);
  Tool floor;
  add_box(floor.mesh, Vec3(0, 0, -0.5 * kD), Vec3(6 * kD, 6 * kD, 0.5 * kD));
  ToolWorld tools(dev, *b.dem, {floor});
  for (int k = 0; k < 200; ++k) tools.step();
  const int all = tools.load(0).contacts;
  Particles p = b.dem->particles();
  int fixed = 0;
  for (size_t i = 0; i < p.size(); ++i)
    if (p.position[i].z() < 2.0 * kD) {
      p.inv_mass[i] = 0.0;
      p.inv_inertia[i] = 0.0;
      ++fixed;
    }
  b.dem->resize_particles(p);
  tools.step();
  std::printf("[ measured ] %d plate contacts, %d with %d of %zu grains fixed\n", all,
              tools.load(0).contacts, fixed, p.size());
  EXPECT_GT(all, 20);
  EXPECT_GT(fixed, 0);
  // every grain on the plate lies in the bed's lowest layer: fixed, so no contact is left
  EXPECT_EQ(tools.load(0).contacts, 0);
  EXPECT_EQ(tools.load(0).wrench, Vec6::Zero());
}

TEST(ToolWorld, ALoadedPlatenComesToRestWithItsWeightBalanced) {
  // a platen of 500 kg, free along z only, dropped onto a settled bed on a static floor
  Device dev;
  Bed b = make_bed(dev, 0.0, 5);
  std::vector<StaticGeom> geoms = b.dem->geoms();
  geoms.push_back(StaticGeom::plane(Vec3::Zero(), Vec3::UnitZ()));
  b.dem->set_geoms(geoms);
  for (int k = 0; k < 200; ++k) b.dem->step();
  const Particles settled = b.dem->particles();
  const double mass = 500.0;
  Tool platen;
  add_box(platen.mesh, Vec3(0, 0, 0.5 * kD), Vec3(3.95 * kD, 3.95 * kD, 0.5 * kD));
  platen.position = Vec3(0, 0, top_surface(settled, -1, 1, -1, 1) + 0.02 * kD);
  platen.mobility(2, 2) = 1.0 / mass;
  platen.external_force = Vec3(0, 0, -mass * 9.81);
  ToolWorld tools(dev, *b.dem, {platen});
  double push = 0.0, z_start = 0.0;
  int n = 0;
  for (int k = 0; k < 400; ++k) {
    tools.step();
    if (k == 300) z_start = tools.tool(0).position.z();
    if (k >= 300) {
      push += tools.load(0).wrench.z();
      ++n;
    }
  }
  push /= n;
  const double sink = z_start - tools.tool(0).position.z();
  std::printf("[ measured ] grains hold the platen with %.1f N against its %.1f N weight; it sank %.2e m in the "
              "last 0.5 s\n", push, mass * 9.81, sink);
  EXPECT_NEAR(push, mass * 9.81, 0.02 * mass * 9.81);
  EXPECT_LT(std::abs(sink), 0.01 * kD);
  EXPECT_GT(tools.tool(0).position.z(), 2.0 * kD);  // it rests on the bed, not through it
}

TEST(ToolWorld, AToolThatWouldTurnIsRefused) {
  Device dev;
  Bed b = make_bed(dev, 0.0, 1);
  Tool t;
  add_box(t.mesh, Vec3::Zero(), Vec3(kD, kD, kD));
  t.mobility(3, 3) = 1.0;
  EXPECT_THROW(ToolWorld(dev, *b.dem, {t}), InputError);
  // nor may a loaded tool be turned by hand
  Tool loaded;
  add_box(loaded.mesh, Vec3::Zero(), Vec3(kD, kD, kD));
  loaded.mobility(2, 2) = 0.01;
  loaded.omega = Vec3(0.0, 0.0, 1.0);
  EXPECT_THROW(ToolWorld(dev, *b.dem, {loaded}), InputError);
}

// a kinematic paddle turning about the vertical through the bed: its orientation follows the
// prescribed rate, the grains it meets are pushed round the way it turns, and they push back with
// a torque against the turn
TEST(ToolWorld, AKinematicToolTurnsAsPrescribed) {
  Device dev;
  Bed b = make_bed(dev, 0.0, 5);
  std::vector<StaticGeom> geoms = b.dem->geoms();
  geoms.push_back(StaticGeom::plane(Vec3::Zero(), Vec3::UnitZ()));
  b.dem->set_geoms(geoms);
  Tool paddle;
  add_box(paddle.mesh, Vec3(0.2, 0, 0.3), Vec3(0.15, 0.02, 0.25));  // from 0.05 to 0.35 m along x
  paddle.position = Vec3(0, 0, 0.08);
  paddle.omega = Vec3(0, 0, 1.0);  // [1/s], counter-clockwise seen from above
  ToolWorld tools(dev, *b.dem, {paddle});
  const int steps = 60;
  double torque = 0.0;
  for (int k = 0; k < steps; ++k) {
    tools.step();
    torque += tools.load(0).wrench(5) / steps;
  }
  const double turned = steps * b.dem->settings().dt * 1.0;
  const Eigen::Quaterniond expected(Eigen::AngleAxisd(turned, Vec3::UnitZ()));
  EXPECT_LT(tools.tool(0).orientation.angularDistance(expected), 1e-12);
  // the grains within the paddle's reach move round counter-clockwise on average
  const Particles p = b.dem->particles();
  double tangential = 0.0;
  int near = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    const Vec3 r(p.position[i].x(), p.position[i].y(), 0.0);
    if (r.norm() < 0.05 || r.norm() > 0.35 || p.position[i].z() > 0.5) continue;
    tangential += Vec3::UnitZ().cross(r.normalized()).dot(p.velocity[i]);
    ++near;
  }
  std::printf(
      "[ measured ] %d grains within reach, mean tangential speed %.3f m/s, torque on the paddle "
      "%.2f N m\n",
      near, tangential / near, torque);
  EXPECT_GT(tangential / near, 0.01);
  EXPECT_LT(torque, 0.0);
}

TEST_P(ToolWorldLayouts, TwoRunsAreBitIdentical) {
  // a blade pushed through a bed: particles and the blade's force bit for bit the same
  const int one_group_rows = GetParam();
  auto run = [&](std::vector<float>& state, Vec6& load, bool renumbered) {
    Device dev;
    Bed b = make_bed(dev, 0.0, 7);
    b.dem->settings().one_group_rows = one_group_rows;
    b.dem->settings().sweep_parts = 3;
    add_floor(b);
    ToolWorld tools(dev, *b.dem, {blade()});
    for (int k = 0; k < 60; ++k) {
      tools.step();
      if (b.dem->one_item_sweeps()) {
        ASSERT_EQ(b.dem->buffers().row_layout == RowLayout::Runs, one_group_rows == 0) << k;
      }
      if (renumbered && k == 30) {
        // every particle kept under its own number: the grains' and the blade's contacts keep
        // their warm start and colours, so nothing may change
        std::vector<int> same(b.dem->size());
        for (size_t i = 0; i < same.size(); ++i) same[i] = static_cast<int>(i);
        b.dem->renumber_particles(b.dem->particles(), same);
        tools.renumber_particles(same);
      }
    }
    state = velocity_floats(*b.dem);
    load = tools.load(0).wrench;
  };
  std::vector<float> a, b, c;
  Vec6 la, lb, lc;
  run(a, la, false);
  run(b, lb, false);
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(float)), 0);
  EXPECT_EQ(la, lb);
  EXPECT_GT(std::abs(la.x()), 0.0);  // the blade did meet the grains
  // the same run with the particles renumbered in place halfway (DemWorld and ToolWorld
  // renumber_particles, as the type-G terrain calls them when particles merge or spawn)
  run(c, lc, true);
  ASSERT_EQ(a.size(), c.size());
  EXPECT_EQ(std::memcmp(a.data(), c.data(), a.size() * sizeof(float)), 0) << "renumbered in place";
  EXPECT_EQ(la, lc) << "renumbered in place";
}

INSTANTIATE_TEST_SUITE_P(ToolWorld, ToolWorldLayouts, ::testing::Values(kPgsOneGroupRows, 0));

TEST(ToolWorld, KinematicToolRowsGiveTheSameBitsInOneLaunchAsLaunchedPerSweep) {
  // a blade pushed through a bed: its rows solved inside the one-group sweep launch
  // (DemSettings::one_group_rows above the rows), with a launch per colour and a tool launch
  // per sweep (one_group_rows 0), and with the particle rows in one group and a tool launch per
  // sweep (one_group_rows at the most particle rows of a step, below particle and tool rows
  // together) end in the same particles and the same load. Coloured (serial_lanes 0): a CPU
  // device otherwise walks the one-group systems interleaved, another order than the launches'
  int most_particle_rows = 0;
  auto run = [&](int one_group_rows, std::vector<float>& state, Vec6& load) {
    Device dev;
    Bed b = make_bed(dev, 0.0, 11);
    b.dem->settings().one_group_rows = one_group_rows;
    b.dem->settings().serial_lanes = 0;
    add_floor(b);
    ToolWorld tools(dev, *b.dem, {blade()});
    int rows = 0;
    for (int k = 0; k < 40; ++k) {
      tools.step();
      rows += tools.load(0).contacts;
      most_particle_rows = std::max(most_particle_rows, b.dem->stats().contacts);
    }
    state = velocity_floats(*b.dem);
    load = tools.load(0).wrench;
    return rows;
  };
  std::vector<float> a, b, c;
  Vec6 la, lb, lc;
  const int rows = run(std::numeric_limits<int>::max(), a, la);
  run(0, b, lb);
  run(most_particle_rows, c, lc);
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(float)), 0);
  EXPECT_EQ(la, lb);
  ASSERT_EQ(a.size(), c.size());
  EXPECT_EQ(std::memcmp(a.data(), c.data(), a.size() * sizeof(float)), 0);
  EXPECT_EQ(la, lc);
  EXPECT_GT(std::abs(la.x()), 0.0);  // the blade did meet the grains
  std::printf("[ measured ] %d blade rows over 40 steps: the same bits either way\n", rows);
}

}  // namespace
}  // namespace talus
