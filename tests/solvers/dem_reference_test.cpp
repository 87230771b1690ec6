// Every DEM device stage against its double-precision twin (solvers/dem_reference) on PoCL,
// with fresh random inputs each run. Discrete results (scan, cells, contact pairs, adjacency,
// colours, partition) must match exactly; real-valued ones within float rounding. Each test
// prints its seed on failure (replay with TALUS_TEST_SEED) and its measured differences.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <set>
#include <utility>

#include "host/error.hpp"
#include "host/scan.hpp"
#include "solvers/dem_reference.hpp"
#include "solvers/dem_world.hpp"
#include "tests/solvers/dem_test_util.hpp"

namespace talus {
namespace {

namespace ref = reference;
using test::Scene;
using test::SceneOptions;
using test::Tally;

std::string at(const char* what, size_t i) { return std::string(what) + " " + std::to_string(i); }

// a device world holding the scene's particles
std::unique_ptr<DemWorld> make_world(const Scene& s) {
  auto world = std::make_unique<DemWorld>(test::shared_device(), s.material, s.settings, s.bounds,
                                          s.geoms);
  world->set_particles(s.particles);
  return world;
}

// a device world of a random scene from a fresh seed (the caller traces `seed_note`), and the
// generator for whatever else the test draws. The colouring tests ask for serial_lanes 0: a CPU
// device otherwise walks such a small system in one work-item, interleaved and not coloured
struct RandomWorld {
  std::string seed_note;
  std::mt19937_64 rng;
  std::unique_ptr<DemWorld> world;
};
RandomWorld random_world(int serial_lanes = kSerialLanes, int one_group_rows = kPgsOneGroupRows) {
  const uint64_t seed = test::fresh_seed();
  RandomWorld out{test::seed_note(seed), std::mt19937_64(seed), nullptr};
  Scene scene = test::random_scene(out.rng);
  scene.settings.serial_lanes = serial_lanes;
  scene.settings.one_group_rows = one_group_rows;
  out.world = make_world(scene);
  return out;
}

// the first stages of a step on the device: the broad and narrow phases and the adjacency; the
// contacts found
int find_device_contacts(DemWorld& w) {
  w.broad_phase();
  w.narrow_phase();
  w.build_adjacency();
  return w.buffers().n_contacts;
}

// the device's inputs, read back (float values, so the reference sees exactly the same)
ref::StepParams params_of(const DemWorld& w) { return ref::from_device(w.params()); }

std::vector<StaticGeom> geoms_of(const DemWorld& w) {
  std::vector<StaticGeom> out;
  auto raw = w.buffers().geoms.download(w.geoms().size());
  for (const TlGeom& g : raw) out.push_back(ref::from_device(g));
  return out;
}

std::vector<ref::Contact> contacts_of(const DemWorld& w, int which) {
  const DemBuffers& b = w.buffers();
  std::vector<ref::Contact> out;
  for (const TlContact& c : b.contacts[which].download(b.n_contacts))
    out.push_back(ref::from_device(c));
  return out;
}
std::vector<ref::Contact> current_contacts(const DemWorld& w) {
  return contacts_of(w, w.buffers().current);
}

std::vector<ref::Row> rows_of(const DemWorld& w) {
  std::vector<ref::Row> out;
  const DemBuffers& b = w.buffers();
  const std::vector<TlParticleRow> rows = b.rows.download(b.n_contacts);
  const std::vector<TlImpulse> impulses = b.impulses.download(b.n_contacts);
  for (size_t k = 0; k < rows.size(); ++k) out.push_back(ref::from_device(rows[k], impulses[k]));
  return out;
}

// the scene's grid must be the one the ambiguity filter assumed
void expect_grid_as_assumed(const Scene& s, const DemWorld& w) {
  ref::StepParams want = test::expected_grid(s);
  ref::StepParams got = params_of(w);
  ASSERT_EQ(got.cell_size, want.cell_size);
  ASSERT_EQ(got.grid_nx, want.grid_nx);
  ASSERT_EQ(got.grid_ny, want.grid_ny);
  ASSERT_EQ(got.grid_nz, want.grid_nz);
  ASSERT_EQ(got.margin_rel, want.margin_rel);
}

// random warm-start impulses on the device's current contacts: normal impulses of both signs of
// interest (zero included), friction partly outside the cone and off the tangent plane,
// rolling mostly beyond its limit
void inject_impulses(DemWorld& w, std::mt19937_64& rng) {
  DemBuffers& b = w.buffers();
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  auto sym = [&](float a) { return a * (2.0f * unit(rng) - 1.0f); };
  auto contacts = b.contacts[b.current].download(b.n_contacts);
  for (size_t c = 0; c < contacts.size(); ++c) {
    TlContact& con = contacts[c];
    // every seventh pulls (a cohesive bond's tension; clamped to the bond's limit, 0 when dry)
    float ln = c % 5 == 0 ? 0.0f : c % 7 == 3 ? -3e-3f * unit(rng) : 5e-3f * unit(rng);
    con.impulse_t = cl_float4{{sym(2e-3f), sym(2e-3f), sym(2e-3f), ln}};
    con.impulse_r = cl_float4{{sym(5e-7f), sym(5e-7f), sym(5e-7f), 0.0f}};
  }
  b.contacts[b.current].upload(contacts);
}

// a colouring is valid when every contact appears exactly once in `order`, row_of_contact is
// its inverse, the ranges cover all rows, and no dynamic body appears twice in one colour
void expect_valid_colouring(const std::vector<ref::Contact>& contacts,
                            const std::vector<int>& order,
                            const std::vector<int>& row_of_contact,
                            const std::vector<int>& colour_start) {
  int n = static_cast<int>(contacts.size());
  ASSERT_EQ(static_cast<int>(order.size()), n);
  std::vector<int> seen(n, 0);
  for (int row = 0; row < n; ++row) {
    ASSERT_TRUE(order[row] >= 0 && order[row] < n) << "row " << row;
    seen[order[row]]++;
    EXPECT_EQ(row_of_contact[order[row]], row) << "row " << row;
  }
  for (int c = 0; c < n; ++c) EXPECT_EQ(seen[c], 1) << "contact " << c << " in order";
  ASSERT_GE(colour_start.size(), 2u);
  EXPECT_EQ(colour_start.front(), 0);
  EXPECT_EQ(colour_start.back(), n);
  for (size_t k = 0; k + 1 < colour_start.size(); ++k) {
    EXPECT_LE(colour_start[k], colour_start[k + 1]);
    std::set<int> bodies;
    for (int row = colour_start[k]; row < colour_start[k + 1]; ++row) {
      const ref::Contact& c = contacts[order[row]];
      for (int body : {c.a, c.b}) {
        if (body < 0) continue;  // static geometry never blocks
        EXPECT_TRUE(bodies.insert(body).second)
            << "body " << body << " twice in colour " << k << " (row " << row << ")";
      }
    }
  }
}

// velocities and angular velocities of device and reference bodies
void compare_bodies(const Particles& got, const Particles& want, double rel, double abs_v,
                    double abs_w, const std::string& label) {
  Tally v(label + " velocity [m/s]"), w(label + " omega [1/s]");
  ASSERT_EQ(got.size(), want.size());
  for (size_t i = 0; i < got.size(); ++i) {
    v.vector(got.velocity[i], want.velocity[i], rel, abs_v, at("body", i));
    w.vector(got.omega[i], want.omega[i], rel, abs_w, at("body", i));
  }
  v.expect_within();
  w.expect_within();
}

// impulses of device and reference rows
void compare_impulses(const std::vector<ref::Row>& got, const std::vector<ref::Row>& want,
                      double rel, double abs_lin, double abs_rot, const std::string& label) {
  Tally n(label + " normal impulse [N s]"), t(label + " friction impulse [N s]"),
      r(label + " rolling impulse [N m s]");
  ASSERT_EQ(got.size(), want.size());
  for (size_t k = 0; k < got.size(); ++k) {
    n.scalar(got[k].impulse_n, want[k].impulse_n, rel, abs_lin, at("row", k));
    t.vector(got[k].impulse_t, want[k].impulse_t, rel, abs_lin, at("row", k));
    r.vector(got[k].impulse_r, want[k].impulse_r, rel, abs_rot, at("row", k));
  }
  n.expect_within();
  t.expect_within();
  r.expect_within();
}

// ---------------------------------------------------------------------------------------------
// scan

TEST(ReferenceScan, DeviceScanMatchesExactlyOnRandomArrays) {
  uint64_t seed = test::fresh_seed();
  SCOPED_TRACE(test::seed_note(seed));
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> value(0, 400);  // 4.2 million of them stay within an int
  Device& dev = test::shared_device();
  DeviceScan scan(dev);
  // one block's edges (TL_SCAN_GROUP x TL_SCAN_ITEMS = 2048 items), two levels and three
  for (size_t n : {size_t(0), size_t(1), size_t(7), size_t(8), size_t(255), size_t(256),
                   size_t(2047), size_t(2048), size_t(2049), size_t(70000), size_t(4200000)}) {
    SCOPED_TRACE("length " + std::to_string(n));
    std::vector<int> in(n);
    for (int& x : in) x = value(rng);
    Buffer<int> d_in(dev, 1), d_out(dev, 1);
    d_in.upload(in);
    scan.exclusive(d_in, d_out, n);
    EXPECT_EQ(d_out.download(n + 1), ref::exclusive_scan(in));
  }
}

// ---------------------------------------------------------------------------------------------
// broad and narrow phase

TEST(ReferenceBroadPhase, CellListsMatchExactly) {
  uint64_t seed = test::fresh_seed();
  SCOPED_TRACE(test::seed_note(seed));
  std::mt19937_64 rng(seed);
  Scene s = test::random_scene(rng);
  auto world = make_world(s);
  expect_grid_as_assumed(s, *world);
  world->broad_phase();

  ref::StepParams p = params_of(*world);
  ref::CellLists want = ref::cell_lists(world->particles(), p);
  const DemBuffers& b = world->buffers();
  size_t n = world->size();
  EXPECT_EQ(b.particle_cell.download(n), want.particle_cell);
  EXPECT_EQ(b.cell_start.download(p.cells() + 1), want.cell_start);
  EXPECT_EQ(b.cell_particles.download(n), want.cell_particles);
  // the top layer lies above the grid: clamped cells must hold particles
  int top_layer = (p.grid_nz - 1) * p.grid_ny * p.grid_nx;
  EXPECT_GT(want.cell_start.back() - want.cell_start[top_layer], 0);
}

// a grid region (DemWorld::set_grid_region, the type-G zone's) that holds every particle, in
// bounds four times the particles' extent: the grid keeps only the lattice cells around them, and
// sixty steps, the region set anew before each from where the particles are, end with the whole
// grid's bytes
TEST(ReferenceBroadPhase, AGridRegionAroundTheParticlesGivesTheWholeGridsBits) {
  uint64_t seed = test::fresh_seed();
  SCOPED_TRACE(test::seed_note(seed));
  std::mt19937_64 rng(seed);
  Scene s = test::random_scene(rng);
  const Bounds box = centres_box(s.particles);
  const Vec3 extent = box.hi - box.lo;
  s.bounds = Bounds{box.lo - 1.5 * extent, box.hi + 1.5 * extent};
  auto whole = make_world(s);
  auto fitted = make_world(s);
  const size_t n = s.particles.size();
  for (int step = 0; step < 60; ++step) {
    fitted->set_grid_region(centres_box(fitted->particles()));
    if (step == 0) {
      const ref::StepParams full = params_of(*whole), part = params_of(*fitted);
      EXPECT_LT(part.cells() * 8, full.cells()) << "the region's grid is not smaller";
      EXPECT_GT(part.grid_i0 + part.grid_j0 + part.grid_k0, 0);
    }
    whole->step();
    fitted->step();
    ASSERT_EQ(whole->stats().contacts, fitted->stats().contacts) << "step " << step;
  }
  auto bytes = [&](DemWorld& w) {
    auto x = w.buffers().position.download(n);
    auto v = w.buffers().velocity.download(n);
    auto o = w.buffers().omega.download(n);
    x.insert(x.end(), v.begin(), v.end());
    x.insert(x.end(), o.begin(), o.end());
    return x;
  };
  const auto a = bytes(*whole), b = bytes(*fitted);
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * sizeof(a[0])));
}

