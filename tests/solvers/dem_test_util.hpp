// Helpers for tests that compare DEM device stages with solvers/dem_reference: a shared PoCL
// device, reproducible random seeds, random granular scenes whose discrete decisions cannot be
// flipped by float rounding, and a tally of the worst difference against a tolerance.
#pragma once
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "host/device.hpp"
#include "solvers/dem_reference.hpp"
#include "solvers/dem_settings.hpp"
#include "solvers/particles.hpp"

namespace talus::test {

// one device per test program, so each kernel program is built once
inline Device& shared_device() {
  static Device dev;
  return dev;
}

// a fresh seed from std::random_device, or TALUS_TEST_SEED to replay a failure
inline uint64_t fresh_seed() {
  if (const char* s = std::getenv("TALUS_TEST_SEED")) return std::strtoull(s, nullptr, 10);
  std::random_device rd;
  return (uint64_t(rd()) << 32) ^ rd();
}

inline std::string seed_note(uint64_t seed) {
  return "seed " + std::to_string(seed) + " (replay with TALUS_TEST_SEED=" + std::to_string(seed) +
         ")";
}

// the nearest float, so host doubles equal what the device holds. The volatile is needed:
// GCC 12.2 at -O2/-O3 (SLP vectorizer) drops the float truncation when two adjacent
// `(double)(float)x` conversions are vectorised together, returning x unchanged
inline double as_float(double x) {
  volatile float f = static_cast<float>(x);
  return f;
}
inline Vec3 as_float(const Vec3& v) {
  return Vec3(as_float(v.x()), as_float(v.y()), as_float(v.z()));
}

// a granular system ready for DemWorld and the reference
struct Scene {
  Particles particles;
  std::vector<StaticGeom> geoms;
  Bounds bounds;
  Material material;
  DemSettings settings;
};

struct SceneOptions {
  int nx = 10, ny = 10, nz = 10;  // lattice sites (some are dropped)
  double radius = 0.01;           // largest radius [m]
  double speed = 0.5;             // velocity components in [-speed, speed] [m/s]
  double spin = 20.0;             // angular velocity components in [-spin, spin] [1/s]
  int fixed = 2;                  // particles with zero inverse mass and inertia
  int inside_box = 2;             // particles kept with their centre inside the oriented box
};

// the grid DemWorld::update_params builds for these particles (kept in step with it)
inline reference::StepParams expected_grid(const Scene& s) {
  reference::StepParams p;
  double max_radius = 0.0;
  for (double r : s.particles.radius) max_radius = std::max(max_radius, r);
  Vec3 extent = s.bounds.hi - s.bounds.lo;
  const double speculative = 2.0 * s.settings.dt * s.settings.max_speed;
  double cell = 2.0 * max_radius * (1.0 + s.settings.margin_rel) + speculative;
  Eigen::Vector3i dims = (extent / cell).array().ceil().cast<int>().cwiseMax(1);
  p.grid_origin = as_float(s.bounds.lo);
  p.cell_size = as_float(cell);
  p.grid_nx = dims.x();
  p.grid_ny = dims.y();
  p.grid_nz = dims.z();
  p.margin_rel = as_float(s.settings.margin_rel);
  p.dt = s.settings.dt;
  p.gravity = s.settings.gravity;
  p.speculative = speculative;
  p.pair_reach = s.settings.pair_reach;
  return p;
}

// the speculative reach of a pair closing at `closing` [m/s] (kernels/narrowphase.cl
// contact_margin, in double)
inline double speculative_reach(const reference::StepParams& p, double closing) {
  if (!p.pair_reach) return p.speculative;
  return std::min(p.speculative, 2.0 * p.dt * std::max(0.0, closing + p.gravity.norm() * p.dt));
}

// particles whose discrete decisions sit within rounding of a threshold: a coordinate within
// 1e-4 cell of a cell boundary, a pair or wall gap within 1e-4 r of the contact margin, a
// centre within 1e-4 r of a box surface, or two box faces nearly equally deep
inline std::vector<char> ambiguous(const Scene& s) {
  const double tiny = 1e-4;
  reference::StepParams p = expected_grid(s);
  const Particles& ps = s.particles;
  size_t n = ps.size();
  std::vector<char> bad(n, 0);
  for (size_t i = 0; i < n; ++i) {
    Vec3 rel = (ps.position[i] - p.grid_origin) / p.cell_size;
    for (int k = 0; k < 3; ++k)
      if (std::abs(rel[k] - std::round(rel[k])) < tiny) bad[i] = 1;
    double ri = ps.radius[i];
    for (const StaticGeom& g : s.geoms) {
      Vec3 normal;
      double gap = reference::sphere_geom(ps.position[i], ri, g, &normal);
      const double reach = speculative_reach(p, ps.velocity[i].dot(normal));
      if (std::abs(gap - p.margin_rel * ri - reach) < tiny * ri) bad[i] = 1;
      if (g.type != StaticGeom::Type::Box) continue;
      // distance of the centre from the surface, and the two shallowest face depths inside
      Vec3 d = ps.position[i] - g.centre;
      Vec3 local(d.dot(g.axes.col(0)), d.dot(g.axes.col(1)), d.dot(g.axes.col(2)));
      Vec3 depth = g.half - local.cwiseAbs();
      if (std::abs(gap + ri) < tiny * ri) bad[i] = 1;
      if (depth.minCoeff() > 0.0) {
        std::sort(depth.data(), depth.data() + 3);
        if (depth[1] - depth[0] < 1e-3 * ri) bad[i] = 1;
      }
    }
  }
  // pairs: drop the later particle (all pairs; a few hundred thousand distance checks)
  for (size_t i = 0; i < n; ++i) {
    if (bad[i]) continue;
    for (size_t j = i + 1; j < n; ++j) {
      if (bad[j]) continue;
      double rmin = std::min(ps.radius[i], ps.radius[j]);
      const Vec3 d = ps.position[j] - ps.position[i];
      double dist = d.norm();
      double gap = dist - ps.radius[i] - ps.radius[j];
      const double closing = dist > 0.0 ? (ps.velocity[i] - ps.velocity[j]).dot(d / dist) : 0.0;
      const double margin = p.margin_rel * rmin + speculative_reach(p, closing);
      if (std::abs(gap - margin) < tiny * rmin || dist < tiny * rmin) bad[j] = 1;
    }
  }
  return bad;
}

inline Particles keep(const Particles& in, const std::vector<char>& drop) {
  Particles out;
  for (size_t i = 0; i < in.size(); ++i) {
    if (drop[i]) continue;
    out.position.push_back(in.position[i]);
    out.velocity.push_back(in.velocity[i]);
    out.omega.push_back(in.omega[i]);
    out.rotation.push_back(in.rotation[i]);
    out.radius.push_back(in.radius[i]);
    out.inv_mass.push_back(in.inv_mass[i]);
    out.inv_inertia.push_back(in.inv_inertia[i]);
  }
  return out;
}

// a jittered lattice of spheres in a walled box (ground, four walls) with one oriented box
// among them; neighbours overlap or sit within the contact margin, and the top layer lies
// above the grid bounds so the clamped cells are exercised. Every value is a float.
inline Scene random_scene(std::mt19937_64& rng, const SceneOptions& o = {}) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  auto sym = [&](double a) { return a * (2.0 * unit(rng) - 1.0); };
  Scene s;
  s.settings.dt = 1e-3;
  double r = o.radius;
  double spacing = 2.0 * r * 0.96;
  Vec3 size(o.nx * spacing, o.ny * spacing, o.nz * spacing);
  s.bounds.lo = Vec3::Zero();
  s.bounds.hi = Vec3(size.x(), size.y(), size.z() - spacing);

