#include "digging/digging.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>

#include "host/error.hpp"
#include "host/stage_times.hpp"
#include "terrain/bucket_fill.hpp"
#include "vehicle/data_file.hpp"

namespace talus {

namespace {
// the broad-phase region beyond the pile: gravel carried back this far in front of the toe [m]
// (the cycles reverse a few metres), and lifted this high [m] (full lift puts the bucket's top
// near 5 m, vehicle/data: hinge pin 3.9-4.0 m at full lift)
constexpr double kCarryBack = 6.0;
constexpr double kCarryHeight = 5.5;
// the machine settles onto its tyres before the clock starts, with no gravel in reach [s]
// (tyre vibrations die out in a few tenths of a second, data/machines damping_time)
constexpr double kVehicleSettle = 1.0;
}  // namespace

PileProfile scenario_pile_profile(const vehicle::Scenario& scenario) {
  const std::string path = vehicle::find_data_file(scenario.pile_profile, "piles");
  if (path.empty())
    throw InputError(scenario.path + ": field 'pile_profile' names '" + scenario.pile_profile +
                     "', which is neither a file nor data/piles/" + scenario.pile_profile + ".json; fix the name");
  PileProfile placed = load_pile_profile(path);
  for (Vec3& p : placed.points) p.x() += scenario.pile_toe_x;
  placed.rear_wall_x += scenario.pile_toe_x;
  return placed;
}

PileBuild build_scenario_pile(Device& dev, const vehicle::Scenario& scenario, const PileProfile& placed,
                              const FidelityPreset& preset, const DiggingOptions& options, Progress* progress) {
  if (!scenario.pile) throw InputError(scenario.path + ": scenario '" + scenario.name + "' has no pile (\"pile\": false)");
  // a type-G level has no particle pile: its terrain is built from the profile by the simulation
  if (is_multiscale(preset)) {
    PileBuild pile;
    pile.geoms = pile_container(placed);
    pile.bounds = pile_bounds(placed, preset.diameter);
    pile.bounds.lo.x() = std::min(pile.bounds.lo.x(), scenario.pile_toe_x - kCarryBack);
    pile.bounds.hi.z() = std::max(pile.bounds.hi.z(), kCarryHeight);
    pile.at_rest = pile.fill_at_rest = true;
    pile.bulk_density = kFieldBulkDensity;
    return pile;
  }
  PileBuild pile = build_pile_cached(dev, placed, preset, options.soil, options.pile,
                                     options.pile_cache, progress);
  pile.bounds.lo.x() = std::min(pile.bounds.lo.x(), scenario.pile_toe_x - kCarryBack);
  pile.bounds.hi.z() = std::max(pile.bounds.hi.z(), kCarryHeight);
  return pile;
}

PileScan scan_scenario_pile(const PileBuild& pile, const PileProfile& placed,
                            const FidelityPreset& preset) {
  if (is_multiscale(preset))
    return scan_surface(
        VoxelTerrain::from_profile(placed, VoxelTerrainOptions{preset.diameter}).surface(), placed);
  return scan_pile(pile.particles, placed, preset.diameter);
}

std::vector<vehicle::RigidPlane> container_walls(const std::vector<StaticGeom>& geoms) {
  std::vector<vehicle::RigidPlane> walls;
  for (const StaticGeom& g : geoms) {
    if (g.type != StaticGeom::Type::Plane) continue;
    const Vec3 n = g.axes.col(0).normalized();
    // a wall stands upright: its normal lies (nearly) in the horizontal plane; the ground does not
    if (std::abs(n.z()) > 0.5) continue;
    walls.push_back({n, n.dot(g.centre)});
  }
  return walls;
}

void check_bucket_sweep(BucketSweep sweep, const FidelityPreset& level, const std::string& field) {
  if (sweep != BucketSweep::Serial && is_multiscale(level))
    throw InputError(field + " " + bucket_sweep_name(sweep) + " at " + level.name +
                     ": a type-G bucket meets the soil through its aggregate, with no chain of "
                     "particle-bucket rows to colour; give a D level, or leave it serial");
}

double applied_sweep_tolerance(double tolerance, const FidelityPreset& level) {
  return is_multiscale(level) ? 0.0 : tolerance;
}

void check_sweep_tolerance(double tolerance, const FidelityPreset& level,
                           const std::string& field) {
  if (is_multiscale(level) && tolerance != 0.0 && tolerance != kDigSweepTolerance)
    throw InputError(field + " " + message_number(tolerance) + " m/s at " + level.name +
                     ": a type-G zone runs its level's " + std::to_string(level.iterations) +
                     " sweeps a step in one launch, with no residual to stop at; give a D level, "
                     "or leave it at its default (which type G does not apply) or 0");
}

DiggingSimulation::DiggingSimulation(Device& dev, const vehicle::Scenario& scenario, const FidelityPreset& preset,
                                     const PileBuild& pile, const DiggingOptions& options,
                                     vehicle::EffectSet* effects)
    : dev_(dev), scenario_(scenario), preset_(preset), log_(100.0), effects_(effects ? *effects : no_effects_) {
  if (!scenario.pile) throw InputError(scenario.path + ": scenario '" + scenario.name + "' has no pile (\"pile\": false)");
  // the type-G options, before the machine is built and settled
  if (!is_multiscale(preset) && !options.content_inertia)
    throw InputError("content_inertia off at " + preset.name +
                     ": at a type-D level the particles in the bucket are the content itself, "
                     "inertia and all; its weight alone is a type-G study (a G level), or leave "
                     "content_inertia on");
  if (!(options.edge_resistance >= 0.0 && options.edge_resistance <= kMaxEdgeResistance))
    throw InputError("edge_resistance " + std::to_string(options.edge_resistance) +
                     ": the factor on the cutting edge's penetration resistance must lie in [0, " +
                     std::to_string(kMaxEdgeResistance) + "] (1: the law as it stands)");
  if (!is_multiscale(preset) && options.edge_resistance != 1.0)
    throw InputError("edge_resistance " + std::to_string(options.edge_resistance) + " at " +
                     preset.name +
                     ": only the type-G levels model the cutting edge's penetration resistance; "
                     "at a type-D level the particles resist the edge themselves: leave it at 1");
  if (!interface_damping_time_valid(options.interface_damping_time))
    throw InputError("interface_damping_time " + std::to_string(options.interface_damping_time) +
                     " s: the aggregate's interfaces' damping time must lie in [" +
                     std::to_string(kMinDampingTime) + ", " + std::to_string(kMaxDampingTime) +
                     "] s, or be 0 for two of the level's steps");
  if (!is_multiscale(preset) && options.interface_damping_time != 0.0)
    throw InputError("interface_damping_time " + std::to_string(options.interface_damping_time) +
                     " s at " + preset.name +
                     ": only the type-G levels have an aggregate with interfaces; at a type-D "
                     "level leave it at 0 (the particle contacts' own: --damping-time)");
  if (!is_multiscale(preset) && !options.bucket_support)
    throw InputError("bucket_support off at " + preset.name +
                     ": at a type-D level the pile's particles hold the bucket up themselves; the "
                     "soil giving way under the bucket is a type-G study (a G level), or leave "
                     "bucket_support on");
  if (!is_multiscale(preset) && options.excavation_reach != 0.0)
    throw InputError("excavation_reach " + std::to_string(options.excavation_reach) + " m at " +
                     preset.name +
                     ": only the type-G levels turn a zone of voxels into particles; use a G "
                     "level or leave it at 0");
  if (!is_multiscale(preset) && options.merge_speed != kMergeSpeed)
    throw InputError("merge_speed " + message_number(options.merge_speed) + " m/s at " +
                     preset.name +
                     ": only the type-G levels merge particles back into voxels; use a G level "
                     "or leave it at " +
                     message_number(kMergeSpeed) + " m/s");
  if (!is_multiscale(preset) && !options.rest_in_bucket)
    throw InputError("rest_in_bucket off at " + preset.name +
                     ": only the type-G levels' kinematic bucket carries its resting load as "
                     "fixed particles (a type-D bucket's load is its particles' own); keeping "
                     "that load in the DEM is a type-G study (a G level), or leave rest_in_bucket "
                     "on");
  if (!is_multiscale(preset) && !options.failure_plane_floor)
    throw InputError("failure_plane_floor off at " + preset.name +
                     ": only the type-G levels have a zone of excavated voxel columns to stand "
                     "on; the columns' staircase is a type-G study (a G level), or leave "
                     "failure_plane_floor on");
  if (!is_multiscale(preset) && (options.avalanche.repose_deg != AvalancheOptions{}.repose_deg ||
                                 options.avalanche.rate != AvalancheOptions{}.rate))
    throw InputError("avalanche (repose " + std::to_string(options.avalanche.repose_deg) +
                     " deg, rate " + std::to_string(options.avalanche.rate) + " /s) at " +
                     preset.name +
                     ": only the type-G levels have a voxel surface that avalanches; at a type-D "
                     "level the particles make the slope themselves (use a G level or leave the "
                     "avalanche at its defaults)");
  check_bucket_sweep(options.coupling.bucket_sweep, preset, "bucket_sweep");
  check_sweep_tolerance(options.sweep_tolerance, preset, "sweep_tolerance");
  if (!is_multiscale(preset) && options.seed_diameter != 1.0)
    throw InputError("seed_diameter " + std::to_string(options.seed_diameter) + " at " +
                     preset.name +
                     ": only the type-G levels' zone particles grow from seeds; use a G level or "
                     "leave it at 1");
  loader_ =
      std::make_unique<vehicle::WheelLoader>(vehicle::machine_file(scenario), scenario.payload);
  // the pile's container walls stop the bucket as they stop the gravel (the ground has its own
  // contact): without them a cycle that drives on after its fill takes the bucket through the
  // rear wall, which holds the load back (docs/multiscale.md)
  loader_->add_bucket_walls(container_walls(pile.geoms));

  // the machine settles on its tyres first, controls at rest
  const double h = preset.dt;
  loader_->set_drive_speed(0.0);
  loader_->set_lift_speed(0.0);
  loader_->set_tilt_speed(0.0);
  for (int k = 0; k < static_cast<int>(std::lround(kVehicleSettle / h)); ++k) loader_->step(h);

  steps_total_ = static_cast<int>(std::lround(scenario.duration / h));
  Material soil = options.soil;
  soil.cohesion = effects_.soil({options.soil.cohesion}).cohesion;
  // type G: the voxel terrain of the scenario's profile, its zone's particles and the aggregate
  // solved with the machine (terrain/multiscale_terrain, terrain/aggregate)
  if (is_multiscale(preset)) {
    MultiscaleOptions terrain;
    terrain.particle_material = soil;
    terrain.bucket_material = options.coupling.material;
    terrain.max_particle_speed = options.max_particle_speed;
    terrain.one_group_rows = options.one_group_rows;
    terrain.serial_lanes = options.serial_lanes;
    terrain.sweep_parts = options.sweep_parts;
    terrain.pair_reach = options.pair_reach;
    terrain.relaxation = options.relaxation;
    terrain.seed_diameter = options.seed_diameter;
    terrain.excavation_reach = options.excavation_reach;
    terrain.merge_speed = options.merge_speed;
    terrain.rest_in_bucket = options.rest_in_bucket;
    terrain.failure_plane_floor = options.failure_plane_floor;
    terrain.avalanche = options.avalanche;
    terrain.seed = options.pile.seed;
    terrain.pressed_depth = options.bucket_support ? kPressedDepth : 0.0;
    terrain_ = std::make_unique<MultiscaleTerrain>(dev, scenario_pile_profile(scenario), preset,
                                                   loader_->bucket_mesh(),
                                                   kinematic_bucket(*loader_), terrain);
    AggregateParameters aggregate;
    aggregate.penetration_factor = options.edge_resistance;
    aggregate.damping_time = options.interface_damping_time;
    aggregate_ = std::make_unique<AggregateCoupling>(loader_->system(), loader_->bucket_body(),
                                                     terrain.soil, aggregate);
    if (options.content_inertia)
      payload_ = std::make_unique<BucketPayload>(loader_->system(), loader_->bucket_body());
    if (options.bucket_support)
      support_ = std::make_unique<BucketSupport>(loader_->system(), loader_->bucket_body(),
                                                 loader_->bucket_mesh(), terrain.soil);
    sensors_ = vehicle::start_with_effects(*loader_, effects_, log_, scenario_);
    return;
  }
  // the particles: the level's timestep and sweeps, speculative contacts for thrown gravel
  DemSettings settings;
  settings.dt = h;
  settings.iterations = preset.iterations;
  settings.tolerance = options.sweep_tolerance;
  settings.sweep = options.sweep;
  settings.one_group_rows = options.one_group_rows;
  settings.serial_lanes = options.serial_lanes;
  settings.sweep_parts = options.sweep_parts;
  settings.pair_reach = options.pair_reach;
  settings.relaxation = options.relaxation;
  settings.max_speed = options.max_particle_speed;
  // the soil: the options' gravel, and what the effects make of it (soil_cohesion)
  dem_ = std::make_unique<DemWorld>(dev, soil, settings, pile.bounds, pile.geoms);
  dem_->set_particles(pile.particles);
  split_ = std::make_unique<SplitSolver>(dev, *dem_, *loader_, options.coupling);
  // the effects start with the settled machine at t = 0
  sensors_ = vehicle::start_with_effects(*loader_, effects_, log_, scenario_);
}

double DiggingSimulation::run(const std::function<void(int)>& after_step) {
  double wall = 0.0;
  while (!done()) {
    // one timed step, then the caller's work
    const auto start = std::chrono::steady_clock::now();
    step();
    wall += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (after_step) after_step(steps_done_);
  }
  return wall;
}

void DiggingSimulation::step() {
  // the feedforward targets at the start of the step
  step(scenario_.drive(time_), scenario_.lift(time_), scenario_.tilt(time_));
}

void DiggingSimulation::step(double drive, double lift, double tilt) {
  // the targets, one coupled step through the effects, the sensors after it (the clock counts
  // steps, so every run samples the same instants)
  // (a profiled run charges what the coupled step's own stages do not cover to "other":
  // controls, effects, sensors)
  StageScope stage(dev_, "other");
  const double h = preset_.dt;
  const double t_end = (steps_done_ + 1) * h;
  if (terrain_) {
    sensors_ = vehicle::step_with_effects(
        *loader_, effects_, time_, h, t_end, {drive, lift, tilt}, [&] { multiscale_step(); },
        &log_);
    ++steps_done_;
    time_ = t_end;
    return;
  }
  sensors_ = vehicle::step_with_effects(
      *loader_, effects_, time_, h, t_end, {drive, lift, tilt}, [&] { split_->step(); }, &log_);
  ++steps_done_;
  time_ = t_end;
  // coupling bookkeeping, and the soil's force on the bucket
  const CouplingStats& s = split_->stats();
  soil_log_.push_back({time_, s.wrench.head<3>(), s.wrench.tail<3>(), s.faces});
  sweep_sum_ += s.sweeps;
  if (s.bucket_contacts > 0) {
    ++contact_steps_;
    pass_sum_ += s.passes;
    max_passes_ = std::max(max_passes_, s.passes);
    max_residual_ = std::max(max_residual_, s.residual);
    if (s.residual >= split_->settings().tolerance) ++capped_steps_;
  }
  max_overlap_rel_ = std::max(max_overlap_rel_, s.max_overlap_rel);
  if (s.particle_residual >= 0.0) residuals_.push_back(s.particle_residual);
}

double DiggingSimulation::loaded_mass() const {
  return talus::loaded_mass(particles(), loader_->bucket_mesh(), bucket_pose(*loader_));
}

Particles DiggingSimulation::particles() const {
  return terrain_ ? terrain_->particles() : dem_->particles();
}

size_t DiggingSimulation::particle_count() const {
  return terrain_ ? terrain_->particle_masses().size() : dem_->size();
}

const DemWorld& DiggingSimulation::dem() const {
  if (!dem_)
    throw Error(
        "digging: a type-G run has no particle world of its own (terrain() holds its particles)");
  return *dem_;
}

const SplitSolver& DiggingSimulation::split() const {
  if (!split_)
    throw Error(
        "digging: a type-G run has no split solver (its soil reaches the machine through the "
        "aggregate)");
  return *split_;
}

const MultiscaleTerrain& DiggingSimulation::terrain() const {
  if (!terrain_) throw Error("digging: a type-D run has no multiscale terrain");
  return *terrain_;
}

const AggregateCoupling& DiggingSimulation::aggregate() const {
  if (!aggregate_) throw Error("digging: a type-D run has no aggregate");
  return *aggregate_;
}

KinematicBucket kinematic_bucket(const vehicle::WheelLoader& loader) {
  const vehicle::RigidBody& body = loader.bodies().at(loader.bucket_body());
  KinematicBucket b;
  b.position = loader.bucket_tip_world();
  b.orientation = body.orientation;
  b.velocity = body.point_velocity(b.position);
  b.omega = body.angular_velocity;
  return b;
}

void DiggingSimulation::multiscale_step() {
  const double h = preset_.dt;
  // the aggregate from the terrain's last step, on the bucket where it stands (a profiled run's
  // stages: the aggregate, the machine's direct solve, then the terrain's own)
  std::optional<StageScope> stage(std::in_place, dev_, "aggregate");
  // (the bucket where the step starts: what follows before the machine's step moves other bodies)
  const KinematicBucket start = kinematic_bucket(*loader_);
  aggregate_->update(*terrain_, loader_->bucket_mesh(), start, h);
  // the resting soil under the bucket's bottom
  if (support_) support_->update(terrain_->voxels(), start);
  // the soil in the bucket and outside the zone: a body welded to the bucket that carries its
  // weight and its inertia (content_inertia, the default), or its weight alone on the bucket (a
  // study; docs/multiscale.md)
  const Particles& p = terrain_->particles();
  const std::vector<double>& mass = terrain_->particle_masses();
  const ActiveZone& zone = terrain_->last_step().zone;
  const vehicle::RigidBody& bucket = loader_->bodies().at(loader_->bucket_body());
  std::vector<int> held;
  for (int k : particles_in_bucket(p, loader_->bucket_mesh(), bucket_pose(*loader_)))
    if (!(zone.depth > 0.0 && zone.contains(p.position[k]))) held.push_back(k);
  // (its mass now: the terrain's step below renumbers the particles)
  double held_mass = 0.0;
  for (int k : held) held_mass += mass[k];
  if (payload_) {
    payload_->update(aggregate_of(p, mass, held));
  } else {
    Vec6 weight = Vec6::Zero();
    for (int k : held) {
      const Vec3 f = mass[k] * loader_->system().gravity();
      weight.head<3>() += f;
      weight.tail<3>() += (p.position[k] - bucket.position).cross(f);
    }
    loader_->system().set_external_wrench(loader_->bucket_body(), weight);
  }
  // the machine's step with the aggregate, then the terrain's with the bucket as it moved: from
  // its pose at the step's start with the twist the machine solved (the terrain moves its tool by
  // h times that twist, so both end the step where the machine's bucket is)
  stage.emplace(dev_, "direct_solve");
  loader_->step(h);
  stage.emplace(dev_, "aggregate");
  aggregate_->after_step(h);
  KinematicBucket moving = kinematic_bucket(*loader_);
  moving.position = start.position;
  moving.orientation = start.orientation;
  stage.reset();
  terrain_->step(moving);
  // what the machine felt of the zone this step
  AggregateSample a;
  a.t = (steps_done_ + 1) * h;
  a.particles = aggregate_->aggregate().particles;
  a.mass = aggregate_->aggregate().mass;
  a.centre = aggregate_->aggregate().centre;
  a.velocity = loader_->system().body(aggregate_->body()).velocity;
  a.zone_velocity = aggregate_->aggregate().velocity;
  a.force_on_bucket = aggregate_->force_on_bucket();
  a.terrain_normal_force = aggregate_->interface_b().normal_force();
  a.terrain_force = aggregate_->terrain_force();
  a.edge_force = aggregate_->edge_force();
  if (support_) a.support_force = support_->force_on_bucket();
  a.held_mass = held_mass;
  a.particle_force = terrain_->last_step().bucket_wrench.head<3>();
  a.soil_force = a.force_on_bucket + aggregate_->edge_force_on_bucket() + a.support_force +
                 held_mass * loader_->system().gravity();
  a.depth_a = aggregate_->depth_a();
  a.depth_b = aggregate_->depth_b();
  const PrincipalAxes axes = principal_axes(aggregate_->aggregate().inertia);
  a.orientation = axes.orientation;
  a.principal_moments = axes.moments;
  aggregate_log_.push_back(a);
}

namespace {
// one step's aggregate sample, field by field
void write_aggregate_sample(ByteWriter& w, const AggregateSample& a) {
  w.f64(a.t);
  w.i64(a.particles);
  w.f64(a.mass);
  write_matrix(w, a.centre);
  write_matrix(w, a.velocity);
  write_matrix(w, a.force_on_bucket);
  for (double v : {a.terrain_normal_force, a.edge_force, a.depth_a, a.depth_b}) w.f64(v);
  write_matrix(w, a.support_force);
  w.f64(a.held_mass);
  write_matrix(w, a.soil_force);
  write_matrix(w, a.particle_force);
  write_matrix(w, a.orientation.coeffs());
  write_matrix(w, a.principal_moments);
  write_matrix(w, a.terrain_force);
  write_matrix(w, a.zone_velocity);
}
AggregateSample read_aggregate_sample(ByteReader& r) {
  AggregateSample a;
  a.t = r.f64("aggregate log");
  a.particles = static_cast<int>(r.i64("aggregate log"));
  a.mass = r.f64("aggregate log");
  read_matrix(r, a.centre, "aggregate log");
  read_matrix(r, a.velocity, "aggregate log");
  read_matrix(r, a.force_on_bucket, "aggregate log");
  for (double* v : {&a.terrain_normal_force, &a.edge_force, &a.depth_a, &a.depth_b})
    *v = r.f64("aggregate log");
  read_matrix(r, a.support_force, "aggregate log");
  a.held_mass = r.f64("aggregate log");
  read_matrix(r, a.soil_force, "aggregate log");
  read_matrix(r, a.particle_force, "aggregate log");
  read_matrix(r, a.orientation.coeffs(), "aggregate log");
  read_matrix(r, a.principal_moments, "aggregate log");
  read_matrix(r, a.terrain_force, "aggregate log");
  read_matrix(r, a.zone_velocity, "aggregate log");
  return a;
}
// bytes a soil force sample takes in a saved state: t, then force, torque and the three faces'
// forces, three doubles each
constexpr std::uint64_t kSoilForceSampleBytes = 8 * (1 + 3 * 5);
// bytes write_aggregate_sample writes
constexpr std::uint64_t kAggregateSampleBytes =
    8 * (1 + 1 + 1 + 3 + 3 + 3 + 4 + 3 + 1 + 3 + 3 + 4 + 3 + 3 + 3);
}  // namespace

void DiggingSimulation::save_state(ByteWriter& w) const {
  w.tag("dig");
  w.f64(time_);
  w.i64(steps_done_);
  w.i64(steps_total_);
  w.i64(contact_steps_);
  w.i64(max_passes_);
  w.i64(capped_steps_);
  w.i64(pass_sum_);
  w.i64(sweep_sum_);
  w.f64(max_residual_);
  w.f64(max_overlap_rel_);
  w.u64(residuals_.size());
  w.f64s(residuals_.data(), residuals_.size());
  w.tag("sensors");
  vehicle::write_sample(w, sensors_);
  log_.save_state(w);
  w.tag("machine");
  loader_->system().save_state(w);
  if (terrain_) {
    // type G: the terrain (voxels, zone particles, ledger), the aggregate's memory, its log
    w.tag("multiscale terrain");
    terrain_->save_state(w);
    w.tag("aggregate");
    aggregate_->save_state(w);
    w.u64(aggregate_log_.size());
    for (const AggregateSample& a : aggregate_log_) write_aggregate_sample(w, a);
  } else {
    w.tag("particles");
    dem_->save_state(w);
    w.tag("bucket contacts");
    split_->save_state(w);
    w.u64(soil_log_.size());
    for (const SoilForceSample& f : soil_log_) {
      w.f64(f.t);
      write_matrix(w, f.force);
      write_matrix(w, f.torque);
      write_matrix(w, f.faces.below);
      write_matrix(w, f.faces.inside);
      write_matrix(w, f.faces.across);
    }
  }
  w.tag("effects");
  effects_.save_state(w);
  w.tag("end");
}

void DiggingSimulation::restore_state(ByteReader& r) {
  r.expect("dig");
  const double time = r.f64("dig clock");
  const std::int64_t steps_done = r.i64("dig clock");
  const std::int64_t steps_total = r.i64("dig clock");
  // a run may step on past its duration, but its step count is an int
  if (steps_total != steps_total_ || steps_done < 0 || steps_done > std::numeric_limits<int>::max())
    throw InputError(r.where() + ": the saved run has " + std::to_string(steps_total) +
                     " steps, this one " + std::to_string(steps_total_) +
                     "; restore a state into a simulation of the same scenario and level");
  time_ = time;
  steps_done_ = static_cast<int>(steps_done);
  contact_steps_ = static_cast<int>(r.i64("coupling counters"));
  max_passes_ = static_cast<int>(r.i64("coupling counters"));
  capped_steps_ = static_cast<int>(r.i64("coupling counters"));
  pass_sum_ = static_cast<long>(r.i64("coupling counters"));
  sweep_sum_ = static_cast<long>(r.i64("coupling counters"));
  max_residual_ = r.f64("coupling counters");
  max_overlap_rel_ = r.f64("coupling counters");
  const std::uint64_t residuals = r.u64("coupling residuals");
  r.need_elements(residuals, 8, "coupling residuals");
  residuals_.resize(residuals);
  r.f64s(residuals_.data(), residuals_.size(), "coupling residuals");
  r.expect("sensors");
  sensors_ = vehicle::read_sample(r, "sensors");
  log_.restore_state(r);
  r.expect("machine");
  loader_->system().restore_state(r);
  if (terrain_) {
    r.expect("multiscale terrain");
    terrain_->restore_state(r);
    r.expect("aggregate");
    aggregate_->restore_state(r);
    const std::uint64_t samples = r.u64("aggregate log");
    r.need_elements(samples, kAggregateSampleBytes, "aggregate log");
    std::vector<AggregateSample> log(samples);
    for (AggregateSample& a : log) a = read_aggregate_sample(r);
    aggregate_log_ = std::move(log);
  } else {
    r.expect("particles");
    dem_->restore_state(r);
    r.expect("bucket contacts");
    split_->restore_state(r);
    const std::uint64_t samples = r.u64("soil force log");
    r.need_elements(samples, kSoilForceSampleBytes, "soil force log");
    std::vector<SoilForceSample> log(samples);
    for (SoilForceSample& f : log) {
      f.t = r.f64("soil force log");
      read_matrix(r, f.force, "soil force log");
      read_matrix(r, f.torque, "soil force log");
      read_matrix(r, f.faces.below, "soil force log");
      read_matrix(r, f.faces.inside, "soil force log");
      read_matrix(r, f.faces.across, "soil force log");
    }
    soil_log_ = std::move(log);
  }
  r.expect("effects");
  effects_.restore_state(r);
  r.expect("end");
}

}  // namespace talus
