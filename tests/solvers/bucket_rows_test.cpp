// The bucket rows (solvers/bucket_rows, kernels/bucket.cl): the device kernels against their
// double twins on fresh random inputs, the warm-start matching, and the rows' effective masses
// against a rigid body whose mobility is known in closed form.
#include "solvers/bucket_rows.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <map>
#include <random>
#include <set>

#include "solvers/dem_world.hpp"
#include "tests/solvers/bucket_test_util.hpp"
#include "tests/solvers/dem_test_util.hpp"

namespace talus {
namespace {

using test::Tally;

// random candidates touching a random bucket: particles of radius 0.05-0.2 m, up to three
// contacts each, normals of all directions, gaps from -10% to +5% of r, a random symmetric
// positive definite mobility of a body of about a tonne, and a random bucket twist
struct RandomCase {
  Particles particles;
  std::vector<BucketContact> contacts;
  BucketBody bucket;
  Vec3 com;
  reference::StepParams params;
};

RandomCase random_case(std::mt19937_64& rng, int n_particles) {
  test::Draws d{rng};
  RandomCase c;
  c.com = test::as_float(Vec3(d.sym(2.0), d.sym(2.0), 1.0 + d.uniform()));
  for (int i = 0; i < n_particles; ++i) {
    test::add_random_particle(c.particles, d, c.com);
    const int k = 1 + static_cast<int>(d.uniform() * 3);
    for (int j = 0; j < k; ++j) c.contacts.push_back(test::random_contact(c.particles, i, d));
  }
  // W = B B^T / m_ref + a floor: symmetric positive definite, entries of a 1-10 t body
  Mat6 B;
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) B(i, j) = d.sym(1.0);
  c.bucket.mobility = (B * B.transpose() + 0.1 * Mat6::Identity()) / 3000.0;
  // the device holds floats: the reference starts from exactly those
  c.bucket = from_device(to_device(c.bucket));
  c.bucket.velocity = test::as_float(Vec3(d.sym(1), d.sym(1), d.sym(1)));
  c.bucket.omega = test::as_float(Vec3(d.sym(0.5), d.sym(0.5), d.sym(0.5)));
  c.params = test::bucket_test_params();
  return c;
}

// rows as the device holds them (float), back in double: the reference starts from these
std::vector<reference::Row> float_rows(const std::vector<reference::Row>& rows) {
  std::vector<reference::Row> out;
  for (const auto& r : rows) out.push_back(reference::from_device(to_device(r)));
  return out;
}

Particles device_particles(const Device&, const Buffer<cl_float4>& x, const Buffer<cl_float4>& v,
                           const Buffer<cl_float4>& w, size_t n) {
  std::vector<cl_float4> q(n, to_float4(Vec3::Zero(), 1.0));
  return reference::particles_from_device(x.download(n), v.download(n), w.download(n), q);
}

TEST(BucketRows, KernelsMatchDoubleReferenceOnRandomContacts) {
  const uint64_t seed = test::fresh_seed();
  SCOPED_TRACE(test::seed_note(seed));
  std::mt19937_64 rng(seed);
  RandomCase c = random_case(rng, 200);
  Device& dev = test::shared_device();

  // warm-start impulses on half the contacts: previous contacts with the same normals
  std::vector<BucketImpulse> previous;
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (size_t k = 0; k < c.contacts.size(); k += 2) {
    BucketImpulse b;
    b.particle = c.contacts[k].particle;
    b.normal = c.contacts[k].normal;
    b.impulse_n = 5.0 * u(rng);
    b.impulse_t = Vec3(u(rng), u(rng), u(rng));
    b.impulse_r = 0.05 * Vec3(u(rng), u(rng), u(rng));
    previous.push_back(b);
  }
  const auto match = match_bucket_contacts(c.contacts, previous);
  auto rows = float_rows(make_bucket_rows(c.contacts, c.particles, c.bucket, c.com, c.params, BucketMaterial{},
                                          previous, match));

  // the same inputs on the device
  std::vector<cl_float4> x, v, w;
  for (size_t i = 0; i < c.particles.size(); ++i) {
    x.push_back(to_float4(c.particles.position[i], c.particles.radius[i]));
    v.push_back(to_float4(c.particles.velocity[i], c.particles.inv_mass[i]));
    w.push_back(to_float4(c.particles.omega[i], c.particles.inv_inertia[i]));
  }
  Buffer<cl_float4> bx(dev, x.size()), bv(dev, v.size()), bw(dev, w.size());
  bx.upload(x);
  bv.upload(v);
  bw.upload(w);
  BucketRowBlock block(dev);
  std::vector<TlRow> device_rows;
  for (const auto& r : rows) device_rows.push_back(to_device(r));
  block.set_rows(device_rows);
  block.set_bucket(c.bucket);

  // gather: exact copies of the candidates' state
  std::vector<int> pick = {7, 3, 199, 0};
  const Particles gathered = block.gather(pick, bx, bv, bw);
  for (size_t k = 0; k < pick.size(); ++k) {
    EXPECT_EQ(gathered.position[k], test::as_float(c.particles.position[pick[k]]));
    EXPECT_EQ(gathered.velocity[k], test::as_float(c.particles.velocity[pick[k]]));
    EXPECT_EQ(gathered.inv_inertia[k], test::as_float(c.particles.inv_inertia[pick[k]]));
  }

  // warm start and five sweeps on both sides
  Particles ref = c.particles;
  BucketBody ref_bucket = c.bucket;
  reference::bucket_warm_start(rows, ref);
  block.warm_start(bv, bw);
  constexpr int kSweeps = 5;
  for (int s = 0; s < kSweeps; ++s) {
    reference::bucket_sweep(rows, ref, ref_bucket);
    block.sweep(bv, bw);
  }
  const Particles got = device_particles(dev, bx, bv, bw, c.particles.size());
  const auto got_rows = block.rows();
  const BucketBody got_bucket = block.bucket();

  // float rounding over five serial sweeps of ~400 rows: relative 1e-4 of the values' scale
  // (measured: about 5e-6)
  Tally velocity("bucket_sweep particle velocities"), impulses("bucket_sweep impulses"),
      twist("bucket_sweep bucket twist");
  for (size_t i = 0; i < ref.size(); ++i) {
    velocity.vector(got.velocity[i], ref.velocity[i], 1e-4, 1e-6, "particle " + std::to_string(i));
    velocity.vector(got.omega[i], ref.omega[i], 1e-4, 1e-5, "omega " + std::to_string(i));
  }
  // impulses near zero (a row leaving contact, friction at the cone's tip) inherit the rounding of
  // the largest ones: their absolute tolerance is scaled by the largest normal impulse
  double scale = 0.0;
  for (const auto& r : rows) scale = std::max(scale, r.impulse_n);
  for (size_t k = 0; k < rows.size(); ++k) {
    const reference::Row g = reference::from_device(got_rows[k]);
    impulses.scalar(g.impulse_n, rows[k].impulse_n, 1e-4, 2e-6 * scale, "lambda_n " + std::to_string(k));
    impulses.vector(g.impulse_t, rows[k].impulse_t, 1e-4, 2e-6 * scale, "lambda_t " + std::to_string(k));
    impulses.vector(g.impulse_r, rows[k].impulse_r, 1e-4, 2e-6 * 0.2 * scale, "lambda_r " + std::to_string(k));
  }
  twist.vector(got_bucket.velocity, ref_bucket.velocity, 1e-4, 1e-7, "bucket v");
  twist.vector(got_bucket.omega, ref_bucket.omega, 1e-4, 1e-7, "bucket omega");
  velocity.expect_within();
  impulses.expect_within();
  twist.expect_within();
}

// the device's warm start and `sweeps` sweeps of `rows` with chunks of `chunk` rows: the particle
// velocities and omegas, the rows and the bucket, all as the device holds them
struct DeviceSweeps {
  std::vector<cl_float4> velocity, omega;
  std::vector<TlRow> rows;
  TlBucketBody bucket;
};

DeviceSweeps device_sweeps(Device& dev, const RandomCase& c, const std::vector<TlRow>& rows,
                           size_t chunk, int sweeps) {
  std::vector<cl_float4> v, w;
  for (size_t i = 0; i < c.particles.size(); ++i) {
    v.push_back(to_float4(c.particles.velocity[i], c.particles.inv_mass[i]));
    w.push_back(to_float4(c.particles.omega[i], c.particles.inv_inertia[i]));
  }
  Buffer<cl_float4> bv(dev, v.size()), bw(dev, w.size());
  bv.upload(v);
  bw.upload(w);
  BucketRowBlock block(dev, chunk);
  block.set_rows(rows);
  block.set_bucket(c.bucket);
  block.warm_start(bv, bw);
  for (int s = 0; s < sweeps; ++s) block.sweep(bv, bw);
  return {bv.download(v.size()), bw.download(w.size()), block.rows(), to_device(block.bucket())};
}

template <class T>
bool same_bytes(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

TEST(BucketRows, ChunksOfAnySizeGiveTheSerialWalkBitForBit) {
  // kernels/bucket.cl walks the rows' chain in chunks loaded into local memory; a particle with
  // several rows in a chunk shares one slot. Rows shuffled so that a particle's rows fall in the
  // same chunk, in different chunks, and apart: chunks of 7 and 64 rows must give the bytes of
  // chunks of one row (the serial walk from global memory)
  const uint64_t seed = test::fresh_seed();
  SCOPED_TRACE(test::seed_note(seed));
  std::mt19937_64 rng(seed);
  const RandomCase c = random_case(rng, 120);
  std::vector<BucketImpulse> previous;
  for (const auto& contact : c.contacts) {
    BucketImpulse b;
    b.particle = contact.particle;
    b.normal = contact.normal;
    b.impulse_n = 2.0;
    b.impulse_t = 0.1 * contact.normal.unitOrthogonal();
    previous.push_back(b);
  }
  const auto match = match_bucket_contacts(c.contacts, previous);
  std::vector<TlRow> rows;
  for (const auto& r : make_bucket_rows(c.contacts, c.particles, c.bucket, c.com, c.params,
                                        BucketMaterial{}, previous, match))
    rows.push_back(to_device(r));
  std::shuffle(rows.begin(), rows.end(), rng);
  Device& dev = test::shared_device();
  const DeviceSweeps serial = device_sweeps(dev, c, rows, 1, 4);
  for (size_t chunk : {size_t{7}, size_t{64}}) {
    SCOPED_TRACE("chunk " + std::to_string(chunk));
    const DeviceSweeps got = device_sweeps(dev, c, rows, chunk, 4);
    EXPECT_TRUE(same_bytes(got.velocity, serial.velocity));
    EXPECT_TRUE(same_bytes(got.omega, serial.omega));
    EXPECT_TRUE(same_bytes(got.rows, serial.rows));
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(got.bucket.velocity.s[k], serial.bucket.velocity.s[k]);
      EXPECT_EQ(got.bucket.omega.s[k], serial.bucket.omega.s[k]);
    }
  }
  // the sweeps did something: the bucket moved
  EXPECT_NE(from_device(serial.bucket).velocity, c.bucket.velocity);
}

// the largest normal-row residual of `rows` (frictionless) [m/s]: the projected step's size in
// velocity, zero where a row is complementary
double worst_normal_residual(const std::vector<ContactRow>& rows, const Particles& p,
                             const BucketBody& b) {
  double worst = 0.0;
  for (const auto& r : rows) {
    const double un = r.normal.dot(b.velocity + b.omega.cross(r.arm_b) - p.velocity[r.a]);
    const double res =
        (std::max(0.0, r.impulse_n + (r.rhs - un - r.sigma * r.impulse_n) * r.inv_dn) -
         r.impulse_n) /
        r.inv_dn;
    worst = std::max(worst, std::abs(res));
  }
  return worst;
}

TEST(BucketRows, FrictionlessSweepsConvergeToNonPenetration) {
  // the reference alone, normal rows only: with compliance the problem is a strictly convex QP,
  // on which projected Gauss-Seidel converges; every normal row ends satisfied (complementarity)
  const uint64_t seed = test::fresh_seed();
  SCOPED_TRACE(test::seed_note(seed));
  std::mt19937_64 rng(seed);
  RandomCase c = random_case(rng, 30);
  const BucketMaterial frictionless{0.0, 0.0};
  auto rows = make_bucket_rows(c.contacts, c.particles, c.bucket, c.com, c.params, frictionless, {}, {});
  Particles p = c.particles;
  BucketBody b = c.bucket;
  std::printf("[ measured ] sweeps  max normal-row residual [m/s]\n");
  double worst = 0.0;
  for (int s = 1; s <= 400; ++s) {
    reference::bucket_sweep(rows, p, b);
    worst = worst_normal_residual(rows, p, b);
    if (s == 1 || s == 10 || s == 50 || s == 100 || s == 400) std::printf("[ measured ] %6d  %.3e\n", s, worst);
  }
  EXPECT_LT(worst, 1e-6);
  for (const auto& r : rows) EXPECT_GE(r.impulse_n, 0.0);
}

TEST(BucketRows, SweepsKeepImpulsesInTheirConesAndMoveTheBucketByW) {
  // with friction and rolling (the default bucket material), after any number of sweeps: every
  // impulse lies in its cone, and the bucket has moved by exactly W times the rows' total wrench
  const uint64_t seed = test::fresh_seed();
  SCOPED_TRACE(test::seed_note(seed));
  std::mt19937_64 rng(seed);
  RandomCase c = random_case(rng, 30);
  auto rows = make_bucket_rows(c.contacts, c.particles, c.bucket, c.com, c.params, BucketMaterial{}, {}, {});
  Particles p = c.particles;
  BucketBody b = c.bucket;
  for (int s = 0; s < 50; ++s) reference::bucket_sweep(rows, p, b);
  for (const auto& r : rows) {
    EXPECT_GE(r.impulse_n, 0.0);
    EXPECT_LE(r.impulse_t.norm(), r.friction * r.impulse_n * (1 + 1e-12) + 1e-15);
    EXPECT_LE(r.impulse_r.norm(), std::sqrt(2.0) * r.rolling_limit * r.impulse_n + 1e-15);
  }
  const Vec6 moved = b.twist() - c.bucket.twist();
  const Vec6 expected = c.bucket.mobility * bucket_wrench_impulse(rows);
  EXPECT_LT((moved - expected).norm(), 1e-9 * (1.0 + expected.norm()));
}

TEST(BucketRows, NormalEffectiveMassOfAFreeRigidBody) {
  // a free body: W = diag(1/m, I^-1). A contact at arm r with normal n has
  // D_n = 1/m_p + 1/m + (r x n)^T I^-1 (r x n) + Sigma
  const double m = 1350.0;
  const Vec3 inertia(973.0, 383.0, 1032.0);
  BucketBody b;
  b.mobility.setZero();
  b.mobility.block<3, 3>(0, 0) = Mat3d::Identity() / m;
  b.mobility.block<3, 3>(3, 3) = inertia.cwiseInverse().asDiagonal();
  Particles p;
  p.add(Vec3(1.0, 0.2, 0.3), 0.1, 2590.0);
  BucketContact c;
  c.particle = 0;
  c.normal = Vec3(0.3, -0.2, 1.0).normalized();
  c.gap = -0.002;
  c.point = p.position[0] + c.normal * (0.1 + 0.5 * c.gap);
  c.arm_particle = c.point - p.position[0];
  reference::StepParams params;
  params.dt = 0.01;
  params.young = 1e8;
  params.poisson = 0.3;
  params.damping_tau = 0.02;
  params.overlap_floor_rel = 1e-4;
  const Vec3 com(0.5, 0.0, 0.0);
  const auto rows = make_bucket_rows({c}, p, b, com, params, BucketMaterial{}, {}, {});
  ASSERT_EQ(rows.size(), 1u);
  const Vec3 rn = (c.point - com).cross(c.normal);
  const double want = p.inv_mass[0] + 1.0 / m + rn.dot(inertia.cwiseInverse().asDiagonal() * rn) + rows[0].sigma;
  EXPECT_NEAR(1.0 / rows[0].inv_dn, want, 1e-12 * want);
  EXPECT_EQ(rows[0].b, TL_BUCKET_BODY);
  EXPECT_DOUBLE_EQ(rows[0].friction, BucketMaterial{}.friction);
  // the friction mass bounds every tangential direction's true effective mass from above
  const Vec3 t = c.normal.unitOrthogonal();
  const Vec3 rt = (c.point - com).cross(t);
  const double true_dt = p.inv_mass[0] + p.inv_inertia[0] * c.arm_particle.squaredNorm() + 1.0 / m +
                         rt.dot(inertia.cwiseInverse().asDiagonal() * rt);
  EXPECT_GE(1.0 / rows[0].inv_dt, true_dt * (1 - 1e-12));
}

TEST(BucketRows, MatchingPairsTheNearestNormalOfTheSameParticleOnce) {
  auto contact = [](int particle, Vec3 n) {
    BucketContact c;
    c.particle = particle;
    c.normal = n.normalized();
    return c;
  };
  auto previous = [](int particle, Vec3 n, double ln) {
    BucketImpulse b;
    b.particle = particle;
    b.normal = n.normalized();
    b.impulse_n = ln;
    return b;
  };
  // particle 3 in the inner corner (bottom and back plate), particle 5 on the bottom only,
  // particle 8 new; previous sorted by particle
  const std::vector<BucketContact> now = {contact(3, Vec3(0, 0, -1)), contact(3, Vec3(-1, 0, -0.1)),
                                          contact(5, Vec3(0.7, 0, -0.7)), contact(8, Vec3(0, 0, -1))};
  const std::vector<BucketImpulse> before = {previous(3, Vec3(-1, 0, 0), 1.0), previous(3, Vec3(0, 0.1, -1), 2.0),
                                             previous(5, Vec3(0, 0, -1), 3.0), previous(7, Vec3(0, 0, -1), 4.0)};
  const auto m = match_bucket_contacts(now, before);
  EXPECT_EQ(m, (std::vector<int>{1, 0, -1, -1}));  // 5: 45 degrees apart is a different contact
  // two new contacts of one particle never share an old one
  const auto twice = match_bucket_contacts({contact(3, Vec3(0, 0, -1)), contact(3, Vec3(0, 0.05, -1))}, before);
  EXPECT_EQ(twice[0], 1);
  EXPECT_EQ(twice[1], -1);
}

// the coloured sweep (BucketSweep::Coloured): a particle's rows in different colours, a colour's
// rows solved at once against the bucket split among them

// the particle of each row
std::vector<int> particles_of(const std::vector<ContactRow>& rows) {
  std::vector<int> out;
  out.reserve(rows.size());
  for (const auto& r : rows) out.push_back(r.a);
  return out;
}

TEST(BucketRows, ColouringPutsAParticlesRowsInDifferentColours) {
  // rows of random particles, up to five a particle, in random order: colour c holds each
  // particle's c-th row in row order, so a colour's rows share no particle, there are as many
  // colours as the most rows one particle has, and each row's split is its colour's size
  const uint64_t seed = test::fresh_seed();
  SCOPED_TRACE(test::seed_note(seed));
  std::mt19937_64 rng(seed);
  std::vector<int> particle;
  std::map<int, int> rows_of;
  for (int k = 0; k < 300; ++k) {
    const int p = static_cast<int>(rng() % 90);
    if (rows_of[p] == 5) continue;
    ++rows_of[p];
    particle.push_back(p);
  }
  int most = 0;
  for (const auto& [p, n] : rows_of) most = std::max(most, n);
  const BucketColouring c = colour_bucket_rows(particle);
  ASSERT_EQ(c.colour_start.size(), static_cast<size_t>(most + 1));
  ASSERT_EQ(c.order.size(), particle.size());
  ASSERT_EQ(c.split.size(), particle.size());
  EXPECT_EQ(c.colour_start.front(), 0);
  EXPECT_EQ(c.colour_start.back(), static_cast<int>(particle.size()));
  // a permutation of the rows
  std::vector<int> sorted = c.order;
  std::sort(sorted.begin(), sorted.end());
  for (size_t k = 0; k < sorted.size(); ++k) EXPECT_EQ(sorted[k], static_cast<int>(k));
  // row k's colour is the number of its particle's rows before it
  std::map<int, int> before;
  std::vector<int> want_colour(particle.size());
  for (size_t k = 0; k < particle.size(); ++k) want_colour[k] = before[particle[k]]++;
  for (int colour = 0; colour < most; ++colour) {
    std::set<int> seen;
    for (int i = c.colour_start[colour]; i < c.colour_start[colour + 1]; ++i) {
      const int k = c.order[i];
      EXPECT_EQ(want_colour[k], colour) << "row " << k;
      EXPECT_TRUE(seen.insert(particle[k]).second) << "particle " << particle[k] << " twice";
      if (i > c.colour_start[colour]) {
        EXPECT_GT(k, c.order[i - 1]);
      }
      EXPECT_EQ(c.split[k], c.colour_start[colour + 1] - c.colour_start[colour]);
    }
  }
  EXPECT_TRUE(colour_bucket_rows({}).empty());
}

TEST(BucketRows, SplitEffectiveMassesSeeTheBucketSplitAmongTheColour) {
  // a row whose colour has s rows sees the bucket's mobility s W: its normal mass
  // 1/m_p + s n^T K n + Sigma, and its rolling mass the particle's plus s times the bucket's
  const uint64_t seed = test::fresh_seed();
  SCOPED_TRACE(test::seed_note(seed));
  std::mt19937_64 rng(seed);
  const RandomCase c = random_case(rng, 20);
  auto one = make_bucket_rows(c.contacts, c.particles, c.bucket, c.com, c.params, BucketMaterial{},
                              {}, {});
  auto split_rows = one;
  auto split_mobility = one;
  const BucketColouring colouring = colour_bucket_rows(particles_of(one));
  set_bucket_effective_masses(split_rows, c.contacts, c.particles, c.bucket.mobility,
                              colouring.split);
  for (size_t k = 0; k < one.size(); ++k) {
    std::vector<ContactRow> alone = {one[k]};
    set_bucket_effective_masses(alone, c.contacts, c.particles,
                                colouring.split[k] * c.bucket.mobility);
    EXPECT_NEAR(split_rows[k].inv_dn, alone[0].inv_dn, 1e-12 * alone[0].inv_dn) << k;
    EXPECT_NEAR(split_rows[k].inv_dt, alone[0].inv_dt, 1e-12 * alone[0].inv_dt) << k;
    EXPECT_NEAR(split_rows[k].inv_dr, alone[0].inv_dr, 1e-12 * alone[0].inv_dr) << k;
    if (colouring.split[k] > 1) {
      EXPECT_LT(split_rows[k].inv_dn, one[k].inv_dn) << k;
    }
  }
  EXPECT_THROW(
      set_bucket_effective_masses(split_rows, c.contacts, c.particles, c.bucket.mobility, {1, 2}),
      Error);
}

// warm-start impulses on every other contact, as in a step after the first
std::vector<BucketImpulse> some_previous(const RandomCase& c, std::mt19937_64& rng) {
  std::vector<BucketImpulse> previous;
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (size_t k = 0; k < c.contacts.size(); k += 2) {
    BucketImpulse b;
    b.particle = c.contacts[k].particle;
    b.normal = c.contacts[k].normal;
    b.impulse_n = 5.0 * u(rng);
    b.impulse_t = Vec3(u(rng), u(rng), u(rng));
    b.impulse_r = 0.05 * Vec3(u(rng), u(rng), u(rng));
    previous.push_back(b);
  }
  return previous;
}

// the device's coloured warm start and `sweeps` sweeps
DeviceSweeps device_coloured_sweeps(Device& dev, const RandomCase& c,
                                    const std::vector<TlRow>& rows,
                                    const BucketColouring& colouring, int sweeps) {
  std::vector<cl_float4> v, w;
  for (size_t i = 0; i < c.particles.size(); ++i) {
    v.push_back(to_float4(c.particles.velocity[i], c.particles.inv_mass[i]));
    w.push_back(to_float4(c.particles.omega[i], c.particles.inv_inertia[i]));
  }
  Buffer<cl_float4> bv(dev, v.size()), bw(dev, w.size());
  bv.upload(v);
  bw.upload(w);
  BucketRowBlock block(dev);
  block.set_rows(rows, colouring);
  block.set_bucket(c.bucket);
  block.warm_start(bv, bw);
  for (int s = 0; s < sweeps; ++s) block.sweep(bv, bw);
  return {bv.download(v.size()), bw.download(w.size()), block.rows(), to_device(block.bucket())};
}

TEST(BucketRows, ColouredKernelsMatchDoubleReferenceOnRandomContacts) {
  // kernels/bucket.cl bucket_warm_start_coloured and bucket_sweep_coloured against their double
  // twins: 200 particles with one to three rows each (so two or three colours of up to 200 rows,
  // more than one work-group's chunk), warm started, five sweeps
  const uint64_t seed = test::fresh_seed();
  SCOPED_TRACE(test::seed_note(seed));
  std::mt19937_64 rng(seed);
  const RandomCase c = random_case(rng, 200);
  const auto previous = some_previous(c, rng);
  const auto match = match_bucket_contacts(c.contacts, previous);
  auto made = make_bucket_rows(c.contacts, c.particles, c.bucket, c.com, c.params, BucketMaterial{},
                               previous, match);
  const BucketColouring colouring = colour_bucket_rows(particles_of(made));
  ASSERT_GE(colouring.colour_start.size(), 3u);
  ASSERT_GT(colouring.colour_start[1], static_cast<int>(BucketRowBlock::kColouredGroup));
  set_bucket_effective_masses(made, c.contacts, c.particles, c.bucket.mobility, colouring.split);
  auto rows = float_rows(made);
  std::vector<TlRow> device_rows;
  device_rows.reserve(rows.size());
  for (const auto& r : rows) device_rows.push_back(to_device(r));

  constexpr int kSweeps = 5;
  Particles ref = c.particles;
  BucketBody ref_bucket = c.bucket;
  reference::bucket_warm_start_coloured(rows, colouring, ref);
  for (int s = 0; s < kSweeps; ++s)
    reference::bucket_sweep_coloured(rows, colouring, ref, ref_bucket);
  Device& dev = test::shared_device();
  const DeviceSweeps got = device_coloured_sweeps(dev, c, device_rows, colouring, kSweeps);

  // float rounding over five sweeps, as the serial walk's test (measured: about 1e-6)
  Tally velocity("bucket_sweep_coloured particle velocities"),
      impulses("bucket_sweep_coloured impulses"), twist("bucket_sweep_coloured bucket twist");
  for (size_t i = 0; i < ref.size(); ++i) {
    velocity.vector(xyz(got.velocity[i]), ref.velocity[i], 1e-4, 1e-6,
                    "particle " + std::to_string(i));
    velocity.vector(xyz(got.omega[i]), ref.omega[i], 1e-4, 1e-5, "omega " + std::to_string(i));
  }
  double scale = 0.0;
  for (const auto& r : rows) scale = std::max(scale, r.impulse_n);
  for (size_t k = 0; k < rows.size(); ++k) {
    const reference::Row g = reference::from_device(got.rows[k]);
    impulses.scalar(g.impulse_n, rows[k].impulse_n, 1e-4, 2e-6 * scale,
                    "lambda_n " + std::to_string(k));
    impulses.vector(g.impulse_t, rows[k].impulse_t, 1e-4, 2e-6 * scale,
                    "lambda_t " + std::to_string(k));
    impulses.vector(g.impulse_r, rows[k].impulse_r, 1e-4, 2e-6 * 0.2 * scale,
                    "lambda_r " + std::to_string(k));
  }
  const BucketBody got_bucket = from_device(got.bucket);
  twist.vector(got_bucket.velocity, ref_bucket.velocity, 1e-4, 1e-7, "bucket v");
  twist.vector(got_bucket.omega, ref_bucket.omega, 1e-4, 1e-7, "bucket omega");
  velocity.expect_within();
  impulses.expect_within();
  twist.expect_within();
  // the sweeps did something: the bucket moved
  EXPECT_GT((ref_bucket.twist() - c.bucket.twist()).norm(), 1e-6);

  // determinism: the same inputs on the same device and work-group size, the same bytes
  const DeviceSweeps again = device_coloured_sweeps(dev, c, device_rows, colouring, kSweeps);
  EXPECT_TRUE(same_bytes(again.velocity, got.velocity));
  EXPECT_TRUE(same_bytes(again.omega, got.omega));
  EXPECT_TRUE(same_bytes(again.rows, got.rows));
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(again.bucket.velocity.s[k], got.bucket.velocity.s[k]);
    EXPECT_EQ(again.bucket.omega.s[k], got.bucket.omega.s[k]);
  }
}