  // ground and four walls, normals into the free side
  s.geoms.push_back(StaticGeom::plane(Vec3::Zero(), Vec3::UnitZ()));
  s.geoms.push_back(StaticGeom::plane(Vec3::Zero(), Vec3::UnitX()));
  s.geoms.push_back(StaticGeom::plane(Vec3(size.x(), 0, 0), -Vec3::UnitX()));
  s.geoms.push_back(StaticGeom::plane(Vec3::Zero(), Vec3::UnitY()));
  s.geoms.push_back(StaticGeom::plane(Vec3(0, size.y(), 0), -Vec3::UnitY()));
  // an oriented box, centred on a lattice site inside the pile
  Vec3 axis = Vec3(sym(1.0), sym(1.0), sym(1.0)).normalized();
  Eigen::Matrix3d axes = Eigen::AngleAxisd(sym(M_PI), axis).toRotationMatrix();
  Vec3 box_centre((o.nx / 2 + 0.5) * spacing, (o.ny / 2 + 0.5) * spacing,
                  (o.nz / 2 + 0.5) * spacing);
  s.geoms.push_back(StaticGeom::box(box_centre, Vec3(1.6, 1.1, 0.9) * spacing, axes));
  for (StaticGeom& g : s.geoms) {
    g.centre = as_float(g.centre);
    g.half = as_float(g.half);
    for (int k = 0; k < 3; ++k) g.axes.col(k) = as_float(Vec3(g.axes.col(k)));
  }