// a region that is not a finite box (NaN, infinite, lo above hi) is refused and leaves the grid
// the world had; nullopt brings the whole bounds' grid back
TEST(ReferenceBroadPhase, ABadGridRegionIsRefusedAndChangesNothing) {
  RandomWorld rw = random_world();
  SCOPED_TRACE(rw.seed_note);
  DemWorld& w = *rw.world;
  const ref::StepParams whole = params_of(w);
  Bounds half = centres_box(w.particles());
  half.hi.z() = 0.5 * (half.lo.z() + half.hi.z());
  w.set_grid_region(half);
  const ref::StepParams part = params_of(w);
  ASSERT_LT(part.grid_nz, whole.grid_nz);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  for (const Bounds& bad : {Bounds{Vec3(nan, 0, 0), half.hi}, Bounds{half.lo, Vec3(0, inf, 0)},
                            Bounds{half.hi + Vec3::Ones(), half.lo}}) {
    EXPECT_THROW(w.set_grid_region(bad), Error);
    ASSERT_TRUE(w.grid_region().has_value());
    EXPECT_EQ(params_of(w).grid_nz, part.grid_nz);
    EXPECT_EQ(params_of(w).grid_k0, part.grid_k0);
  }
  w.set_grid_region(std::nullopt);
  EXPECT_EQ(params_of(w).grid_nz, whole.grid_nz);
  EXPECT_EQ(params_of(w).grid_k0, 0);
}

// a grid region that holds the lower half of the particles alone: the device places each particle
// as the reference does (its lattice cell, offset to the region's grid, the rest clamped into the
// border cells), and the narrow phase still finds every pair the whole grid finds
TEST(ReferenceBroadPhase, AGridRegionClampsTheParticlesOutsideItAndMissesNoPair) {
  uint64_t seed = test::fresh_seed();
  SCOPED_TRACE(test::seed_note(seed));
  std::mt19937_64 rng(seed);
  const Scene s = test::random_scene(rng);
  Bounds region = centres_box(s.particles);
  region.hi.z() = 0.5 * (region.lo.z() + region.hi.z());
  auto whole = make_world(s);
  auto fitted = make_world(s);
  fitted->set_grid_region(region);
  expect_grid_as_assumed(s, *whole);
  const ref::StepParams p = params_of(*fitted);
  EXPECT_LT(p.grid_nz, params_of(*whole).grid_nz);
  fitted->broad_phase();
  const ref::CellLists want = ref::cell_lists(fitted->particles(), p);
  const DemBuffers& b = fitted->buffers();
  const size_t n = fitted->size();
  EXPECT_EQ(b.particle_cell.download(n), want.particle_cell);
  EXPECT_EQ(b.cell_start.download(p.cells() + 1), want.cell_start);
  EXPECT_EQ(b.cell_particles.download(n), want.cell_particles);
  // the top layer of the region's grid holds the clamped upper half
  const int top_layer = (p.grid_nz - 1) * p.grid_ny * p.grid_nx;
  EXPECT_GT(want.cell_start.back() - want.cell_start[top_layer], static_cast<int>(n / 4));
  // the same pairs, as sets (their order may differ where particles share a clamped cell)
  whole->broad_phase();
  whole->narrow_phase();
  fitted->narrow_phase();
  auto pairs = [](const std::vector<ref::Contact>& cs) {
    std::set<std::pair<int, int>> out;
    for (const ref::Contact& c : cs) out.insert({c.a, c.b});
    return out;
  };
  const auto got = pairs(current_contacts(*fitted)), all = pairs(current_contacts(*whole));
  EXPECT_EQ(got, all);
  EXPECT_GT(all.size(), n / 4);  // a test with pairs to find
}

// the contacts of one narrow phase on the device against the reference's own detection: the
// same pairs in the same order, geometry within float rounding; returns how many of each kind
struct ContactKinds {
  size_t contacts = 0;
  int plane = 0, box = 0, inside_box = 0, speculative = 0;
  std::set<int> boxes;  // the static geometries with a box contact
};
ContactKinds expect_narrow_phase_matches(const Scene& s) {
  auto world = make_world(s);
  expect_grid_as_assumed(s, *world);
  world->broad_phase();
  world->narrow_phase();

  // the reference runs its own broad phase and loops over all static geometry: the whole
  // detection path is independent, the device's column bins included
  ref::StepParams p = params_of(*world);
  Particles particles = world->particles();
  std::vector<StaticGeom> geoms = geoms_of(*world);
  ref::ContactSet want = ref::find_contacts(particles, geoms, ref::cell_lists(particles, p), p);
  std::vector<ref::Contact> got = current_contacts(*world);
  const DemBuffers& b = world->buffers();
  EXPECT_EQ(b.owner_offsets[b.current].download(world->size() + 1), want.owner_offsets);
  ContactKinds kinds;
  EXPECT_EQ(got.size(), want.contacts.size());
  if (got.size() != want.contacts.size()) return kinds;
  kinds.contacts = got.size();

  // same pairs in the same order; geometry within float rounding of the inputs
  Tally normal("contact normal"), gap("contact gap [m]"), arms("contact arms [m]"),
      reduced("contact R* [m]"), stiffness("contact k_n [N/m^1.5]");
  for (size_t c = 0; c < got.size(); ++c) {
    const ref::Contact& g = got[c];
    const ref::Contact& w = want.contacts[c];
    EXPECT_EQ(g.a, w.a) << "contact " << c;
    EXPECT_EQ(g.b, w.b) << "contact " << c;
    if (g.a != w.a || g.b != w.b) return kinds;
    double r = particles.radius[w.a];
    // the normal is d/|d|, d the float difference of two points about |x| from the origin, so
    // each component of d is rounded by about 2^-24 |x| and the direction by that over |d|: a
    // centre outside a box and near its surface (|d| = r + gap small) has a normal good only to
    // a few 1e-5 (seed 2492422959582495625 made 1.2e-5 against the former flat 1e-5)
    const double centre_distance = (w.b >= 0 ? r + particles.radius[w.b] : r) + w.gap;
    const double rounding = 8.0 * 0x1p-24 * (particles.position[w.a].norm() + r);
    const double normal_tol =
        centre_distance > 0.0 ? std::max(1e-5, rounding / centre_distance) : 1e-5;
    normal.vector(g.normal, w.normal, 0.0, normal_tol, at("contact", c));
    gap.scalar(g.gap, w.gap, 0.0, 1e-5 * r, at("contact", c));
    arms.vector(g.arm_a, w.arm_a, 0.0, 1e-5 * r, at("contact", c));
    arms.vector(g.arm_b, w.arm_b, 0.0, 1e-5 * r, at("contact", c));
    reduced.scalar(g.reduced_radius, w.reduced_radius, 1e-6, 0.0, at("contact", c));
    stiffness.scalar(g.stiffness, w.stiffness, 1e-5, 0.0, at("contact", c));
    EXPECT_EQ(g.impulse_n, 0.0);
    EXPECT_EQ(g.impulse_t, Vec3::Zero());
    EXPECT_EQ(g.impulse_r, Vec3::Zero());
    const bool is_box = w.b < 0 && geoms[-1 - w.b].type == StaticGeom::Type::Box;
    if (w.b < 0) (is_box ? kinds.box : kinds.plane)++;
    if (is_box) kinds.boxes.insert(-1 - w.b);
    if (is_box && w.gap < -r) kinds.inside_box++;
    if (w.gap > 0.0) kinds.speculative++;
  }
  normal.expect_within();
  gap.expect_within();
  arms.expect_within();
  reduced.expect_within();
  stiffness.expect_within();
  return kinds;
}

TEST(ReferenceNarrowPhase, ContactsMatchPairsOrderAndGeometry) {
  uint64_t seed = test::fresh_seed();
  SCOPED_TRACE(test::seed_note(seed));
  std::mt19937_64 rng(seed);
  const Scene s = test::random_scene(rng);
  const ContactKinds k = expect_narrow_phase_matches(s);
  // the sample exercised every kind of contact
  EXPECT_GT(k.plane, 0);
  EXPECT_GT(k.box, 0);
  EXPECT_GT(k.inside_box, 0);
  EXPECT_GT(k.speculative, 0);
  std::printf(
      "[ measured ] %zu particles, %zu contacts (%d plane, %d box of which %d centre "
      "inside, %d speculative)\n",
      s.particles.size(), k.contacts, k.plane, k.box, k.inside_box, k.speculative);
}

