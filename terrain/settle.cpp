#include "terrain/settle.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace talus {

double rms_speed(const Particles& p) {
  double sum = 0.0;
  int n = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    if (p.inv_mass[i] <= 0.0) continue;
    sum += p.velocity[i].squaredNorm();
    ++n;
  }
  return n > 0 ? std::sqrt(sum / n) : 0.0;
}

SettleResult settle(DemWorld& world, const SettleOptions& o, Progress* progress) {
  SettleResult r;
  double t0 = world.time();
  double dt = world.settings().dt;
  int check_every = std::max(1, static_cast<int>(std::lround(o.check_interval / dt)));
  while (world.time() - t0 < o.max_time - 0.5 * dt) {
    world.step();
    ++r.steps;
    if (r.steps % check_every != 0) continue;
    r.rms_speed = rms_speed(world.particles());
    double elapsed = world.time() - t0;
    if (progress) {
      char note[96];
      std::snprintf(note, sizeof note, "t=%.2f s, rms speed %.3f m/s, %d contacts", elapsed,
                    r.rms_speed, world.stats().contacts);
      progress->update(world.time(), note);
    }
    if (elapsed >= o.min_time && r.rms_speed < o.rest_speed) {
      r.at_rest = true;
      break;
    }
  }
  r.sim_time = world.time() - t0;
  r.rms_speed = rms_speed(world.particles());
  r.at_rest = r.rms_speed < o.rest_speed;
  return r;
}

double max_overlap(const Particles& p, const std::vector<StaticGeom>& geoms) {
  // brute force over a sorted sweep in x: fine for the sizes where it is used (outputs, tests)
  size_t n = p.size();
  std::vector<size_t> idx(n);
  for (size_t i = 0; i < n; ++i) idx[i] = i;
  std::sort(idx.begin(), idx.end(), [&](size_t a, size_t b) { return p.position[a].x() < p.position[b].x(); });
  double rmax = 0.0;
  for (double r : p.radius) rmax = std::max(rmax, r);
  double worst = 0.0;
  for (size_t u = 0; u < n; ++u) {
    size_t i = idx[u];
    for (size_t w = u + 1; w < n; ++w) {
      size_t j = idx[w];
      if (p.position[j].x() - p.position[i].x() > 2 * rmax) break;
      double overlap = p.radius[i] + p.radius[j] - (p.position[j] - p.position[i]).norm();
      worst = std::max(worst, overlap);
    }
    // static geometry: planes only (boxes are not used where this is called)
    for (auto& g : geoms) {
      if (g.type != StaticGeom::Type::Plane) continue;
      double d = (p.position[i] - g.centre).dot(g.axes.col(0));
      worst = std::max(worst, p.radius[i] - d);
    }
  }
  return worst;
}

}  // namespace talus