TEST(BucketRows, ColouredSweepsKeepImpulsesInTheirConesAndMoveTheBucketByW) {
  // the split copies' mean change is W times the colour's impulse change, so after any number
  // of coloured sweeps the bucket has moved by exactly W times the rows' total wrench, as the
  // direct solve will move it (the outer passes' agreement rests on this)
  const uint64_t seed = test::fresh_seed();
  SCOPED_TRACE(test::seed_note(seed));
  std::mt19937_64 rng(seed);
  RandomCase c = random_case(rng, 30);
  auto rows = make_bucket_rows(c.contacts, c.particles, c.bucket, c.com, c.params, BucketMaterial{},
                               {}, {});
  const BucketColouring colouring = colour_bucket_rows(particles_of(rows));
  set_bucket_effective_masses(rows, c.contacts, c.particles, c.bucket.mobility, colouring.split);
  Particles p = c.particles;
  BucketBody b = c.bucket;
  for (int s = 0; s < 50; ++s) reference::bucket_sweep_coloured(rows, colouring, p, b);
  for (const auto& r : rows) {
    EXPECT_GE(r.impulse_n, 0.0);
    EXPECT_LE(r.impulse_t.norm(), r.friction * r.impulse_n * (1 + 1e-12) + 1e-15);
    EXPECT_LE(r.impulse_r.norm(), std::sqrt(2.0) * r.rolling_limit * r.impulse_n + 1e-15);
  }
  const Vec6 moved = b.twist() - c.bucket.twist();
  const Vec6 expected = c.bucket.mobility * bucket_wrench_impulse(rows);
  EXPECT_LT((moved - expected).norm(), 1e-9 * (1.0 + expected.norm()));
}

