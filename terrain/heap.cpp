#include "terrain/heap.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include "terrain/pile.hpp"
#include "terrain/settle.hpp"
#include "terrain/soil_sample.hpp"

namespace talus {

namespace {

}  // namespace

FlankFit measure_flank_angle(const Particles& p, double bin_width, int sectors) {
  FlankFit fit;
  // the heap's height: the highest free particle top
  for (size_t i = 0; i < p.size(); ++i)
    if (p.inv_mass[i] > 0) fit.height = std::max(fit.height, p.position[i].z() + p.radius[i]);
  double rmax = 0.0;
  for (size_t i = 0; i < p.size(); ++i)
    if (p.inv_mass[i] > 0) rmax = std::max(rmax, p.position[i].head<2>().norm());
  int bins = static_cast<int>(rmax / bin_width) + 1;
  // upper envelope of free particles per (sector, radial bin)
  std::vector<std::vector<double>> top(sectors, std::vector<double>(bins, 0.0));
  for (size_t i = 0; i < p.size(); ++i) {
    if (p.inv_mass[i] <= 0) continue;
    const Vec3& x = p.position[i];
    double rho = x.head<2>().norm();
    int s = static_cast<int>((std::atan2(x.y(), x.x()) + M_PI) / (2 * M_PI) * sectors) % sectors;
    int b = static_cast<int>(rho / bin_width);
    top[s][b] = std::max(top[s][b], x.z() + p.radius[i]);
  }
  // per sector: the flank between 20% and 80% of the height
  std::vector<double> angles;
  for (int s = 0; s < sectors; ++s) {
    std::vector<double> r, z;
    for (int b = 0; b < bins; ++b) {
      double h = top[s][b];
      if (h > 0.2 * fit.height && h < 0.8 * fit.height) {
        r.push_back((b + 0.5) * bin_width);
        z.push_back(h);
      }
    }
    if (r.size() < 3) continue;
    angles.push_back(std::atan(-least_squares_slope(r, z)) * 180.0 / M_PI);
  }
  fit.sectors = static_cast<int>(angles.size());
  if (angles.empty()) return fit;
  double mean = 0.0;
  for (double a : angles) mean += a;
  mean /= angles.size();
  double var = 0.0;
  for (double a : angles) var += (a - mean) * (a - mean);
  fit.angle_deg = mean;
  fit.spread_deg = std::sqrt(var / angles.size());
  return fit;
}

namespace {

// the heap's layout: particle size, lattice spacing, the column's half width and height, and the
// half width of a base wide enough for the run-out [m]
struct HeapLayout {
  double d = 0.0, spacing = 0.0, half = 0.0, column_height = 0.0, base_half = 0.0;
};

HeapLayout heap_layout(const HeapOptions& o) {
  HeapLayout l;
  l.d = o.diameter;
  l.spacing = 1.1 * l.d * 1.02;
  l.half = 0.5 * o.columns * l.spacing;
  l.column_height = o.layers * l.spacing;
  l.base_half = l.half + 1.2 * l.column_height;
  return l;
}

// the rough base (fixed particles on a square grid) and the column (a jittered lattice of
// D +- 0.1 D spheres inside the walls)
Particles heap_particles(const Material& material, const HeapOptions& o, const HeapLayout& l) {
  const double d = l.d, spacing = l.spacing, half = l.half, base_half = l.base_half;
  Particles particles;
  for (double x = -base_half; x <= base_half; x += d)
    for (double y = -base_half; y <= base_half; y += d) {
      particles.add(Vec3(x, y, 0.5 * d), 0.5 * d, material.density);
      particles.inv_mass.back() = 0.0;
      particles.inv_inertia.back() = 0.0;
    }
  std::mt19937 rng(o.seed);
  std::uniform_real_distribution<double> size(0.9 * d, 1.1 * d);
  double jitter = 0.5 * (spacing - 1.1 * d);
  std::uniform_real_distribution<double> offset(-jitter, jitter);
  for (int k = 0; k < o.layers; ++k)
    for (int j = 0; j < o.columns; ++j)
      for (int i = 0; i < o.columns; ++i) {
        Vec3 x(-half + (i + 0.5) * spacing, -half + (j + 0.5) * spacing, d + (k + 0.5) * spacing);
        particles.add(x + Vec3(offset(rng), offset(rng), offset(rng)), 0.5 * size(rng), material.density);
      }
  return particles;
}

// the ground, and four walls at +-w in x and y when w > 0
std::vector<StaticGeom> ground_and_walls(double w) {
  std::vector<StaticGeom> geoms = {StaticGeom::plane(Vec3::Zero(), Vec3::UnitZ())};
  if (w <= 0.0) return geoms;
  geoms.push_back(StaticGeom::plane(Vec3(-w, 0, 0), Vec3::UnitX()));
  geoms.push_back(StaticGeom::plane(Vec3(w, 0, 0), -Vec3::UnitX()));
  geoms.push_back(StaticGeom::plane(Vec3(0, -w, 0), Vec3::UnitY()));
  geoms.push_back(StaticGeom::plane(Vec3(0, w, 0), -Vec3::UnitY()));
  return geoms;
}

}  // namespace

HeapResult run_heap_test(Device& dev, const Material& material, const HeapOptions& o,
                         Progress* progress) {
  // the base and the column inside its walls
  HeapResult result;
  const HeapLayout l = heap_layout(o);
  const double d = l.d, half = l.half, base_half = l.base_half;
  const Particles particles = heap_particles(material, o, l);
  result.particles = o.columns * o.columns * o.layers;
  Bounds bounds{Vec3(-base_half - d, -base_half - d, 0.0),
                Vec3(base_half + d, base_half + d, l.column_height + 3 * d)};

  // the world, filled without friction for a dense column when asked
  DemSettings settings;
  settings.dt = o.dt;
  settings.iterations = o.iterations;
  Material fill_material = material;
  if (o.dense_fill) {
    fill_material.friction = 0.0;
    fill_material.rolling = 0.0;
  }
  DemWorld world(dev, fill_material, settings, bounds, ground_and_walls(half));
  world.set_particles(particles);

  // fill: settle inside the walls, then measure the bulk density away from walls and surfaces
  SettleOptions fill;
  fill.min_time = 0.5;
  fill.max_time = o.max_fill_time;
  settle(world, fill, progress);
  Particles settled = world.particles();
  double top = 0.0;
  for (size_t i = 0; i < settled.size(); ++i)
    if (settled.inv_mass[i] > 0) top = std::max(top, settled.position[i].z());
  double margin = 2.0 * d;
  Bounds core{Vec3(-half + margin, -half + margin, d + margin), Vec3(half - margin, half - margin, top - margin)};
  result.bulk_density = bulk_density(settled, core, material.density);

  // the gravel's own friction on; the walls retreat slowly, then go
  world.set_material(material);
  if (o.wall_speed > 0.0) {
    int steps = static_cast<int>(std::lround(o.wall_travel / (o.wall_speed * o.dt)));
    for (int k = 1; k <= steps; ++k) {
      world.set_geoms(ground_and_walls(half + k * o.wall_speed * o.dt), GeomChange::Moved);
      world.step();
      if (progress) progress->update(world.time(), "walls retreating");
    }
  }
  const std::vector<StaticGeom> ground = ground_and_walls(0.0);
  world.set_geoms(ground);
  SettleOptions runout;
  runout.min_time = 1.0;
  runout.max_time = o.max_runout_time;
  settle(world, runout, progress);

  // the heap's flank
  result.final_state = world.particles();
  result.geoms = ground;
  result.sim_time = world.time();
  FlankFit fit = measure_flank_angle(result.final_state, d);
  result.repose_angle_deg = fit.angle_deg;
  result.repose_spread_deg = fit.spread_deg;
  result.sectors = fit.sectors;
  result.heap_height = fit.height;
  return result;
}

}  // namespace talus