// each pair's own speculative reach (DemSettings::pair_reach): the device finds the reference's
// contacts with the reach 2 h (closing speed + |g| h) of each pair and each wall, at most the
// fastest's; fewer than with the fastest's reach for every pair, and still speculative ones (the
// scene's grains move at up to 0.5 m/s in every component)
TEST(ReferenceNarrowPhase, EachPairsOwnReachMatchesAndMakesFewerContacts) {
  uint64_t seed = test::fresh_seed();
  SCOPED_TRACE(test::seed_note(seed));
  std::mt19937_64 rng(seed);
  Scene s = test::random_scene(rng);
  s.settings.max_speed = 2.0;  // [m/s] a reach of 2 h v_max = 0.4 r at the scene's 1 ms
  // particles within rounding of either rule's threshold are dropped for both
  std::vector<char> drop = test::ambiguous(s);
  s.settings.pair_reach = true;
  const std::vector<char> drop_own = test::ambiguous(s);
  for (std::size_t i = 0; i < drop.size(); ++i) drop[i] = drop[i] || drop_own[i];
  s.particles = test::keep(s.particles, drop);
  s.settings.pair_reach = false;
  const ContactKinds fastest = expect_narrow_phase_matches(s);
  s.settings.pair_reach = true;
  const ContactKinds own = expect_narrow_phase_matches(s);
  EXPECT_GT(own.speculative, 0);
  EXPECT_LT(own.contacts, fastest.contacts);
  std::printf(
      "[ measured ] %zu particles: %zu contacts with the fastest's reach, %zu with each "
      "pair's own (%d speculative)\n",
      s.particles.size(), fastest.contacts, own.contacts, own.speculative);
}

// many small boxes among the particles, as the multiscale terrain's voxel columns are (issue
// 14): the device tests each particle only against the boxes binned to its grid column, and
// still finds every contact the reference finds by looping over them all
TEST(ReferenceNarrowPhase, ManyBoxesBinnedByColumnGiveEveryContact) {
  uint64_t seed = test::fresh_seed();
  SCOPED_TRACE(test::seed_note(seed));
  std::mt19937_64 rng(seed);
  Scene s = test::random_scene(rng);
  // forty boxes of half a grain to two grains, half of them upright columns, at random places
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double r = SceneOptions{}.radius;
  const Vec3 extent = s.bounds.hi - s.bounds.lo;
  for (int k = 0; k < 40; ++k) {
    const Vec3 centre = s.bounds.lo + Vec3(unit(rng), unit(rng), unit(rng)).cwiseProduct(extent);
    const Vec3 half = r * Vec3(0.5 + 1.5 * unit(rng), 0.5 + 1.5 * unit(rng), 0.5 + 1.5 * unit(rng));
    Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();
    if (k % 2 == 1) {
      const Vec3 axis = Vec3(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5).normalized();
      axes = Eigen::AngleAxisd(M_PI * unit(rng), axis).toRotationMatrix();
    }
    StaticGeom g = StaticGeom::box(test::as_float(centre), test::as_float(half), axes);
    for (int c = 0; c < 3; ++c) g.axes.col(c) = test::as_float(Vec3(g.axes.col(c)));
    s.geoms.push_back(g);
  }
  // particles whose decisions sit within rounding of a threshold of a new box leave too; with no
  // speculative reach and with one (2 h v_max = 0.4 r at the scene's 1 ms: the columns list the
  // boxes within the largest radius, its margin and that reach, dem_world.cpp bin_geoms)
  for (int pass = 0; pass < 10; ++pass) {
    s.settings.max_speed = 2.0;  // [m/s]
    std::vector<char> drop = test::ambiguous(s);
    s.settings.max_speed = 0.0;
    const std::vector<char> drop_still = test::ambiguous(s);
    for (std::size_t i = 0; i < drop.size(); ++i) drop[i] = drop[i] || drop_still[i];
    if (std::find(drop.begin(), drop.end(), 1) == drop.end()) break;
    s.particles = test::keep(s.particles, drop);
  }
  s.settings.max_speed = 2.0;
  const ContactKinds speculative = expect_narrow_phase_matches(s);
  EXPECT_GT(speculative.boxes.size(), 20u);
  s.settings.max_speed = 0.0;
  const ContactKinds k = expect_narrow_phase_matches(s);
  // most of the new boxes touch a particle, and the bins did cull: a column lists fewer
  // geometries than there are
  EXPECT_GT(k.boxes.size(), 20u);
  auto world = make_world(s);
  world->broad_phase();
  world->narrow_phase();  // bins the geometry it reads
  const std::vector<int> start = world->buffers().geom_column_start.download(
      static_cast<size_t>(world->params().grid_nx) * world->params().grid_ny + 1);
  const size_t columns = start.size() - 1;
  EXPECT_LT(static_cast<size_t>(start.back()), columns * s.geoms.size());
  std::printf(
      "[ measured ] %zu particles, %zu static geometries, %zu contacts (%d box, with %zu "
      "boxes); the bins hold %.1f geometries a column\n",
      s.particles.size(), s.geoms.size(), k.contacts, k.box, k.boxes.size(),
      static_cast<double>(start.back()) / columns);
}

// the write pass's two paths (DemSettings::narrow_phase_slots): a particle written from the
// partners its count pass kept gives the bytes of one visited again. Worlds with 0 slots (every
// particle with a contact visited twice), 2 (both paths) and the default step three times from
// one random scene (the second and third narrow phases warm start from the last); every contact
// byte and every particle state byte must agree. The scene's fastest reach makes particles own up
// to ~6 contacts
TEST(ReferenceNarrowPhase, ContactsWrittenFromTheSlotsAreThoseOfASecondVisit) {
  uint64_t seed = test::fresh_seed();
  SCOPED_TRACE(test::seed_note(seed));
  std::mt19937_64 rng(seed);
  Scene s = test::random_scene(rng);
  s.settings.max_speed = 2.0;  // [m/s] a reach of 2 h v_max = 0.4 r at the scene's 1 ms
  struct Outcome {
    std::vector<int> owned;           // contacts each particle owns, in the last step
    std::vector<TlContact> contacts;  // the last step's
    std::vector<cl_float4> state;     // positions, velocities and angular velocities after it
    std::vector<int> partners;        // the last count pass's slots, slots per particle
  };
  const auto run = [&](int slots) {
    s.settings.narrow_phase_slots = slots;
    auto world = make_world(s);
    for (int step = 0; step < 3; ++step) world->step();
    const DemBuffers& b = world->buffers();
    const int last = 1 - b.current;
    const size_t n = world->size();
    Outcome o;
    const std::vector<int> offsets = b.owner_offsets[last].download(n + 1);
    for (size_t i = 0; i < n; ++i) o.owned.push_back(offsets[i + 1] - offsets[i]);
    o.contacts = b.contacts[last].download(b.n_contacts);
    if (slots > 0) o.partners = b.contact_partners.download(n * static_cast<size_t>(slots));
    o.state = b.position.download(n);
    for (auto buffer : {&DemBuffers::velocity, &DemBuffers::omega}) {
      const auto v = (b.*buffer).download(n);
      o.state.insert(o.state.end(), v.begin(), v.end());
    }
    return o;
  };
  const Outcome visited = run(0);
  const Outcome both = run(2);
  const Outcome kept = run(kNarrowPhaseSlots);
  // with 2 slots some particles are written from them and some visited again
  const auto over = [&](int slots) {
    return std::count_if(visited.owned.begin(), visited.owned.end(),
                         [&](int k) { return k > slots; });
  };
  EXPECT_GT(over(2), 0);
  EXPECT_LT(over(2), static_cast<long>(visited.owned.size()));
  // the count pass kept each particle's partners in its slots: the other bodies of the contacts
  // it owns, in order, as many as fit (what the write pass wrote from)
  for (const auto& [o, slots] : {std::pair{&both, 2}, std::pair{&kept, kNarrowPhaseSlots}}) {
    size_t first = 0;
    for (size_t i = 0; i < visited.owned.size(); ++i) {
      for (int k = 0; k < std::min(visited.owned[i], slots); ++k)
        ASSERT_EQ(o->partners[i * static_cast<size_t>(slots) + static_cast<size_t>(k)],
                  visited.contacts[first + static_cast<size_t>(k)].b)
            << slots << " slots, particle " << i << ", partner " << k;
      first += static_cast<size_t>(visited.owned[i]);
    }
  }
  for (const Outcome* o : {&both, &kept}) {
    EXPECT_EQ(o->owned, visited.owned);
    ASSERT_EQ(o->contacts.size(), visited.contacts.size());
    EXPECT_EQ(0, std::memcmp(o->contacts.data(), visited.contacts.data(),
                             visited.contacts.size() * sizeof(TlContact)));
    ASSERT_EQ(o->state.size(), visited.state.size());
    EXPECT_EQ(0, std::memcmp(o->state.data(), visited.state.data(),
                             visited.state.size() * sizeof(cl_float4)));
  }
  std::printf(
      "[ measured ] %zu particles own %zu contacts, at most %d each; %ld own more than 2, %ld more "
      "than the default %d slots\n",
      visited.owned.size(), visited.contacts.size(),
      *std::max_element(visited.owned.begin(), visited.owned.end()), over(2),
      over(kNarrowPhaseSlots), kNarrowPhaseSlots);
}

// DemSettings::narrow_phase_slots outside 0-kMaxNarrowPhaseSlots is refused, naming the field;
// the range's ends are taken
TEST(ReferenceNarrowPhase, SlotsOutsideTheirRangeAreRefused) {
  std::mt19937_64 rng(1);
  Scene s = test::random_scene(rng);
  for (int slots : {0, kMaxNarrowPhaseSlots}) {
    s.settings.narrow_phase_slots = slots;
    EXPECT_NO_THROW(make_world(s)->step()) << slots << " slots";
  }
  for (int slots : {-1, kMaxNarrowPhaseSlots + 1}) {
    s.settings.narrow_phase_slots = slots;
    try {
      make_world(s);
      ADD_FAILURE() << slots << " slots accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("DemSettings.narrow_phase_slots"), std::string::npos)
          << e.what();
    }
  }
}

// a random world stepped once, its last step's contacts as stored on the device (impulses
// solved: the warm-start source), this step's contacts found on the device after `between` (a
// change of the world between the steps), and the reference's from the device's positions with
// the same source (static contacts matched with `match_static`). Positions moved: pairs may now
// sit anywhere near the margin, so callers compare the impulse matching on the pairs both found
struct WarmStartCase {
  std::string seed_note;  // the fresh seed, for the caller's SCOPED_TRACE
  ref::ContactSet previous;
  std::vector<ref::Contact> got;
  ref::ContactSet want;
  std::map<std::pair<int, int>, const ref::Contact*> want_by_pair;  // into want.contacts
};