TEST(BucketRows, ColouredSweepsConvergeLikeTheSerialWalk) {
  // both sweeps on the same frictionless rows (a strictly convex QP), from zero impulses, the
  // residual printed against the sweeps: the coloured sweep converges too, to the same impulses.
  // It needs more sweeps: a row sees the bucket s times lighter. This case is a hard one for it:
  // 60 particles of 1-90 kg with one to three rows each, colours of up to 60 rows sharing a
  // bucket of a few hundred kilograms (W's scale, 1/3000 kg^-1 times a random B B^T); over seeds
  // 1-40 the coloured sweep took 1.2-12.8 times the serial walk's sweeps to 1e-6 m/s (at most
  // 472). A dig's bucket is the machine's articulated mass, tonnes, shared among its rows; what
  // the coloured sweep does to a dig's sweeps and loads is measured in docs/digging.md
  const uint64_t seed = test::fresh_seed();
  SCOPED_TRACE(test::seed_note(seed));
  std::mt19937_64 rng(seed);
  RandomCase c = random_case(rng, 60);
  const BucketMaterial frictionless{0.0, 0.0};
  auto serial =
      make_bucket_rows(c.contacts, c.particles, c.bucket, c.com, c.params, frictionless, {}, {});
  auto coloured = serial;
  const BucketColouring colouring = colour_bucket_rows(particles_of(coloured));
  set_bucket_effective_masses(coloured, c.contacts, c.particles, c.bucket.mobility,
                              colouring.split);
  Particles ps = c.particles, pc = c.particles;
  BucketBody bs = c.bucket, bc = c.bucket;
  constexpr double kConverged = 1e-6;  // [m/s]
  int serial_at = -1, coloured_at = -1;
  std::printf("[ measured ] sweeps  max normal-row residual [m/s]: serial  coloured\n");
  for (int s = 1; s <= 5000; ++s) {
    reference::bucket_sweep(serial, ps, bs);
    reference::bucket_sweep_coloured(coloured, colouring, pc, bc);
    const double rs = worst_normal_residual(serial, ps, bs),
                 rc = worst_normal_residual(coloured, pc, bc);
    if (serial_at < 0 && rs < kConverged) serial_at = s;
    if (coloured_at < 0 && rc < kConverged) coloured_at = s;
    if (s == 1 || s == 3 || s == 10 || s == 30 || s == 100 || s == 300 || s == 1000 || s == 5000)
      std::printf("[ measured ] %6d  %.3e  %.3e\n", s, rs, rc);
  }
  std::printf("[ measured ] sweeps to %.0e m/s: serial %d, coloured %d (colours %zu)\n", kConverged,
              serial_at, coloured_at, colouring.colour_start.size() - 1);
  ASSERT_GT(serial_at, 0);
  ASSERT_GT(coloured_at, 0);
  // the same solution: the problem's minimiser is unique
  double scale = 0.0;
  for (const auto& r : serial) scale = std::max(scale, r.impulse_n);
  for (size_t k = 0; k < serial.size(); ++k)
    EXPECT_NEAR(coloured[k].impulse_n, serial[k].impulse_n, 1e-6 * scale) << "row " << k;
  EXPECT_LT((bc.twist() - bs.twist()).norm(), 1e-6 * (1.0 + bs.twist().norm()));
}

}  // namespace
}  // namespace talus
