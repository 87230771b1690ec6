#include "terrain/cutting_test.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "host/error.hpp"
#include "solvers/tool_world.hpp"
#include "terrain/aggregate.hpp"
#include "terrain/multiscale_terrain.hpp"
#include "terrain/soil_sample.hpp"
#include "vehicle/joints.hpp"
#include "vehicle/multibody.hpp"

namespace talus {

namespace {

constexpr double kDegree = M_PI / 180.0;
// the deepest cut the test makes [m]: the default pile's height (SPEC §2.5), which is all a bucket
// ever cuts; the bed grows with the depth squared, so a typo must not start a huge run
constexpr double kMaxDepth = 2.0;

// the steady part's means (from result.steady_from on): the blade's force, its spread over the
// windows, and the equation's force
void steady_means(CuttingResult& result) {
  double mean = 0.0, square = 0.0, fee = 0.0;
  int n = 0;
  for (const CuttingSample& x : result.series)
    if (x.travel >= result.steady_from) {
      mean += x.force_x;
      square += x.force_x * x.force_x;
      fee += x.fee_force;
      ++n;
    }
  if (n == 0) return;
  mean /= n;
  result.force = mean;
  result.force_spread = std::sqrt(std::max(0.0, square / n - mean * mean));
  result.fee_force = fee / n;
}

}  // namespace

void check_cutting_options(const CuttingOptions& o) {
  if (!(o.diameter > 0.0) || !(o.dt > 0.0) || o.iterations < 1 || !(o.depth > 0.0) || !(o.speed > 0.0) ||
      !(o.travel > 0.0) || !(o.blade_friction >= 0.0) || !(o.internal_friction_deg > 0.0))
    throw InputError("cutting test options: diameter, dt, iterations, depth, speed, travel and friction angle "
                     "must be positive");
  if (!interface_damping_time_valid(o.interface_damping_time))
    throw InputError("cutting test: --interface-damping-time " +
                     std::to_string(o.interface_damping_time) +
                     " s must be 0 (two steps) or lie in [" + std::to_string(kMinDampingTime) +
                     ", " + std::to_string(kMaxDampingTime) + "] s");
  if (o.depth < 0.5 * o.diameter || o.depth > kMaxDepth)
    throw InputError("cutting test: --depth " + std::to_string(o.depth) + " m must lie between half a particle (" +
                     std::to_string(0.5 * o.diameter) + " m) and " + std::to_string(kMaxDepth) +
                     " m (the pile's height); choose a depth in that range");
  fee_force(kFieldBulkDensity, o.depth, 1.0, 90.0, std::atan(o.blade_friction) / kDegree, o.internal_friction_deg);
}

CuttingResult run_cutting_test(Device& dev, const Material& material, const CuttingOptions& o, Progress* progress) {
  check_cutting_options(o);
  CuttingResult result;
  const double d = o.diameter;
  // the bin: as wide as 10 D or 4 depths, long enough for the travel, the last wedge and a margin
  const double width = std::max(10.0 * d, 4.0 * o.depth);
  double beta = 0.0;
  fee_force(kFieldBulkDensity, o.depth, width, 90.0, std::atan(o.blade_friction) / kDegree, o.internal_friction_deg, 0.0, &beta);
  const double wedge = o.depth / std::tan(beta * kDegree);
  const double length = o.travel + 2.0 * wedge + 6.0 * d;
  const double bed = o.depth + std::max(3.0 * d, 0.3);  // bed height over the rough base [m]
  result.width = width;

  // rough base, then the bed filled densely to the field's bulk density
  Particles particles;
  add_rough_base(particles, 0.5 * d, length - 0.5 * d, -0.5 * width + 0.5 * d, 0.5 * width - 0.5 * d, d,
                 material.density);
  const double solid = (kFieldBulkDensity / material.density) * length * width * bed;
  const Particles fill = emit_box_particles(Vec3(0.0, -0.5 * width, d), Vec3(length, 0.5 * width, d + 2.2 * bed), d,
                                            material.density, solid, o.seed);
  for (size_t i = 0; i < fill.size(); ++i) particles.add(fill.position[i], fill.radius[i], material.density);
  result.particles = static_cast<int>(fill.size());
  const StaticGeom floor = StaticGeom::plane(Vec3::Zero(), Vec3::UnitZ());
  std::vector<StaticGeom> bin = {floor,
                                 StaticGeom::plane(Vec3(length, 0, 0), -Vec3::UnitX()),
                                 StaticGeom::plane(Vec3(0, -0.5 * width, 0), Vec3::UnitY()),
                                 StaticGeom::plane(Vec3(0, 0.5 * width, 0), -Vec3::UnitY())};
  std::vector<StaticGeom> filling = bin;
  filling.push_back(StaticGeom::plane(Vec3::Zero(), Vec3::UnitX()));
  const Bounds bounds{Vec3(-2.0 * d, -0.5 * width - d, 0.0), Vec3(length + d, 0.5 * width + d, d + 2.4 * bed + 4.0 * d)};
  auto sample = dense_sample(dev, material, o.dt, o.iterations, bounds, filling, particles, progress);
  DemWorld& world = *sample;
  const Particles settled = world.particles();
  const double surface = mean_surface(settled, 2.0 * d, length - 2.0 * d, -0.5 * width, 0.5 * width, d);
  double solid_volume = 0.0;
  for (size_t i = 0; i < settled.size(); ++i)
    if (settled.inv_mass[i] > 0.0) solid_volume += 4.0 / 3.0 * M_PI * std::pow(settled.radius[i], 3);
  result.bed_density = material.density * solid_volume / (length * width * (surface - d));
  const double blade_bottom = surface - o.depth;
  const double tool_friction_deg = std::atan(o.blade_friction) / kDegree;
  if (blade_bottom < 2.0 * d) throw InputError("cutting test: depth " + std::to_string(o.depth) + " m is deeper than the bed");

  // the bed's face below the cut stays held; above it the blade takes the front wall's place
  const double blade_thickness = 0.5 * d, blade_height = o.depth + 3.0 * d;
  bin.push_back(StaticGeom::box(Vec3(-d, 0, 0.5 * blade_bottom), Vec3(d, 0.5 * width + d, 0.5 * blade_bottom),
                                Eigen::Matrix3d::Identity()));
  world.set_geoms(bin);
  Tool blade;
  add_box(blade.mesh, Vec3(-0.5 * blade_thickness, 0, 0.5 * blade_height),
          Vec3(0.5 * blade_thickness, 0.5 * width - 0.1 * d, 0.5 * blade_height));
  blade.position = Vec3(-0.01 * d, 0, blade_bottom);
  blade.velocity = Vec3(o.speed, 0, 0);
  blade.material.friction = o.blade_friction;
  blade.material.rolling = material.rolling;
  ToolWorld tools(dev, world, {blade});

  // push: force means per quarter D of travel
  const int window_steps = std::max(1, static_cast<int>(std::lround(0.25 * d / (o.speed * o.dt))));
  const int steps = static_cast<int>(std::lround(o.travel / (o.speed * o.dt)));
  Vec3 sum = Vec3::Zero();
  int in_window = 0;
  for (int k = 1; k <= steps; ++k) {
    tools.step();
    sum += tools.load(0).wrench.head<3>();
    if (++in_window < window_steps && k < steps) continue;
    CuttingSample x;
    x.travel = k * o.speed * o.dt;
    x.force_x = -sum.x() / in_window;
    x.force_z = sum.z() / in_window;
    // the heap over the wedge in front of the blade, and the equation under it
    const double front = tools.tool(0).position.x();
    x.surcharge = mean_surface(world.particles(), front, front + wedge, -0.5 * width, 0.5 * width, d) - surface;
    x.fee_force = fee_force(result.bed_density, o.depth, width, 90.0, tool_friction_deg, o.internal_friction_deg,
                            x.surcharge);
    result.series.push_back(x);
    sum.setZero();
    in_window = 0;
    if (progress) {
      char note[96];
      std::snprintf(note, sizeof note, "blade at %.2f m, %.1f kN", x.travel, 1e-3 * x.force_x);
      progress->update(world.time(), note);
    }
  }

  // the steady part: after the first wedge has formed
  result.steady_from = std::min(wedge, 0.5 * o.travel);
  steady_means(result);
  result.fee_force_level = fee_force(result.bed_density, o.depth, width, 90.0, tool_friction_deg,
                                     o.internal_friction_deg, 0.0, &result.fee_failure_angle_deg);
  result.sim_time = world.time();
  result.final_state = world.particles();
  return result;
}

CuttingResult run_multiscale_cutting_test(Device& dev, const FidelityPreset& level,
                                          const CuttingOptions& options, const BulkSoil& soil,
                                          Progress* progress) {
  if (!find_multiscale_preset(level.name))
    throw InputError("cutting test: level '" + level.name +
                     "' is not a type-G level (G50, G100, G200, G400)");
  CuttingOptions o = options;
  o.diameter = level.diameter;
  o.dt = level.dt;
  o.iterations = level.iterations;
  check_cutting_options(o);
  CuttingResult result;
  const double h = level.diameter;
  const double tool_friction_deg = std::atan(o.blade_friction) / kDegree;
  const double phi = soil.effective_friction_deg();
  // the bed: a level block of voxels `depth` + 2 cells high, as wide as the blade (4 depths, at
  // least 10 cells: whole cells), long enough for the travel, two wedges and a margin
  double beta = 0.0;
  fee_force(kFieldBulkDensity, o.depth, 1.0, 90.0, tool_friction_deg, phi, 0.0, &beta);
  const double wedge = o.depth / std::tan(beta * kDegree);
  const double width = h * std::ceil(std::max(10.0 * h, 4.0 * o.depth) / h);
  const double bed = o.depth + 2.0 * h;
  PileProfile profile;
  profile.name = "level bed";
  profile.width = width;
  profile.points = {Vec3(0.0, 0.0, bed), Vec3(o.travel + 2.0 * wedge + 1.0, 0.0, bed)};
  profile.rear_wall_x = profile.points.back().x();
  result.width = width;
  result.bed_density = kFieldBulkDensity;

  // the blade: a plate 5 cm thick behind its face, from its tip (the mesh origin) up to 3 cells
  // above the bed, as wide as the bed; its cutting plane stands vertical (tip straight under the
  // top)
  const double thickness = 0.05, tall = bed - (bed - o.depth) + 3.0 * h;
  vehicle::BucketMesh mesh;
  add_box(mesh, Vec3(-0.5 * thickness, 0.0, 0.5 * tall),
          Vec3(0.5 * thickness, 0.5 * width - 1e-3, 0.5 * tall));
  mesh.profile = {Vec3::Zero(), Vec3(0.0, 0.0, tall)};
  mesh.inner_width = width;
  const Vec3 tip0(0.5 * h, 0.0, bed - o.depth);
  const Vec3 com_offset(-0.5 * thickness, 0.0, 0.5 * tall);  // the blade body's centre from its tip

  // the machine: the blade on a rail along x, its motor at the test's speed
  vehicle::MultibodySystem system;
  vehicle::RigidBody plate;
  plate.name = "blade";
  plate.mass = 500.0;  // [kg]: a blade's order; the motor holds its speed whatever the mass
  plate.inertia = Eigen::Matrix3d::Identity() * 100.0;
  plate.position = tip0 + com_offset;
  plate.velocity = Vec3(o.speed, 0.0, 0.0);
  const int blade = system.add_body(plate);
  auto& rail = system.add_constraint(std::make_unique<vehicle::PrismaticJoint>(
      system.bodies(), vehicle::kWorld, blade, plate.position, Vec3::UnitX()));
  rail.name = "rail";
  rail.motor.enabled = true;
  rail.motor.target_speed = o.speed;
  AggregateParameters interfaces;
  interfaces.damping_time = o.interface_damping_time;
  AggregateCoupling coupling(system, blade, soil, interfaces);

  KinematicBucket state;
  state.position = tip0;
  state.velocity = Vec3(o.speed, 0.0, 0.0);
  MultiscaleOptions terrain_options;
  terrain_options.soil = soil;
  terrain_options.bucket_material.friction = o.blade_friction;
  terrain_options.seed = o.seed;
  MultiscaleTerrain terrain(dev, profile, level, mesh, state, terrain_options);

  // push: force means per quarter of a wedge's length of travel
  const int window_steps =
      std::max(1, static_cast<int>(std::lround(0.25 * wedge / (o.speed * o.dt))));
  const int steps = static_cast<int>(std::lround(o.travel / (o.speed * o.dt)));
  double force_x = 0.0, force_z = 0.0, load = 0.0, edge = 0.0, edge_steady = 0.0;
  int edge_windows = 0;
  int in_window = 0, most = 0;
  for (int k = 1; k <= steps; ++k) {
    // the aggregate from the last terrain step, the machine's step, then the terrain's
    coupling.update(terrain, mesh, state, o.dt);
    system.step(o.dt);
    coupling.after_step(o.dt);
    state.velocity = system.body(blade).velocity;
    terrain.step(state);
    state.position = system.body(blade).position - com_offset;
    force_x += rail.actuator_force() - coupling.edge_force();
    edge += coupling.edge_force();
    force_z += coupling.force_on_bucket().z();
    load += coupling.aggregate().mass;
    most = std::max(most, static_cast<int>(terrain.particle_masses().size()));
    if (++in_window < window_steps && k < steps) continue;
    CuttingSample x;
    x.travel = k * o.speed * o.dt;
    x.force_x = force_x / in_window;
    x.force_z = force_z / in_window;
    // the load the aggregate carried, as the wedge and a surcharge q over its top (length d cot
    // beta)
    const double mass = load / in_window;
    x.surcharge =
        mass / (kFieldBulkDensity * width * o.depth / std::tan(beta * kDegree)) - 0.5 * o.depth;
    x.fee_force =
        fee_force(kFieldBulkDensity, o.depth, width, 90.0, tool_friction_deg, phi, x.surcharge);
    result.series.push_back(x);
    if (x.travel >= std::min(wedge, 0.5 * o.travel)) {
      edge_steady += edge / in_window;
      ++edge_windows;
    }
    force_x = force_z = load = edge = 0.0;
    in_window = 0;
    if (progress) {
      char note[96];
      std::snprintf(note, sizeof note, "blade at %.2f m, %.1f kN", x.travel, 1e-3 * x.force_x);
      progress->update(terrain.time(), note);
    }
  }

  // the steady part: after the first wedge has formed
  result.steady_from = std::min(wedge, 0.5 * o.travel);
  steady_means(result);
  result.fee_force_level = fee_force(kFieldBulkDensity, o.depth, width, 90.0, tool_friction_deg,
                                     phi, 0.0, &result.fee_failure_angle_deg);
  result.particles = most;
  result.edge_force = edge_windows > 0 ? edge_steady / edge_windows : 0.0;
  result.sim_time = terrain.time();
  result.final_state = terrain.particles();
  return result;
}

}  // namespace talus