WarmStartCase warm_start_case(const std::function<void(DemWorld&)>& between, bool match_static) {
  const uint64_t seed = test::fresh_seed();
  std::mt19937_64 rng(seed);
  Scene s = test::random_scene(rng);
  auto world = make_world(s);
  world->step();
  WarmStartCase out;
  out.seed_note = test::seed_note(seed);
  const DemBuffers& b = world->buffers();
  const int prev = 1 - b.current;
  out.previous.contacts = contacts_of(*world, prev);
  out.previous.owner_offsets = b.owner_offsets[prev].download(world->size() + 1);
  between(*world);
  world->broad_phase();
  world->narrow_phase();
  out.got = current_contacts(*world);
  const ref::StepParams p = params_of(*world);
  const Particles particles = world->particles();
  out.want = ref::find_contacts(particles, geoms_of(*world), ref::cell_lists(particles, p), p,
                                &out.previous, match_static);
  for (const ref::Contact& c : out.want.contacts) out.want_by_pair[{c.a, c.b}] = &c;
  return out;
}

TEST(ReferenceNarrowPhase, WarmStartCarriesImpulsesToTheSamePairs) {
  const WarmStartCase w = warm_start_case([](DemWorld&) {}, true);
  SCOPED_TRACE(w.seed_note);
  const std::vector<ref::Contact>& got = w.got;
  const ref::ContactSet& previous = w.previous;

  // compare on the pairs both found (float rounding may flip a pair at the margin now)
  int carried = 0, fresh = 0, unmatched = 0;
  for (size_t c = 0; c < got.size(); ++c) {
    auto it = w.want_by_pair.find({got[c].a, got[c].b});
    if (it == w.want_by_pair.end()) {
      ++unmatched;
      continue;
    }
    const ref::Contact& want = *it->second;
    EXPECT_EQ(got[c].impulse_n, want.impulse_n) << "contact " << c;
    EXPECT_EQ(got[c].impulse_t, want.impulse_t) << "contact " << c;
    EXPECT_EQ(got[c].impulse_r, want.impulse_r) << "contact " << c;
    EXPECT_EQ(got[c].previous, want.previous) << "contact " << c;
    (want.impulse_n != 0.0 || want.impulse_t != Vec3::Zero() ? carried : fresh)++;
  }
  // every carried impulse is the one last step solved for this pair, which `previous` names
  for (size_t c = 0; c < got.size(); ++c) {
    int a = got[c].a, bb = got[c].b;
    const ref::Contact* old = nullptr;
    int old_index = -1;
    for (int k = previous.owner_offsets[a]; k < previous.owner_offsets[a + 1]; ++k)
      if (previous.contacts[k].b == bb) {
        old = &previous.contacts[k];
        old_index = k;
      }
    EXPECT_EQ(got[c].previous, old_index) << "contact " << c;
    if (old == nullptr) {
      EXPECT_EQ(got[c].impulse_n, 0.0) << "new contact " << c << " has an impulse";
    } else {
      EXPECT_EQ(got[c].impulse_n, old->impulse_n) << "contact " << c;
      EXPECT_EQ(got[c].impulse_t, old->impulse_t) << "contact " << c;
    }
  }
  EXPECT_LE(unmatched, 2) << "more pairs differ than float rounding at the margin explains";
  EXPECT_GT(carried, 0);
  std::printf("[ measured ] %zu contacts: %d carried impulses, %d without, %d pairs only on "
              "the device\n",
              got.size(), carried, fresh, unmatched);
}

// geometry renumbered between steps (DemWorld::set_geoms, GeomChange::Renumbered: the type-G
// terrain's boxes): particle pairs carry last step's impulses, static contacts start from zero,
// as the reference with match_static off; both still name the same pair of last step
// (`previous`, what the colouring carries: a colour depends on the bodies alone)
TEST(ReferenceNarrowPhase, RenumberedGeometryKeepsOnlyThePairsWarmStart) {
  const WarmStartCase w = warm_start_case(
      [](DemWorld& world) { world.set_geoms(world.geoms(), GeomChange::Renumbered); }, false);
  SCOPED_TRACE(w.seed_note);
  const std::vector<ref::Contact>& got = w.got;
  int pairs_carried = 0, static_contacts = 0, static_named = 0;
  for (size_t c = 0; c < got.size(); ++c) {
    if (got[c].b < 0) {
      ++static_contacts;
      static_named += got[c].previous >= 0 ? 1 : 0;
      EXPECT_EQ(got[c].impulse_n, 0.0) << "static contact " << c << " kept an impulse";
      EXPECT_EQ(got[c].impulse_t, Vec3::Zero()) << "static contact " << c;
    }
    auto it = w.want_by_pair.find({got[c].a, got[c].b});
    if (it == w.want_by_pair.end()) continue;
    EXPECT_EQ(got[c].impulse_n, it->second->impulse_n) << "contact " << c;
    EXPECT_EQ(got[c].impulse_t, it->second->impulse_t) << "contact " << c;
    EXPECT_EQ(got[c].previous, it->second->previous) << "contact " << c;
    if (got[c].b >= 0 && got[c].impulse_n != 0.0) ++pairs_carried;
  }
  EXPECT_GT(pairs_carried, 0);
  EXPECT_GT(static_contacts, 0);
  EXPECT_GT(static_named, 0) << "no static contact named its pair of last step";
  std::printf(
      "[ measured ] %zu contacts: %d pairs carried their impulses, %d static started at zero\n",
      got.size(), pairs_carried, static_contacts);
}

// ---------------------------------------------------------------------------------------------
// adjacency and colouring

TEST(ReferenceAdjacency, MatchesExactly) {
  RandomWorld r = random_world();
  SCOPED_TRACE(r.seed_note);
  auto& world = r.world;
  find_device_contacts(*world);

  ref::Adjacency want = ref::adjacency(current_contacts(*world), static_cast<int>(world->size()));
  const DemBuffers& b = world->buffers();
  EXPECT_EQ(b.adjacency_offsets.download(world->size() + 1), want.offsets);
  EXPECT_EQ(b.adjacency.download(want.contacts.size()), want.contacts);
}

TEST(ReferenceColouring, MatchesExactlyAndIsValid) {
  RandomWorld r = random_world(/*serial_lanes=*/0);
  SCOPED_TRACE(r.seed_note);
  auto& world = r.world;
  find_device_contacts(*world);
  world->colour_contacts();

  std::vector<ref::Contact> contacts = current_contacts(*world);
  int nc = static_cast<int>(contacts.size());
  ASSERT_GT(nc, 0);
  int rounds = 0;
  ref::Adjacency adjacency = ref::adjacency(contacts, static_cast<int>(world->size()));
  std::vector<int> colours = ref::colour_contacts(contacts, adjacency, &rounds);
  ref::Partition want = ref::partition_by_colour(colours);
  const DemBuffers& b = world->buffers();
  EXPECT_EQ(b.colour.download(nc), colours);  // unpacked in place by colour_histogram
  EXPECT_EQ(b.colour_rounds, rounds);
  EXPECT_EQ(b.order.download(nc), want.order);
  EXPECT_EQ(b.row_of_contact.download(nc), want.row_of_contact);
  EXPECT_EQ(b.colour_start, want.colour_start);
  // both are valid colourings
  expect_valid_colouring(contacts, b.order.download(nc), b.row_of_contact.download(nc),
                         b.colour_start);
  expect_valid_colouring(contacts, want.order, want.row_of_contact, want.colour_start);
  std::printf("[ measured ] %d contacts: %zu colours in %d rounds\n", nc,
              want.colour_start.size() - 1, rounds);
}

// a system one work-item walks (a CPU device, up to one_group_rows rows) is laid out without
// colours: the contacts cut into `serial_lanes` blocks, the rows taking one of each in turn. The
// device's order must be the reference's exactly, for block counts from one (contact order) to
// more blocks than contacts, and a bijection whose neighbouring rows come from different blocks
TEST(ReferenceColouring, InterleavedRowsMatchExactly) {
  RandomWorld r = random_world();
  SCOPED_TRACE(r.seed_note);
  auto& world = r.world;
  if (!world->one_item_sweeps()) GTEST_SKIP() << "this device sweeps in several work-items";
  const int nc = find_device_contacts(*world);
  ASSERT_GT(nc, 0);
  const int drawn = 2 + static_cast<int>(r.rng() % 60);
  for (int lanes : {1, 2, 3, kSerialLanes, drawn, nc - 1, nc + 5, kMaxSerialLanes}) {
    if (lanes < 1 || lanes > kMaxSerialLanes) continue;
    SCOPED_TRACE("serial_lanes " + std::to_string(lanes));
    world->settings().serial_lanes = lanes;
    world->colour_contacts();
    const ref::Partition want = ref::interleaved_partition(nc, lanes);
    const DemBuffers& b = world->buffers();
    EXPECT_TRUE(b.row_layout == RowLayout::Interleaved);
    EXPECT_EQ(b.colour_start, (std::vector<int>{0, nc}));
    EXPECT_EQ(b.colour_start_dev.download(2), (std::vector<int>{0, nc}));
    const std::vector<int> order = b.order.download(nc), row_of = b.row_of_contact.download(nc);
    EXPECT_EQ(order, want.order);
    EXPECT_EQ(row_of, want.row_of_contact);
    // a bijection, and rows next to each other from different blocks while every block has a
    // contact left (block of c: the last j with floor(j nc / lanes) <= c)
    auto block = [&](int c) {
      int j = 0;
      while (j + 1 < lanes && std::int64_t(j + 1) * nc / lanes <= c) ++j;
      return j;
    };
    std::vector<int> seen(nc, 0);
    for (int row = 0; row < nc; ++row) {
      ASSERT_GE(order[row], 0);
      ASSERT_LT(order[row], nc);
      ++seen[order[row]];
      EXPECT_EQ(row_of[order[row]], row);
      if (lanes > 1 && row + 1 < (nc / lanes) * lanes) {
        EXPECT_NE(block(order[row]), block(order[row + 1])) << "rows " << row << ", " << row + 1;
      }
    }
    EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), nc);
  }
  // colours again with 0
  world->settings().serial_lanes = 0;
  world->colour_contacts();
  EXPECT_FALSE(world->buffers().row_layout == RowLayout::Interleaved);
  EXPECT_GT(world->buffers().colour_start.size(), 2u);
  std::printf(
      "[ measured ] %d contacts: interleaved orders equal the reference's (1 to %d blocks)\n", nc,
      kMaxSerialLanes);
}

