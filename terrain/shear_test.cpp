#include "terrain/shear_test.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "host/error.hpp"
#include "solvers/tool_world.hpp"
#include "terrain/soil_sample.hpp"

namespace talus {

namespace {


// the box in diameters (file comment): length, width, height, lower half, wall thickness
constexpr double kLength = 16.0, kWidth = 8.0, kHeight = 10.0, kLower = 5.0, kWall = 4.0;

}  // namespace

void shear_angles(const std::vector<ShearSample>& series, double window, ShearResult& r) {
  r.peak_friction_deg = r.critical_friction_deg = r.dilatancy_deg = 0.0;
  const size_t n = series.size();
  if (n < 2) return;
  // samples per window (the series is evenly spaced in travel); both measures are taken over
  // whole windows, so the largest of many noisy window means does not pick the noise
  const double spacing = (series.back().travel - series.front().travel) / static_cast<double>(n - 1);
  const size_t w = std::max<size_t>(2, static_cast<size_t>(std::lround(window / spacing)) + 1);
  // mobilised friction: tau / sigma over each window; the peak is the largest
  const double s_end = series.back().travel;
  for (size_t k = 0; k + w <= n; ++k) {
    double tau = 0.0, sigma = 0.0;
    for (size_t j = k; j < k + w; ++j) {
      tau += series[j].shear_stress;
      sigma += series[j].normal_stress;
    }
    if (!(sigma > 0.0)) continue;
    const double phi = std::atan(tau / sigma) * 180.0 / M_PI;
    if (phi > r.peak_friction_deg) {
      r.peak_friction_deg = phi;
      r.peak_travel = series[k + w / 2].travel;
    }
  }
  // critical state: the mean stress ratio over the last quarter of the travel
  double tau = 0.0, sigma = 0.0;
  for (const ShearSample& x : series)
    if (x.travel >= 0.75 * s_end) {
      tau += x.shear_stress;
      sigma += x.normal_stress;
    }
  if (sigma > 0.0) r.critical_friction_deg = std::atan(tau / sigma) * 180.0 / M_PI;
  // dilatancy: the platen's steepest rise, a least-squares slope over each window
  double steepest = 0.0;
  for (size_t k = 0; k + w <= n; ++k) {
    std::vector<double> s, z;
    for (size_t j = k; j < k + w; ++j) {
      s.push_back(series[j].travel);
      z.push_back(series[j].platen_z);
    }
    steepest = std::max(steepest, least_squares_slope(s, z));
  }
  r.dilatancy_deg = std::atan(steepest) * 180.0 / M_PI;
}

ShearResult run_shear_test(Device& dev, const Material& material, const ShearOptions& o, Progress* progress) {
  if (!(o.diameter > 0.0) || !(o.dt > 0.0) || o.iterations < 1 || !(o.normal_stress > 0.0) ||
      !(o.speed > 0.0) || !(o.travel_diameters > 0.0) || o.travel_diameters > kWall)
    throw InputError("shear test options: diameter, dt, iterations, normal stress and speed must be positive, "
                     "travel at most " + std::to_string(static_cast<int>(kWall)) + " diameters");
  ShearResult result;
  const double d = o.diameter;
  const double L = kLength * d, W = kWidth * d, H = kHeight * d, low = kLower * d, T = kWall * d;
  const double travel = o.travel_diameters * d;

  // dense fill inside four plane walls: solid volume of the field's bulk density over the box
  const double solid = (kFieldBulkDensity / material.density) * L * W * H;
  Particles particles = emit_box_particles(Vec3(-0.5 * L, -0.5 * W, 0.0), Vec3(0.5 * L, 0.5 * W, 2.2 * H), d,
                                           material.density, solid, o.seed);
  result.particles = static_cast<int>(particles.size());
  const StaticGeom floor = StaticGeom::plane(Vec3::Zero(), Vec3::UnitZ());
  std::vector<StaticGeom> filling = {floor,
                                     StaticGeom::plane(Vec3(-0.5 * L, 0, 0), Vec3::UnitX()),
                                     StaticGeom::plane(Vec3(0.5 * L, 0, 0), -Vec3::UnitX()),
                                     StaticGeom::plane(Vec3(0, -0.5 * W, 0), Vec3::UnitY()),
                                     StaticGeom::plane(Vec3(0, 0.5 * W, 0), -Vec3::UnitY())};
  const Bounds bounds{Vec3(-0.5 * L - T - d, -0.5 * W - T - d, 0.0), Vec3(0.5 * L + T + travel + d, 0.5 * W + T + d, 2.4 * H)};
  auto sample = dense_sample(dev, material, o.dt, o.iterations, bounds, filling, particles, progress);
  DemWorld& world = *sample;

  // the lower half's walls stay (4 D thick boxes); the upper half's become the ring
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  std::vector<StaticGeom> lower = {floor};
  for (double side : {-1.0, 1.0}) {
    lower.push_back(StaticGeom::box(Vec3(side * 0.5 * (L + T), 0, 0.5 * low), Vec3(0.5 * T, 0.5 * W + T, 0.5 * low), I));
    lower.push_back(StaticGeom::box(Vec3(0, side * 0.5 * (W + T), 0.5 * low), Vec3(0.5 * L + T, 0.5 * T, 0.5 * low), I));
  }
  world.set_geoms(lower);
  const double ring_height = 2.0 * (H - low) + 4.0 * d;
  Tool ring;
  ring.position = Vec3(0, 0, low);
  for (double side : {-1.0, 1.0}) {
    add_box(ring.mesh, Vec3(side * 0.5 * (L + T), 0, 0.5 * ring_height), Vec3(0.5 * T, 0.5 * W + T, 0.5 * ring_height));
    add_box(ring.mesh, Vec3(0, side * 0.5 * (W + T), 0.5 * ring_height), Vec3(0.5 * L, 0.5 * T, 0.5 * ring_height));
  }
  const double wall_friction = o.ring_friction >= 0.0 ? o.ring_friction : material.friction;
  ring.material.friction = wall_friction;
  ring.material.rolling = material.rolling;
  // the platen: a plate 1 D thick, a twentieth of D clear of the ring, free along z only
  const double area = L * W;
  const Vec3 gravity = world.settings().gravity;  // [m/s^2]
  const double g = -gravity.z();
  const double platen_mass = o.normal_stress * area / g;
  Tool platen;
  add_box(platen.mesh, Vec3(0, 0, 0.5 * d), Vec3(0.5 * L - 0.05 * d, 0.5 * W - 0.05 * d, 0.5 * d));
  const Particles settled = world.particles();
  platen.position = Vec3(0, 0, top_surface(settled, -L, L, -W, W) + 0.02 * d);
  platen.mobility(2, 2) = 1.0 / platen_mass;
  platen.external_force = platen_mass * gravity;
  platen.material.friction = wall_friction;
  platen.material.rolling = material.rolling;
  ToolWorld tools(dev, world, {ring, platen});

  // consolidation under the platen until it stops sinking
  const int window_steps = std::max(1, static_cast<int>(std::lround(0.1 * d / (o.speed * o.dt))));
  for (double t = 0.0; t < 3.0; t += o.dt) {
    tools.step();
    if (progress) progress->update(world.time(), "platen consolidating");
    if (t > 0.5 && std::abs(tools.tool(1).velocity.z()) < 1e-3 * o.speed) break;
  }
  const double z0 = tools.tool(1).position.z();
  double solid_volume = 0.0;
  for (double r : settled.radius) solid_volume += 4.0 / 3.0 * M_PI * r * r * r;
  result.bulk_density = material.density * solid_volume / (area * z0);

  // shear: the ring and the platen along x at the test's speed, forces averaged per window
  tools.tool(0).velocity = Vec3(o.speed, 0, 0);
  tools.tool(1).velocity.x() = o.speed;
  const int steps = static_cast<int>(std::lround(travel / (o.speed * o.dt)));
  Vec3 ring_force = Vec3::Zero(), platen_force = Vec3::Zero();
  int in_window = 0;
  for (int k = 1; k <= steps; ++k) {
    tools.step();
    ring_force += tools.load(0).wrench.head<3>();
    platen_force += tools.load(1).wrench.head<3>();
    if (++in_window < window_steps && k < steps) continue;
    ring_force /= in_window;
    platen_force /= in_window;
    // the grains above the shear plane (their weight loads it too)
    const Particles now = world.particles();
    double upper = 0.0;
    for (size_t i = 0; i < now.size(); ++i)
      if (now.position[i].z() > low) upper += now.mass(i);
    ShearSample x;
    x.travel = k * o.speed * o.dt;
    x.shear_stress = -(ring_force.x() + platen_force.x()) / area;
    x.normal_stress = (platen_force.z() + ring_force.z() + upper * g) / area;
    x.platen_z = tools.tool(1).position.z() - z0;
    result.series.push_back(x);
    ring_force.setZero();
    platen_force.setZero();
    in_window = 0;
    if (progress) {
      char note[96];
      std::snprintf(note, sizeof note, "shear %.2f D, tau/sigma %.3f", x.travel / d, x.shear_stress / x.normal_stress);
      progress->update(world.time(), note);
    }
  }
  shear_angles(result.series, 0.5 * d, result);
  result.sim_time = world.time();
  result.final_state = world.particles();
  return result;
}

}  // namespace talus
