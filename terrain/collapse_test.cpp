#include "terrain/collapse_test.hpp"

#include <algorithm>
#include <cmath>

#include "host/error.hpp"
#include "terrain/settle.hpp"
#include "terrain/soil_sample.hpp"

namespace talus {

namespace {
// the channel in diameters (file comment)
constexpr double kColumnLength = 12.0, kWidth = 6.0;
}  // namespace

double runout_front(const Particles& p, double back, double gap) {
  std::vector<std::pair<double, double>> spans;  // (near side, far side) along x
  for (size_t i = 0; i < p.size(); ++i)
    if (p.inv_mass[i] > 0.0) spans.emplace_back(p.position[i].x() - p.radius[i], p.position[i].x() + p.radius[i]);
  std::sort(spans.begin(), spans.end());
  double front = back;
  for (const auto& [near, far] : spans) {
    if (near > front + gap) break;
    front = std::max(front, far);
  }
  return front;
}

CollapseResult run_collapse_test(Device& dev, const Material& material, const CollapseOptions& o,
                                 Progress* progress) {
  if (!(o.diameter > 0.0) || !(o.dt > 0.0) || o.iterations < 1 || !(o.aspect > 0.0) || o.aspect > 3.0 ||
      !(o.max_time > 0.0))
    throw InputError("collapse test options: diameter, dt, iterations and time must be positive, aspect in (0, 3] (the laboratory law's range)");
  CollapseResult result;
  const double d = o.diameter;
  const double L0 = kColumnLength * d, W = kWidth * d, H0 = o.aspect * L0;
  // the channel reaches past the run-out of lambda = 1.8 with a margin
  const double channel = L0 * (2.0 + 1.8 * o.aspect) + 4.0 * d;

  // rough base under the whole channel, the column on it (its bottom at one D)
  Particles particles;
  add_rough_base(particles, -0.5 * d, channel, -0.5 * W + 0.5 * d, 0.5 * W - 0.5 * d, d, material.density);
  const double solid = (kFieldBulkDensity / material.density) * L0 * W * H0;
  const Particles column = emit_box_particles(Vec3(0.0, -0.5 * W, d), Vec3(L0, 0.5 * W, d + 2.2 * H0), d,
                                              material.density, solid, o.seed);
  for (size_t i = 0; i < column.size(); ++i) particles.add(column.position[i], column.radius[i], material.density);
  result.particles = static_cast<int>(column.size());

  const std::vector<StaticGeom> channel_walls = {StaticGeom::plane(Vec3::Zero(), Vec3::UnitZ()),
                                                 StaticGeom::plane(Vec3(0, 0, 0), Vec3::UnitX()),
                                                 StaticGeom::plane(Vec3(0, -0.5 * W, 0), Vec3::UnitY()),
                                                 StaticGeom::plane(Vec3(0, 0.5 * W, 0), -Vec3::UnitY())};
  std::vector<StaticGeom> gated = channel_walls;
  gated.push_back(StaticGeom::plane(Vec3(L0, 0, 0), -Vec3::UnitX()));
  const Bounds bounds{Vec3(-d, -0.5 * W - d, 0.0), Vec3(channel + d, 0.5 * W + d, d + 2.4 * H0)};
  auto sample = dense_sample(dev, material, o.dt, o.iterations, bounds, gated, particles, progress);
  DemWorld& world = *sample;
  Particles settled = world.particles();
  result.initial_length = L0;
  result.initial_height = top_surface(settled, 0.0, L0, -W, W) - d;
  result.aspect_ratio = result.initial_height / L0;

  // the gate goes at once; the column spreads until it comes to rest
  world.set_geoms(channel_walls);
  SettleOptions runout;
  runout.min_time = 1.0;
  runout.max_time = o.max_time;
  settle(world, runout, progress);
  result.final_state = world.particles();
  result.final_length = runout_front(result.final_state, 0.0, d);
  result.final_height = top_surface(result.final_state, 0.0, channel, -W, W) - d;
  result.runout_ratio = (result.final_length - L0) / L0;
  result.sim_time = world.time();
  return result;
}

}  // namespace talus