// the runs' arithmetic shared by the kernels and the host (kernels/dem_types.h), checked from its
// promise for every count of parts up to kMaxSweepParts: the runs fit the partition's colours,
// every pair of parts has a run, within one part its own, and no part is touched by two runs of
// one level (the runs of a level are walked side by side)
TEST(ReferenceColouring, RunLevelsGiveEveryPairOfPartsOneRunAndKeepALevelsRunsApart) {
  for (int parts = 1; parts <= kMaxSweepParts; ++parts) {
    SCOPED_TRACE("parts " + std::to_string(parts));
    const int runs = tl_runs(parts);
    ASSERT_LE(runs, TL_MAX_COLOURS);
    ASSERT_GE(runs, parts);
    // each run's level: the last level whose first run is at or below it
    const int levels = tl_run_levels(parts);
    std::vector<int> level_of(runs, -1);
    for (int l = 0; l < levels; ++l)
      for (int r = tl_run_first(parts, l); r < runs; ++r) level_of[r] = l;
    // for each level, the one run each part's contacts of that level go to
    std::vector<std::vector<int>> run_at(levels, std::vector<int>(parts, -1));
    for (int pa = 0; pa < parts; ++pa) {
      for (int pb = 0; pb < parts; ++pb) {
        const int r = tl_run_of(pa, pb, parts);
        ASSERT_GE(r, 0);
        ASSERT_LT(r, runs);
        if (pa == pb) {
          EXPECT_EQ(r, pa);
        }
        EXPECT_EQ(r, tl_run_of(pb, pa, parts)) << pa << ", " << pb;
        for (int p : {pa, pb}) {
          int& slot = run_at[level_of[r]][p];
          EXPECT_TRUE(slot == -1 || slot == r)
              << "part " << p << " in runs " << slot << " and " << r << " of level " << level_of[r];
          slot = r;
        }
      }
    }
    // the top level is one run, which a part pair across the middle uses
    EXPECT_EQ(tl_run_first(parts, levels - 1), runs - 1);
  }
  std::printf("[ measured ] runs of 2, 16, 32 parts: %d, %d, %d\n", tl_runs(2), tl_runs(16),
              tl_runs(32));
}

// a large system on a CPU device is laid out in runs (its parts by particle index, then the runs
// across them level by level, each interleaved): the device's layout must equal the reference's
// for parts and blocks drawn fresh; no dynamic body may appear in two runs of one level (their
// walks run side by side), and the rows outside level 0 are exactly the contacts across parts
TEST(ReferenceColouring, RunsMatchExactlyAndKeepALevelsRunsApart) {
  // every system walks in runs, however small (the threshold is a speed question)
  RandomWorld r = random_world(kSerialLanes, /*one_group_rows=*/0);
  SCOPED_TRACE(r.seed_note);
  auto& world = r.world;
  if (!world->one_item_sweeps()) GTEST_SKIP() << "this device sweeps in several work-items";
  const int nc = find_device_contacts(*world);
  const int n = static_cast<int>(world->size());
  ASSERT_GT(nc, 0);
  const std::vector<ref::Contact> contacts = current_contacts(*world);
  const int drawn_parts = 2 + static_cast<int>(r.rng() % (kMaxSweepParts - 2));
  const int drawn_lanes = 1 + static_cast<int>(r.rng() % 40);
  int across_seen = 0;
  for (auto [parts, lanes] :
       {std::pair{1, kSerialLanes}, std::pair{2, kSerialLanes}, std::pair{3, 1},
        std::pair{drawn_parts, drawn_lanes}, std::pair{kMaxSweepParts, 2},
        std::pair{kMaxSweepParts, kMaxSerialLanes}}) {
    SCOPED_TRACE("sweep_parts " + std::to_string(parts) + ", serial_lanes " +
                 std::to_string(lanes));
    world->settings().sweep_parts = parts;
    world->settings().serial_lanes = lanes;
    ASSERT_EQ(world->sweep_parts(), parts);
    world->colour_contacts();
    const ref::Partition want = ref::run_partition(contacts, n, parts, lanes);
    const DemBuffers& b = world->buffers();
    ASSERT_TRUE(b.row_layout == RowLayout::Runs);
    EXPECT_EQ(b.run_parts, parts);
    EXPECT_EQ(b.colour_start, want.colour_start);
    const int runs = tl_runs(parts);
    ASSERT_EQ(b.colour_start.size(), static_cast<size_t>(runs + 1));
    const std::vector<int> order = b.order.download(nc), row_of = b.row_of_contact.download(nc);
    EXPECT_EQ(order, want.order);
    EXPECT_EQ(row_of, want.row_of_contact);
    // a bijection; a part's run holds only contacts within that part; within each level, every
    // dynamic body in one run only
    // (a copy: a structured binding cannot be captured in C++17)
    const int part_count = parts;
    const auto part_of = [&](int body) {
      return static_cast<int>(std::int64_t(body) * part_count / n);
    };
    std::vector<int> seen(nc, 0);
    for (int l = 0; l < tl_run_levels(parts); ++l) {
      const int first = tl_run_first(parts, l);
      std::vector<int> run_of_body(n, -1);
      for (int k = first; k < first + tl_run_groups(parts, l); ++k) {
        for (int row = b.colour_start[k]; row < b.colour_start[k + 1]; ++row) {
          const int c = order[row];
          ASSERT_GE(c, 0);
          ASSERT_LT(c, nc);
          ++seen[c];
          EXPECT_EQ(row_of[c], row);
          const int pa = part_of(contacts[c].a);
          const int pb = contacts[c].b >= 0 ? part_of(contacts[c].b) : pa;
          EXPECT_EQ(pa == pb, l == 0) << "row " << row << " of level " << l;
          if (l == 0) {
            EXPECT_EQ(pa, k) << "row " << row;
          }
          for (int body : {contacts[c].a, contacts[c].b}) {
            if (body < 0) continue;
            EXPECT_TRUE(run_of_body[body] == -1 || run_of_body[body] == k)
                << "body " << body << " in runs " << run_of_body[body] << " and " << k;
            run_of_body[body] = k;
          }
        }
      }
    }
    EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), nc);
    const int across = b.colour_start[runs] - b.colour_start[parts];
    if (parts == 1) {
      EXPECT_EQ(across, 0);
    }
    across_seen += across;
    std::printf("[ measured ] %d parts, %d runs: %d of %d contacts across parts\n", parts, runs,
                across, nc);
  }
  EXPECT_GT(across_seen, 0) << "no part boundary was crossed: the test saw nothing";
  // colours again with serial_lanes 0
  world->settings().serial_lanes = 0;
  world->colour_contacts();
  EXPECT_TRUE(world->buffers().row_layout == RowLayout::Colours);
}

// a world stepped twice carries its last step's colours to the contacts that persist; the
// device's carried and final colours, rounds and partition must match the reference's exactly.
// Last step's colours are also overwritten with random ones from a few colours, so that many
// persisting neighbours carry the same colour and the guard against it (drop_colour_conflicts)
// must act: it still ends in a valid colouring, equal to the reference's
TEST(ReferenceColouring, CarriedColoursMatchExactlyAndAreValid) {
  RandomWorld r = random_world(/*serial_lanes=*/0);
  SCOPED_TRACE(r.seed_note);
  auto& world = r.world;
  world->step();
  world->step();
  ASSERT_TRUE(world->carries_colours());
  DemBuffers& b = world->buffers();
  const int previous_count = b.n_contacts;
  for (bool scrambled : {false, true}) {
    SCOPED_TRACE(scrambled ? "random colours carried" : "last step's colours carried");
    std::vector<int> previous_colours = b.colour_previous.download(previous_count);
    if (scrambled) {
      for (int& k : previous_colours) k = static_cast<int>(r.rng() % 4);
      b.colour_previous.upload(previous_colours);
    }
    find_device_contacts(*world);
    world->colour_contacts();
    std::vector<ref::Contact> contacts = current_contacts(*world);
    const int nc = static_cast<int>(contacts.size());
    ASSERT_GT(nc, 0);
    ref::Adjacency adjacency = ref::adjacency(contacts, static_cast<int>(world->size()));
    std::vector<int> start =
        ref::carried_colours(contacts, adjacency, previous_colours, world->fresh_colours());
    int carried = 0, persisting = 0, below_cap = 0;
    for (int c = 0; c < nc; ++c) {
      persisting += contacts[c].previous >= 0 ? 1 : 0;
      below_cap += contacts[c].previous >= 0 &&
                           previous_colours[contacts[c].previous] < world->fresh_colours()
                       ? 1
                       : 0;
      carried += start[c] >= 0 ? 1 : 0;
    }
    int rounds = 0;
    std::vector<int> colours = ref::colour_contacts(contacts, adjacency, &rounds, start);
    ref::Partition want = ref::partition_by_colour(colours);
    EXPECT_EQ(b.colour.download(nc), colours);
    EXPECT_EQ(b.colour_rounds, rounds);
    EXPECT_EQ(b.order.download(nc), want.order);
    EXPECT_EQ(b.row_of_contact.download(nc), want.row_of_contact);
    EXPECT_EQ(b.colour_start, want.colour_start);
    expect_valid_colouring(contacts, want.order, want.row_of_contact, want.colour_start);
    // most contacts persist from one step to the next and keep a colour below the cap; the
    // guard drops colours only when the carried ones clash (four colours on a particle's eight
    // or more contacts must)
    EXPECT_GT(persisting, nc / 2);
    if (scrambled)
      EXPECT_LT(carried, below_cap) << "no carried colour was dropped";
    else
      EXPECT_EQ(carried, below_cap) << "a valid colouring lost a colour in the carry";
    std::printf(
        "[ measured ] %d contacts, %d persist, %d below the cap of %d colours, %d keep "
        "their colour; %zu colours in %d rounds\n",
        nc, persisting, below_cap, world->fresh_colours(), carried, want.colour_start.size() - 1,
        rounds);
  }
}

