#include "terrain/soil_sample.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include "terrain/settle.hpp"

namespace talus {

namespace {
// the longest a sample may take to settle [s]: a 10-20 D column falls and packs within about
// 1 s (free fall over 2 m takes 0.64 s); settle() stops earlier once the grains are at rest
constexpr double kSampleSettleTime = 3.0;
}  // namespace

double least_squares_slope(const std::vector<double>& x, const std::vector<double>& y) {
  const double n = static_cast<double>(x.size());
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (size_t k = 0; k < x.size(); ++k) {
    sx += x[k];
    sy += y[k];
    sxx += x[k] * x[k];
    sxy += x[k] * y[k];
  }
  const double den = n * sxx - sx * sx;
  return den > 0.0 ? (n * sxy - sx * sy) / den : 0.0;
}

Particles emit_box_particles(const Vec3& lo, const Vec3& hi, double diameter, double density,
                             double solid_volume, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> size(0.9 * diameter, 1.1 * diameter);
  const double spacing = lattice_spacing(diameter);
  const double jitter = 0.5 * (spacing - 1.1 * diameter);
  std::uniform_real_distribution<double> offset(-jitter, jitter);
  const int nx = std::max(1, static_cast<int>(std::floor((hi.x() - lo.x()) / spacing)));
  const int ny = std::max(1, static_cast<int>(std::floor((hi.y() - lo.y()) / spacing)));
  // the lattice centred in x and y
  const double x0 = 0.5 * (lo.x() + hi.x()) - 0.5 * (nx - 1) * spacing;
  const double y0 = 0.5 * (lo.y() + hi.y()) - 0.5 * (ny - 1) * spacing;
  Particles particles;
  double solid = 0.0;
  for (double z = lo.z() + 0.5 * spacing; z + 0.5 * spacing <= hi.z() && solid < solid_volume; z += spacing)
    for (int j = 0; j < ny && solid < solid_volume; ++j)
      for (int i = 0; i < nx && solid < solid_volume; ++i) {
        const Vec3 jit(offset(rng), offset(rng), offset(rng));
        const double r = 0.5 * size(rng);
        particles.add(Vec3(x0 + i * spacing, y0 + j * spacing, z) + jit, r, density);
        solid += 4.0 / 3.0 * M_PI * r * r * r;
      }
  // stored column by column: neighbours stay near in memory
  return particles.permuted(spatial_order(particles, spacing));
}

void add_rough_base(Particles& particles, double x0, double x1, double y0, double y1, double diameter,
                    double density) {
  for (double x = x0; x <= x1 + 1e-9; x += diameter)
    for (double y = y0; y <= y1 + 1e-9; y += diameter) {
      particles.add(Vec3(x, y, 0.5 * diameter), 0.5 * diameter, density);
      particles.inv_mass.back() = 0.0;
      particles.inv_inertia.back() = 0.0;
    }
}

std::unique_ptr<DemWorld> dense_sample(Device& dev, const Material& material, double dt, int iterations,
                                       const Bounds& bounds, std::vector<StaticGeom> geoms,
                                       const Particles& particles, Progress* progress) {
  DemSettings settings;
  settings.dt = dt;
  settings.iterations = iterations;
  auto world = std::make_unique<DemWorld>(dev, lab_walls(material), settings, bounds, std::move(geoms));
  world->set_particles(particles);
  // the dense fill ends with material's own friction on (settle_dense)
  settle_dense(*world, lab_walls(material), kSampleSettleTime, progress);
  return world;
}

double settle_dense(DemWorld& world, const Material& material, double max_time, Progress* progress) {
  Material fill = material;
  fill.friction = 0.0;
  fill.rolling = 0.0;
  world.set_material(fill);
  SettleOptions o;
  o.min_time = 0.5;
  o.max_time = max_time;
  const SettleResult r = settle(world, o, progress);
  world.set_material(material);
  return r.sim_time;
}

double mean_surface(const Particles& p, double x0, double x1, double y0, double y1, double d) {
  const int nx = std::max(1, static_cast<int>(std::lround((x1 - x0) / d)));
  const int ny = std::max(1, static_cast<int>(std::lround((y1 - y0) / d)));
  const double cx = (x1 - x0) / nx, cy = (y1 - y0) / ny;
  std::vector<double> top(static_cast<size_t>(nx) * static_cast<size_t>(ny), 0.0);
  for (size_t i = 0; i < p.size(); ++i) {
    if (p.inv_mass[i] <= 0.0) continue;
    const int ix = static_cast<int>(std::floor((p.position[i].x() - x0) / cx));
    const int iy = static_cast<int>(std::floor((p.position[i].y() - y0) / cy));
    if (ix < 0 || ix >= nx || iy < 0 || iy >= ny) continue;
    double& t = top[static_cast<size_t>(iy) * static_cast<size_t>(nx) + static_cast<size_t>(ix)];
    t = std::max(t, p.position[i].z() + p.radius[i]);
  }
  double sum = 0.0;
  for (double t : top) sum += t;
  return sum / static_cast<double>(top.size());
}

double top_surface(const Particles& p, double x0, double x1, double y0, double y1) {
  double top = 0.0;
  for (size_t i = 0; i < p.size(); ++i) {
    if (p.inv_mass[i] <= 0.0) continue;
    const Vec3& x = p.position[i];
    if (x.x() < x0 || x.x() > x1 || x.y() < y0 || x.y() > y1) continue;
    top = std::max(top, x.z() + p.radius[i]);
  }
  return top;
}

}  // namespace talus