  // lattice sites with jitter and random radii, velocities and orientations
  int inside = 0;
  for (int z = 0; z < o.nz; ++z)
    for (int y = 0; y < o.ny; ++y)
      for (int x = 0; x < o.nx; ++x) {
        Vec3 site = (Vec3(x, y, z) + Vec3::Constant(0.5)) * spacing;
        Vec3 pos = site + Vec3(sym(0.1 * r), sym(0.1 * r), sym(0.1 * r));
        double radius = (s.particles.size() == 0 ? 1.0 : 0.75 + 0.25 * unit(rng)) * r;
        Vec3 normal;
        double box_gap = reference::sphere_geom(pos, radius, s.geoms.back(), &normal);
        if (box_gap < -radius && inside++ >= o.inside_box) continue;
        s.particles.add(as_float(pos), as_float(radius), s.material.density);
        s.particles.velocity.back() = as_float(Vec3(sym(o.speed), sym(o.speed), sym(o.speed)));
        s.particles.omega.back() = as_float(Vec3(sym(o.spin), sym(o.spin), sym(o.spin)));
        Eigen::Vector4d q(sym(1.0), sym(1.0), sym(1.0), sym(1.0));
        q.normalize();
        for (int k = 0; k < 4; ++k) q[k] = as_float(q[k]);
        s.particles.rotation.back() = q;
        s.particles.inv_mass.back() = as_float(s.particles.inv_mass.back());
        s.particles.inv_inertia.back() = as_float(s.particles.inv_inertia.back());
      }
  // a few fixed particles (never the first: it carries the largest radius)
  for (int k = 1; k <= o.fixed && k < static_cast<int>(s.particles.size()); ++k) {
    size_t i = static_cast<size_t>(k) * 7 % s.particles.size();
    s.particles.inv_mass[i] = 0.0;
    s.particles.inv_inertia[i] = 0.0;
  }
  // drop ambiguous particles until none is left (dropping can change the largest radius)
  for (int pass = 0; pass < 10; ++pass) {
    std::vector<char> drop = ambiguous(s);
    if (std::find(drop.begin(), drop.end(), 1) == drop.end()) break;
    s.particles = keep(s.particles, drop);
  }
  return s;
}

// the worst difference between device and reference values, as a fraction of its tolerance
struct Tally {
  explicit Tally(std::string what_) : what(std::move(what_)) {}
  std::string what;
  double max_diff = 0.0;   // largest absolute difference seen
  double max_ratio = 0.0;  // largest difference / tolerance
  std::string worst;
  long checked = 0;

  void add(double diff, double tol, const std::string& where) {
    ++checked;
    max_diff = std::max(max_diff, diff);
    double ratio = tol > 0.0 ? diff / tol : (diff > 0.0 ? INFINITY : 0.0);
    if (!(ratio <= max_ratio)) {
      max_ratio = ratio;
      worst = where + ": difference " + fmt(diff) + ", tolerance " + fmt(tol);
    }
  }
  // |got - want| <= rel |want| + abs
  void scalar(double got, double want, double rel, double abs, const std::string& where) {
    add(std::abs(got - want), rel * std::abs(want) + abs,
        where + " (device " + fmt(got) + ", reference " + fmt(want) + ")");
  }
  // |got - want|_2 <= rel |want|_2 + abs
  void vector(const Vec3& got, const Vec3& want, double rel, double abs, const std::string& where) {
    add((got - want).norm(), rel * want.norm() + abs, where);
  }
  // fails the test when any difference exceeded its tolerance; prints the measured maximum
  void expect_within() const {
    std::printf("[ measured ] %-44s max |diff| %.3e  max diff/tol %.3f  (%ld values)\n",
                what.c_str(), max_diff, max_ratio, checked);
    EXPECT_LE(max_ratio, 1.0) << what << ": worst at " << worst;
  }
  static std::string fmt(double x) {
    std::ostringstream s;
    s.precision(9);
    s << x;
    return s.str();
  }
};

}  // namespace talus::test