// particles removed and added between two steps (DemWorld::renumber_particles: the type-G
// terrain's merge and spawn): a pair of two survivors keeps last step's impulses under its new
// numbers, a new particle's contacts start from zero, and the colouring carries the survivors'
// colours, exactly as the reference does from the renumbered lists
TEST(ReferenceColouring, RenumberedParticlesKeepTheirPairsWarmStartAndColours) {
  RandomWorld r = random_world(/*serial_lanes=*/0);
  SCOPED_TRACE(r.seed_note);
  DemWorld& world = *r.world;
  world.step();
  world.step();
  ASSERT_TRUE(world.carries_colours());
  const DemBuffers& b = world.buffers();
  // last step's pairs and their impulses, by the old numbers
  std::map<std::pair<int, int>, ref::Contact> before;
  for (const ref::Contact& c : contacts_of(world, 1 - b.current)) before[{c.a, c.b}] = c;
  // every fifth particle merged away; two of them come back as new particles at the end
  Particles old = world.particles();
  std::vector<int> new_index_of_old(old.size(), -1);
  std::vector<size_t> kept, gone;
  for (size_t k = 0; k < old.size(); ++k) (k % 5 == 2 ? gone : kept).push_back(k);
  for (size_t j = 0; j < kept.size(); ++j) new_index_of_old[kept[j]] = static_cast<int>(j);
  Particles now = old.permuted(kept);
  std::vector<int> old_of_new(kept.begin(), kept.end());
  for (size_t k : {gone[0], gone[1]}) {
    now.add(old.position[k], old.radius[k],
            1.0 / (old.inv_mass[k] * 4.0 / 3.0 * M_PI * std::pow(old.radius[k], 3)));
    old_of_new.push_back(-1);
  }
  world.renumber_particles(now, new_index_of_old);
  ASSERT_TRUE(world.carries_colours());
  world.broad_phase();
  world.narrow_phase();
  // impulses: a survivors' pair of last step carries its own; any other contact starts at zero
  const std::vector<ref::Contact> got = current_contacts(world);
  int carried = 0, fresh = 0;
  for (size_t c = 0; c < got.size(); ++c) {
    const int a = old_of_new[got[c].a];
    const int bb = got[c].b >= 0 ? old_of_new[got[c].b] : got[c].b;
    const auto it = a >= 0 && (got[c].b < 0 || bb >= 0) ? before.find({a, bb}) : before.end();
    if (it == before.end()) {
      EXPECT_EQ(got[c].impulse_n, 0.0) << "contact " << c << " is new";
      EXPECT_EQ(got[c].previous, -1) << "contact " << c << " is new";
      ++fresh;
    } else {
      EXPECT_EQ(got[c].impulse_n, it->second.impulse_n) << "contact " << c;
      EXPECT_EQ(got[c].impulse_t, it->second.impulse_t) << "contact " << c;
      EXPECT_GE(got[c].previous, 0) << "contact " << c;
      ++carried;
    }
  }
  EXPECT_GT(carried, static_cast<int>(got.size()) / 3);
  EXPECT_GT(fresh, 0);
  // colours: the device's against the reference's from the renumbered colours
  world.build_adjacency();
  world.colour_contacts();
  const int nc = static_cast<int>(got.size());
  const std::vector<int> previous_colours = b.colour_previous.download(b.n_contacts);
  ref::Adjacency adjacency = ref::adjacency(got, static_cast<int>(world.size()));
  int rounds = 0;
  const std::vector<int> colours = ref::colour_contacts(
      got, adjacency, &rounds,
      ref::carried_colours(got, adjacency, previous_colours, world.fresh_colours()));
  const ref::Partition want = ref::partition_by_colour(colours);
  EXPECT_EQ(b.colour.download(nc), colours);
  EXPECT_EQ(b.order.download(nc), want.order);
  expect_valid_colouring(got, want.order, want.row_of_contact, want.colour_start);
  std::printf(
      "[ measured ] %zu particles (%zu merged, 2 new): %d contacts kept their impulses, %d "
      "started at zero; %zu colours in %d rounds\n",
      now.size(), gone.size(), carried, fresh, want.colour_start.size() - 1, rounds);
  // a numbering whose survivors change order is refused
  std::vector<int> swapped(now.size(), -1);
  for (size_t k = 0; k < swapped.size(); ++k) swapped[k] = static_cast<int>(k);
  std::swap(swapped[0], swapped[1]);
  EXPECT_THROW(world.renumber_particles(now, swapped), Error);
}

// particles that only change size between two steps (DemWorld::resize_particles: the type-G
// terrain's growing seeds): the sizes reach the device, and every contact, impulse and colour of
// the last step stays for the next one's warm start and colouring (the same start as the
// renumbering test above)
TEST(ReferenceColouring, ResizedParticlesKeepEveryContactAndTheirColours) {
  RandomWorld r = random_world(/*serial_lanes=*/0);
  SCOPED_TRACE(r.seed_note);
  DemWorld& world = *r.world;
  world.step();
  world.step();
  ASSERT_TRUE(world.carries_colours());
  const DemBuffers& b = world.buffers();
  // last step's contacts and colours, as the next step's narrow phase and colouring read them
  const int n_contacts = b.n_contacts;
  const std::vector<TlContact> contacts = b.contacts[1 - b.current].download(n_contacts);
  const std::vector<int> colours = b.colour_previous.download(n_contacts);
  // every third particle grows by 5 % (a growing type-G seed), the others keep their size
  Particles p = world.particles();
  const double density = 1.0 / (p.inv_mass[0] * 4.0 / 3.0 * M_PI * std::pow(p.radius[0], 3));
  for (size_t k = 0; k < p.size(); k += 3) p.resize(k, 1.05 * p.radius[k], density);
  world.resize_particles(p);
  // the sizes reached the device, the contacts, their impulses and colours did not move
  const Particles q = world.particles();
  for (size_t k = 0; k < p.size(); ++k) {
    EXPECT_EQ(q.radius[k], static_cast<double>(static_cast<float>(p.radius[k]))) << k;
    EXPECT_EQ(q.inv_mass[k], static_cast<double>(static_cast<float>(p.inv_mass[k]))) << k;
    EXPECT_EQ(q.inv_inertia[k], static_cast<double>(static_cast<float>(p.inv_inertia[k]))) << k;
    EXPECT_EQ(q.position[k], p.position[k]) << k;
  }
  EXPECT_DOUBLE_EQ(world.max_radius(), *std::max_element(p.radius.begin(), p.radius.end()));
  ASSERT_EQ(b.n_contacts, n_contacts);
  EXPECT_TRUE(world.carries_colours());
  const std::vector<TlContact> after = b.contacts[1 - b.current].download(n_contacts);
  EXPECT_EQ(std::memcmp(after.data(), contacts.data(), contacts.size() * sizeof(TlContact)), 0);
  EXPECT_EQ(b.colour_previous.download(n_contacts), colours);
  // and the world steps on from them
  world.step();
  EXPECT_GT(b.n_contacts, 0);
  // another count is refused
  Particles fewer = p.permuted({0, 1});
  EXPECT_THROW(world.resize_particles(fewer), Error);
}

// ---------------------------------------------------------------------------------------------
// rows, gravity and warm start

// a device world with contacts, adjacency and colours of a fresh scene of cohesive particles
// (touching pairs hold tension, so the rows' lower bounds and cones differ from dry ones; the dry
// path is the five-step test's), and random warm-start impulses on its contacts
std::unique_ptr<DemWorld> world_with_contacts(std::mt19937_64& rng, SweepKind sweep,
                                              Scene* scene_out = nullptr, double relaxation = 1.0) {
  Scene s = test::random_scene(rng);
  s.settings.sweep = sweep;
  s.settings.relaxation = relaxation;
  // moist-soil tensile strengths [Pa]: bonds of the order of the injected impulses per step
  s.material.cohesion = std::uniform_real_distribution<double>(1e3, 3e4)(rng);
  auto world = make_world(s);
  world->broad_phase();
  world->narrow_phase();
  inject_impulses(*world, rng);
  world->build_adjacency();
  world->colour_contacts();
  if (scene_out != nullptr) *scene_out = s;
  return world;
}

void compare_rows(const std::vector<ref::Row>& got, const std::vector<ref::Row>& want,
                  const std::vector<ref::Contact>& contacts, const ref::StepParams& p,
                  const std::string& label) {
  ASSERT_EQ(got.size(), want.size());
  const double rel = 1e-4;
  Tally rhs(label + " rhs [m/s]"), inv_dn(label + " 1/D_n"), sigma(label + " sigma"),
      inv_dt(label + " 1/D_t"), inv_dr(label + " 1/D_r"), coef(label + " mu, mu_r R*"),
      geometry(label + " normal and arms"), impulses(label + " initial impulses");
  for (size_t k = 0; k < got.size(); ++k) {
    const ref::Row& g = got[k];
    const ref::Row& w = want[k];
    ASSERT_EQ(g.contact, w.contact) << "row " << k;
    ASSERT_EQ(g.a, w.a) << "row " << k;
    ASSERT_EQ(g.b, w.b) << "row " << k;
    // the rhs is a difference of two terms, -(4/h) upsilon gap + upsilon u_n: relative to
    // their size (velocities below 1 m/s), not to the result
    double upsilon = 1.0 / (1.0 + 4.0 * p.damping_tau / p.dt);
    double terms = upsilon * (4.0 / p.dt * std::abs(contacts[w.contact].gap) + 1.0);
    rhs.scalar(g.rhs, w.rhs, rel, rel * terms, at("row", k));
    inv_dn.scalar(g.inv_dn, w.inv_dn, rel, 0.0, at("row", k));
    sigma.scalar(g.sigma, w.sigma, rel, 0.0, at("row", k));
    inv_dt.scalar(g.inv_dt, w.inv_dt, rel, 0.0, at("row", k));
    inv_dr.scalar(g.inv_dr, w.inv_dr, rel, 0.0, at("row", k));
    coef.scalar(g.friction, w.friction, 1e-7, 0.0, at("row", k));
    coef.scalar(g.rolling_limit, w.rolling_limit, 1e-6, 0.0, at("row", k));
    coef.scalar(g.cohesion, w.cohesion, 1e-6, 0.0, at("row", k));
    // the normal exact; each arm is stored as its length along n (kernels/dem_types.h
    // TlParticleRow), a float dot product and a product away from the contact's arm: a few
    // roundings, 1e-6 of its length
    geometry.vector(g.normal, w.normal, 0.0, 0.0, at("row", k));
    geometry.vector(g.arm_a, w.arm_a, 1e-6, 0.0, at("row", k));
    geometry.vector(g.arm_b, w.arm_b, 1e-6, 0.0, at("row", k));
    // exact, except a pulling warm start clamped to the bond limit (float h F_c vs double). The
    // cones' radii mu (lambda_n + h F_c) and mu_r R* (lambda_n + h F_c) cancel when a pulling
    // impulse nears the bond limit, so a clamped impulse is good to float's rounding of the
    // terms, 1e-6 of mu (|lambda_n| + h F_c), not of the small radius itself
    const double bond_terms = std::abs(w.impulse_n) + w.cohesion;
    impulses.scalar(g.impulse_n, w.impulse_n, 1e-6, 0.0, at("row", k));
    impulses.vector(g.impulse_t, w.impulse_t, rel, 1e-12 + 1e-6 * w.friction * bond_terms, at("row", k));
    impulses.vector(g.impulse_r, w.impulse_r, rel, 1e-15 + 1e-6 * w.rolling_limit * bond_terms, at("row", k));
  }
  for (const Tally* t : {&rhs, &inv_dn, &sigma, &inv_dt, &inv_dr, &coef, &geometry, &impulses})
    t->expect_within();
}

TEST(ReferenceRows, PrepareRowsMatchWithinRelative1em4) {
  uint64_t seed = test::fresh_seed();
  SCOPED_TRACE(test::seed_note(seed));
  std::mt19937_64 rng(seed);
  auto world = world_with_contacts(rng, SweepKind::Pgs);
  std::vector<ref::Contact> contacts = current_contacts(*world);
  ref::StepParams p = params_of(*world);
  std::vector<int> order = world->buffers().order.download(contacts.size());
  for (bool warm : {true, false}) {
    SCOPED_TRACE(warm ? "warm start" : "cold start");
    world->settings().warm_start = warm;
    world->prepare_rows();
    compare_rows(rows_of(*world), ref::prepare_rows(contacts, order, world->particles(), p, warm),
                 contacts, p, warm ? "warm rows" : "cold rows");
  }
}

TEST(ReferenceRows, GravityAndWarmStartMatch) {
  uint64_t seed = test::fresh_seed();
  SCOPED_TRACE(test::seed_note(seed));
  std::mt19937_64 rng(seed);
  auto world = world_with_contacts(rng, SweepKind::Pgs);
  world->prepare_rows();
  ref::StepParams p = params_of(*world);
  Particles bodies = world->particles();
  std::vector<ref::Row> rows = rows_of(*world);
  const DemBuffers& b = world->buffers();
  std::vector<ref::Contact> contacts = current_contacts(*world);
  ref::Adjacency adjacency = ref::adjacency(contacts, static_cast<int>(world->size()));
  std::vector<int> row_of_contact = b.row_of_contact.download(contacts.size());

  world->apply_gravity();
  ref::apply_gravity(bodies, p);
  compare_bodies(world->particles(), bodies, 1e-6, 1e-7, 0.0, "gravity");

  world->warm_start();
  ref::apply_row_impulses(rows, adjacency, row_of_contact, bodies);
  compare_bodies(world->particles(), bodies, 1e-5, 1e-6, 1e-5, "warm start");
}

// ---------------------------------------------------------------------------------------------
// sweeps

// the device after gravity and warm start, and the reference on exactly its state
struct SweepStart {
  std::unique_ptr<DemWorld> world;
  Particles bodies;
  std::vector<ref::Row> rows;
  std::vector<ref::Contact> contacts;
  ref::Adjacency adjacency;
  std::vector<int> row_of_contact;
};

SweepStart sweep_start_from(std::unique_ptr<DemWorld> world) {
  SweepStart s;
  s.world = std::move(world);
  DemWorld& w = *s.world;
  w.prepare_rows();
  w.apply_gravity();
  w.warm_start();
  s.bodies = w.particles();
  s.rows = rows_of(w);
  s.contacts = current_contacts(w);
  s.adjacency = ref::adjacency(s.contacts, static_cast<int>(w.size()));
  s.row_of_contact = w.buffers().row_of_contact.download(s.contacts.size());
  return s;
}

SweepStart sweep_start(std::mt19937_64& rng, SweepKind sweep) {
  return sweep_start_from(world_with_contacts(rng, sweep));
}

// tolerances of the sweeps: 1e-4 relative, plus absolute floors. Velocities (~0.5 m/s):
// 1e-6 m/s. Angular velocities (~20 1/s): 2e-4 1/s (1e-5 of the scale), since a sphere's
// inverse inertia (~2e6 1/(kg m^2)) turns float rounding of a rolling or friction impulse into
// ~1e-5 1/s, and rolling resistance can stop a spin entirely (no relative scale left).
// Impulses (~5e-3 N s; rolling up to mu_r R* lambda_n ~2.5e-5 N m s with the gravel's mu_r of
// 1.0): 1e-6 of their scale.
constexpr double kVelocityFloor = 1e-6;  // [m/s]
void compare_sweep_state(SweepStart& s, const std::string& label) {
  compare_bodies(s.world->particles(), s.bodies, 1e-4, kVelocityFloor, 2e-4, label);
  compare_impulses(rows_of(*s.world), s.rows, 1e-4, 5e-9, 2.5e-11, label);
}

void compare_residuals(SweepStart& s, const std::string& label) {
  double device_rms = s.world->residual();
  auto got = s.world->buffers().residual.download(s.rows.size());
  const double relaxation = params_of(*s.world).relaxation;
  std::vector<double> want = ref::row_residuals(s.rows, s.bodies, relaxation);
  Tally t(label + " row residual [m^2/s^2]");
  // a squared residual r^2: relative 1e-3, floor at (1e-5 m/s)^2, plus 2 r dv, the first-order
  // change of r^2 when the velocities it is the difference of round by dv. dv is the bodies'
  // velocity floor, a measured scale rather than a bound (the friction and rolling rows also
  // carry the angular velocities' rounding times their arms): without the term a row at
  // r = 3.3e-4 m/s failed 4 times in ~1,200 fresh seeds; with it the worst of 300 is 0.29
  for (size_t k = 0; k < want.size(); ++k) {
    // an entry is a squared residual, or -1 for a row without normal impulse or step (zero)
    ASSERT_TRUE(got[k] >= 0.0f || got[k] == -1.0f) << "row " << k << ": " << got[k];
    const double r = std::sqrt(std::max(want[k], 0.0));
    t.scalar(std::max(got[k], 0.0f), want[k], 1e-3, 1e-10 + 2.0 * r * kVelocityFloor, at("row", k));
  }
  t.expect_within();
  EXPECT_NEAR(device_rms, ref::residual(s.rows, s.bodies, relaxation), 1e-3 * device_rms + 1e-6);
}

// one PGS sweep on the device and the reference, compared, then four more
void one_and_five_pgs_sweeps(SweepStart& s, const std::string& label) {
  const std::vector<int>& colour_start = s.world->buffers().colour_start;
  s.world->sweep(1);
  ref::pgs_sweep(s.rows, colour_start, s.bodies);
  compare_sweep_state(s, label + " 1 sweep");
  compare_residuals(s, label + " 1 sweep");
  s.world->sweep(4);
  for (int it = 0; it < 4; ++it) ref::pgs_sweep(s.rows, colour_start, s.bodies);
  compare_sweep_state(s, label + " 5 sweeps");
}

TEST(ReferenceSweeps, PgsOneAndFiveSweeps) {
  uint64_t seed = test::fresh_seed();
  SCOPED_TRACE(test::seed_note(seed));
  std::mt19937_64 rng(seed);
  SweepStart s = sweep_start(rng, SweepKind::Pgs);
  compare_residuals(s, "pgs before sweeps");
  one_and_five_pgs_sweeps(s, "pgs");

  // the solved impulses go back to their contacts
  s.world->store_impulses();
  ref::store_impulses(s.rows, s.contacts);
  std::vector<ref::Contact> stored = current_contacts(*s.world);
  std::vector<ref::Row> device_rows = rows_of(*s.world);
  for (const ref::Row& r : device_rows) {
    EXPECT_EQ(stored[r.contact].impulse_n, r.impulse_n);
    EXPECT_EQ(stored[r.contact].impulse_t, r.impulse_t);
    EXPECT_EQ(stored[r.contact].impulse_r, r.impulse_r);
  }
}

// projected SOR (DemSettings::relaxation): the rows' inverse effective masses carry a fresh omega
// in (0.3, 1.9), and one and five relaxed sweeps match the reference's
TEST(ReferenceSweeps, RelaxedPgsMatchesWithAFreshOmega) {
  uint64_t seed = test::fresh_seed();
  SCOPED_TRACE(test::seed_note(seed));
  std::mt19937_64 rng(seed);
  const double omega = std::uniform_real_distribution<double>(0.3, 1.9)(rng);
  std::printf("[ measured ] relaxation %.4f\n", omega);
  // the rows on the state before the step, as the reference makes them with the same omega
  std::mt19937_64 twin_rng = rng;
  auto world = world_with_contacts(rng, SweepKind::Pgs, nullptr, omega);
  const ref::StepParams p = params_of(*world);
  EXPECT_EQ(p.relaxation, static_cast<double>(static_cast<float>(omega)));
  const std::vector<ref::Contact> contacts = current_contacts(*world);
  const std::vector<int> order = world->buffers().order.download(contacts.size());
  const Particles before = world->particles();
  world->prepare_rows();
  compare_rows(rows_of(*world), ref::prepare_rows(contacts, order, before, p, true), contacts, p,
               "relaxed rows");
  // the relaxation scales the steps: each inverse effective mass is omega times plain PGS's (the
  // same scene with omega 1, from the same draws)
  auto plain = world_with_contacts(twin_rng, SweepKind::Pgs);
  plain->prepare_rows();
  const std::vector<ref::Row> relaxed_rows = rows_of(*world), plain_rows = rows_of(*plain);
  ASSERT_EQ(relaxed_rows.size(), plain_rows.size());
  for (size_t k = 0; k < plain_rows.size(); ++k) {
    EXPECT_NEAR(relaxed_rows[k].inv_dn, omega * plain_rows[k].inv_dn, 1e-6 * relaxed_rows[k].inv_dn)
        << "row " << k;
    EXPECT_NEAR(relaxed_rows[k].inv_dt, omega * plain_rows[k].inv_dt, 1e-6 * relaxed_rows[k].inv_dt)
        << "row " << k;
  }

  // the relaxed sweeps from the device's state after gravity and the warm start
  SweepStart s = sweep_start_from(std::move(world));
  one_and_five_pgs_sweeps(s, "relaxed pgs");
}

TEST(ReferenceSweeps, JacobiOneAndFiveIterations) {
  uint64_t seed = test::fresh_seed();
  SCOPED_TRACE(test::seed_note(seed));
  std::mt19937_64 rng(seed);
  SweepStart s = sweep_start(rng, SweepKind::Jacobi);
  // jacobi rows are in contact order, one colour
  std::vector<int> one_colour{0, static_cast<int>(s.rows.size())};
  EXPECT_EQ(s.world->buffers().colour_start, one_colour);

  s.world->sweep(1);
  ref::jacobi_iteration(s.rows, s.adjacency, s.row_of_contact, s.bodies);
  compare_sweep_state(s, "jacobi 1 iteration");
  compare_residuals(s, "jacobi 1 iteration");

  s.world->sweep(4);
  for (int it = 0; it < 4; ++it)
    ref::jacobi_iteration(s.rows, s.adjacency, s.row_of_contact, s.bodies);
  compare_sweep_state(s, "jacobi 5 iterations");
}

// ---------------------------------------------------------------------------------------------
// positions

TEST(ReferenceIntegrate, PositionsAndRotationsWithin1em6) {
  uint64_t seed = test::fresh_seed();
  SCOPED_TRACE(test::seed_note(seed));
  std::mt19937_64 rng(seed);
  Scene s = test::random_scene(rng);
  auto world = make_world(s);
  Particles bodies = world->particles();
  world->integrate();
  ref::integrate(bodies, params_of(*world));

  Particles got = world->particles();
  Tally x("integrated position [m]"), q("integrated rotation");
  for (size_t i = 0; i < got.size(); ++i) {
    x.vector(got.position[i], bodies.position[i], 0.0, 1e-6, at("body", i));
    q.add((got.rotation[i] - bodies.rotation[i]).norm(), 1e-6, at("body", i));
    if (bodies.inv_mass[i] == 0.0) {
      EXPECT_EQ(got.position[i], s.particles.position[i]) << "fixed particle " << i << " moved";
      EXPECT_EQ(got.rotation[i], s.particles.rotation[i]) << "fixed particle " << i << " turned";
    }
  }
  x.expect_within();
  q.expect_within();
}

// ---------------------------------------------------------------------------------------------
// full steps

// the pairs of two contact lists differ only where a gap sits within 1e-5 r of the margin
// (float rounding decides such a pair); returns whether the lists are identical
bool same_pairs_or_marginal(const std::vector<ref::Contact>& got,
                            const std::vector<ref::Contact>& want, const ref::ReferenceWorld& rw,
                            int step) {
  bool same = got.size() == want.size();
  for (size_t c = 0; same && c < got.size(); ++c)
    same = got[c].a == want[c].a && got[c].b == want[c].b;
  if (same) return true;
  std::set<std::pair<int, int>> g, w;
  for (auto& c : got) g.insert({c.a, c.b});
  for (auto& c : want) w.insert({c.a, c.b});
  auto marginal = [&](const ref::Contact& c, const char* side) {
    double rmin = c.b >= 0 ? std::min(rw.particles.radius[c.a], rw.particles.radius[c.b])
                           : rw.particles.radius[c.a];
    EXPECT_LT(std::abs(c.gap - rw.params.margin_rel * rmin), 1e-5 * rmin)
        << "step " << step << ": pair " << c.a << "," << c.b << " only " << side;
  };
  for (auto& c : want)
    if (!g.count({c.a, c.b})) marginal(c, "in the reference");
  for (auto& c : got)
    if (!w.count({c.a, c.b})) marginal(c, "on the device");
  std::printf("[ note     ] step %d: a pair crossed the contact margin within rounding\n", step);
  return false;
}

// DemWorld::step against reference::step for five steps from the same ~500 particles, twice:
//  - synchronised: before every step the reference takes the device's state (particles and
//    last step's contacts with their impulses), so each step starts from identical inputs.
//    The device computes gaps in float (errors ~1e-9 m), and the secant Hertz compliance
//    1/(k_n sqrt(overlap)) of a barely touching pair (overlap down to the floor, 1e-4 R* =
//    5e-7 m) turns that into up to 1e-3 relative in sigma; twenty sweeps carry it into the
//    velocities. Measured over 40 runs: positions <= 8e-8 m, velocities <= 8e-5 m/s.
//    Tolerances: positions 3e-7 m (3e-5 of the radius), velocities 1e-4 rel + 3e-4 m/s.
//  - free running: the reference steps on its own doubles. Float storage of positions
//    (7e-9 m per step) feeds back through the SPOOK rhs (4 upsilon/h = 440 1/s) and the same
//    compliance, growing about 1.5x per step. Measured over 40 runs: positions <= 1.4e-6 m,
//    velocities <= 1.4e-3 m/s. Tolerances: positions 3e-6 m (3e-4 of the radius), velocities
//    1e-2 rel + 3e-3 m/s.
// Where a pair's gap sits within rounding of the contact margin, one side may have a contact
// the other lacks, and the solves then legitimately differ: such a sample is redrawn (seen
// about once in 80 runs).
void five_steps(SweepKind sweep, int serial_lanes, int one_group_rows = kPgsOneGroupRows,
                int sweep_parts = 0) {
  const double synced_position_tol = 3e-7, free_position_tol = 3e-6;
  const std::string name = std::string(sweep_name(sweep)) + " (serial_lanes " +
                           std::to_string(serial_lanes) + ", one_group_rows " +
                           std::to_string(one_group_rows) + ", sweep_parts " +
                           std::to_string(sweep_parts) + ")";
  for (int attempt = 0; attempt < 3; ++attempt) {
    uint64_t seed = test::fresh_seed() + attempt;
    SCOPED_TRACE(test::seed_note(seed));
    std::mt19937_64 rng(seed);
    SceneOptions options;
    options.nx = options.ny = options.nz = 8;
    options.speed = 0.1;
    options.spin = 5.0;
    Scene s = test::random_scene(rng, options);
    s.settings.sweep = sweep;
    s.settings.iterations = 20;
    s.settings.serial_lanes = serial_lanes;
    s.settings.one_group_rows = one_group_rows;
    s.settings.sweep_parts = sweep_parts;
    auto world = make_world(s);
    ref::ReferenceWorld free;
    free.one_item_sweeps = world->one_item_sweeps();
    free.sweep_parts = world->sweep_parts();
    free.particles = world->particles();
    free.geoms = geoms_of(*world);
    free.params = params_of(*world);
    free.settings = world->settings();
    ref::ReferenceWorld synced = free;

    bool flipped = false;
    Tally sx(name + " synced step position [m]"), sv(name + " synced step velocity [m/s]");
    Tally fx(name + " 5 free steps position [m]"), fv(name + " 5 free steps velocity [m/s]");
    for (int step = 1; step <= 5 && !flipped; ++step) {
      // the synchronised reference starts from the device's state
      const DemBuffers& b = world->buffers();
      synced.particles = world->particles();
      synced.has_previous = b.has_previous;
      if (b.has_previous) {
        synced.previous.contacts = contacts_of(*world, 1 - b.current);
        synced.previous.owner_offsets = b.owner_offsets[1 - b.current].download(world->size() + 1);
      }
      synced.colours_carried = world->carries_colours();
      synced.fresh_colours = world->fresh_colours();
      if (synced.colours_carried)
        synced.previous_colours = b.colour_previous.download(b.n_contacts);
      world->step();
      ref::step(synced);
      ref::step(free);
      // the layout under test is the one the device made
      const bool walked = sweep == SweepKind::Pgs && serial_lanes > 0 && free.one_item_sweeps;
      EXPECT_EQ(b.row_layout == RowLayout::Interleaved,
                walked && b.n_contacts <= s.settings.one_group_rows)
          << "step " << step;
      EXPECT_EQ(b.row_layout == RowLayout::Runs, walked && b.n_contacts > s.settings.one_group_rows)
          << "step " << step;
      // this step's contacts (the device swapped its current and previous lists)
      std::vector<ref::Contact> got = contacts_of(*world, 1 - b.current);
      if (!same_pairs_or_marginal(got, synced.current.contacts, synced, step) ||
          !same_pairs_or_marginal(got, free.current.contacts, free, step)) {
        flipped = true;
        break;
      }
      EXPECT_EQ(world->stats().colour_rounds, free.colour_rounds) << "step " << step;
      Particles device = world->particles();
      for (size_t i = 0; i < device.size(); ++i) {
        std::string where = "step " + std::to_string(step) + " body " + std::to_string(i);
        sx.vector(device.position[i], synced.particles.position[i], 0.0, synced_position_tol,
                  where);
        sv.vector(device.velocity[i], synced.particles.velocity[i], 1e-4, 3e-4, where);
        fx.vector(device.position[i], free.particles.position[i], 0.0, free_position_tol, where);
        fv.vector(device.velocity[i], free.particles.velocity[i], 1e-2, 3e-3, where);
      }
    }
    if (flipped) continue;
    for (const Tally* t : {&sx, &sv, &fx, &fv}) t->expect_within();
    std::printf("[ measured ] %zu particles, %zu contacts in the last step\n",
                free.particles.size(), free.current.contacts.size());
    return;
  }
  FAIL() << "three samples in a row had a pair cross the margin within rounding: unlikely";
}

// PGS as a CPU device runs this system (one work-item, rows interleaved), and coloured (as a GPU)
TEST(ReferenceStep, FiveStepsPgsMatchPositions) { five_steps(SweepKind::Pgs, kSerialLanes); }
TEST(ReferenceStep, FiveStepsColouredPgsMatchPositions) { five_steps(SweepKind::Pgs, 0); }
// PGS as a CPU device runs a large system (its parts side by side, then their boundary), here
// with every system above the one-group threshold, in three parts
TEST(ReferenceStep, FiveStepsPgsInRunsMatchPositions) {
  five_steps(SweepKind::Pgs, kSerialLanes, /*one_group_rows=*/0, /*sweep_parts=*/3);
}
TEST(ReferenceStep, FiveStepsJacobiMatchPositions) { five_steps(SweepKind::Jacobi, kSerialLanes); }

}  // namespace
}  // namespace talus
