// `talus run --scenario NAME [--fidelity LEVEL] --out DIR`: replay a scenario's feedforward
// target speeds on the wheel loader and write DIR/timeseries.csv (100 Hz sensors, SPEC §2.4) and
// DIR/summary.json. Scenarios with a pile (FB35, HD27, RD21) dig in a particle pile built at the
// fidelity level (digging/digging.hpp) and also write the pile's laser scan, particle snapshots
// for ParaView, and PNG figures. --effect NAME:key=value,... adds model extensions (vehicle/effect.hpp,
// docs/effects.md), --effect-plugin FILE loads more from a shared library; summary.json lists them.
#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "apps/commands.hpp"
#include "apps/outputs.hpp"
#include "apps/run.hpp"
#include "digging/digging.hpp"
#include "host/error.hpp"
#include "host/files.hpp"
#include "host/interrupt.hpp"
#include "host/progress.hpp"
#include "host/version.hpp"
#include "io/output.hpp"
#include "io/plot.hpp"
#include "io/render.hpp"
#include "sim2real/replay.hpp"
#include "sim2real/timeseries.hpp"
#include "terrain/aggregate.hpp"
#include "vehicle/data_file.hpp"
#include "vehicle/effect.hpp"
#include "vehicle/effect_plugin.hpp"
#include "vehicle/scenario.hpp"
#include "vehicle/sensors.hpp"
#include "vehicle/wheel_loader.hpp"

namespace talus::app {

namespace {

// the side-view image size [px] (2:1, the shape of a pile seen from the side)
constexpr int kImageWidth = 1600, kImageHeight = 800;
// simulated time between progress notes, which count the load in the bucket [s]
constexpr double kProgressNoteInterval = 0.5;
// simulated time between the samples of load.csv, the load in the bucket as the dig goes [s]:
// ten a second show when a bucket fills (HD27's fill takes about 1.5 s) at no cost worth
// timing (a sample downloads the particles, outside the timed steps)
constexpr double kLoadSampleInterval = 0.1;

// one line for stderr: "effects: a (k=v, ...), b (...)"
std::string effects_note(const vehicle::EffectSet& effects) {
  std::ostringstream note;
  for (size_t i = 0; i < effects.size(); ++i) {
    note << (i ? "; " : "") << effects[i].name();
    const auto params = effects[i].to_json()["params"];
    std::string list;
    for (const auto& [k, v] : params.items())
      list += (list.empty() ? "" : ", ") + k + "=" + (v.is_string() ? v.get<std::string>() : v.dump());
    if (!list.empty()) note << " (" << list << ")";
  }
  return note.str();
}

// DIR/timeseries.csv and DIR/summary.json through the contract's writers, and the summary where
// --json asks for it
void write_run(const RunOptions& o, const sim2real::Run& finished) {
  // which talus made it, and how
  sim2real::Run run = finished;
  add_provenance(run.summary.details, o.command_line);
  // summary.json last: it marks the folder's run as complete (start_output_folder removed the old
  // one)
  const std::filesystem::path dir(o.out);
  sim2real::save_timeseries(dir / sim2real::kTimeseriesFile, run.series);
  sim2real::save_summary(dir / sim2real::kSummaryFile, run.summary);
  if (o.json == "-") {
    std::cout << sim2real::to_json(run.summary).dump(2) << "\n";
  } else if (!o.json.empty()) {
    write_json(o.json, sim2real::to_json(run.summary));
  }
}

// a scenario without particles: the machine alone on flat ground
void run_vehicle_only(const RunOptions& o, const vehicle::Scenario& sc, vehicle::EffectSet& effects) {
  const std::string machine = vehicle::machine_file(sc);
  start_output_folder(o.out);
  const int steps = static_cast<int>(std::llround(sc.duration / sc.timestep));
  if (!o.quiet) {
    const vehicle::WheelLoader loader(machine, sc.payload);
    std::cerr << "talus run: " << sc.name << ", " << sc.duration << " s at h = " << sc.timestep * 1e3 << " ms on "
              << loader.name() << " (" << loader.operating_mass() << " kg with payload)\n";
  }
  const auto start = std::chrono::steady_clock::now();
  if (!effects.empty() && !o.quiet) std::cerr << "talus run: effects: " << effects_note(effects) << "\n";
  Progress progress("run " + sc.name, sc.duration, !o.quiet);
  const vehicle::SensorLog log = sim2real::simulate_on_flat_ground(sc, effects, &progress);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  progress.finish();
  sim2real::Run run = sim2real::vehicle_run(sc, log);
  const double realtime_factor = wall > 0 ? steps * sc.timestep / wall : 0.0;
  run.summary.details = {{"sim_time_s", steps * sc.timestep},
                         {"wall_time_s", wall},
                         {"realtime_factor", realtime_factor},
                         {"effects", effects.to_json()}};
  write_run(o, run);
  if (!o.quiet)
    std::cerr << "talus run: wrote " << o.out << "/timeseries.csv (" << log.samples().size()
              << " samples) and summary.json; work " << log.work() / 1e3 << " kJ, real-time factor "
              << realtime_factor << "\n";
}

// one snapshot: its time and its files, the particles' and the machine's
struct Snapshot {
  double t = 0.0;
  std::string particles, machine;
};

// a ParaView collection of the snapshots with their times (File > Open particles.pvd): part 0 the
// particles, part 1 the machine, so each time step opens as one multiblock of both
std::string pvd_collection(const std::vector<Snapshot>& snapshots) {
  std::ostringstream s;
  s.precision(10);
  s << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n  <Collection>\n";
  for (const Snapshot& snap : snapshots) {
    s << "    <DataSet timestep=\"" << snap.t
      << "\" group=\"\" part=\"0\" name=\"particles\" file=\"" << snap.particles << "\"/>\n";
    s << "    <DataSet timestep=\"" << snap.t << "\" group=\"\" part=\"1\" name=\"machine\" file=\""
      << snap.machine << "\"/>\n";
  }
  s << "  </Collection>\n</VTKFile>\n";
  return s.str();
}

// the side view of particles and the posed bucket (cut away), ray-traced, coloured by speed
void write_render(const std::string& path, const Particles& particles,
                  const vehicle::WheelLoader& loader, const Bounds& view,
                  const VoxelTerrain* terrain = nullptr) {
  RenderScene scene;
  scene.particles = &particles;
  scene.colouring = ParticleColouring::Speed;
  scene.max_speed = 1.0;  // m/s: the paper's figures colour 0-1 m/s
  // a cutaway bucket: without its near side plate (the camera looks along +y from the -y side),
  // so the gravel inside shows
  vehicle::BucketMesh cutaway = loader.bucket_mesh();
  const double near_side = -0.5 * cutaway.inner_width;
  cutaway.triangles.erase(std::remove_if(cutaway.triangles.begin(), cutaway.triangles.end(),
                                         [&](const std::array<int, 3>& t) {
                                           return std::all_of(t.begin(), t.end(), [&](int v) {
                                             return std::abs(cutaway.vertices[v].y() - near_side) < 1e-9;
                                           });
                                         }),
                          cutaway.triangles.end());
  scene.meshes.push_back(posed_mesh(cutaway, bucket_pose(loader)));
  // the type-G terrain's voxel surface, gravel brown
  if (terrain) scene.meshes.push_back(terrain_mesh(*terrain, scene.particle_colour));
  scene.ground_height = 0.0;
  const Camera camera = side_camera(view.lo, view.hi, double(kImageWidth) / kImageHeight);
  Image picture = render_particles(scene, camera, kImageWidth, kImageHeight);
  draw_scale_bar(picture, camera.view_height / kImageHeight);
  picture.write_png(path);
}

// the dig's options from the flags: the pile's seed and formwork, the studies' rolling
// resistance, the residual record and the sweep
DiggingOptions digging_options(const RunOptions& o) {
  DiggingOptions options;
  options.pile.seed = o.seed;
  if (o.rolling >= 0.0) {
    // the gravel's rolling resistance, between grains and against the bucket alike
    options.soil.rolling = o.rolling;
    options.coupling.material.rolling = o.rolling;
  }
  options.coupling.record_residual = o.residuals;
  options.sweep_tolerance = o.sweep_tolerance;
  options.pair_reach = o.pair_reach;
  options.relaxation = o.relaxation;
  options.seed_diameter = o.seed_diameter;
  options.edge_resistance = o.edge_resistance;
  options.excavation_reach = o.excavation_reach;
  options.merge_speed = o.merge_speed;
  options.rest_in_bucket = o.rest_in_bucket;
  options.interface_damping_time = o.interface_damping_time;
  options.content_inertia = o.content_inertia;
  options.bucket_support = o.bucket_support;
  options.failure_plane_floor = o.failure_plane_floor;
  options.avalanche.repose_deg = o.repose_angle;
  options.avalanche.rate = o.avalanche_rate;
  if (o.form_speed >= 0.0) options.pile.form_speed = o.form_speed;
  options.pile.hold_face = o.hold_face;
  options.sweep = parse_sweep(o.sweep, "--sweep");
  options.coupling.bucket_sweep = parse_bucket_sweep(o.bucket_sweep, "--bucket-sweep");
  check_relaxation(o.relaxation, options.sweep, "--relaxation");
  options.pile_cache.enabled = o.pile_cache;
  options.pile_cache.note = [quiet = o.quiet](const std::string& line) {
    if (!quiet) std::cerr << "talus run: " << line << "\n";
  };
  return options;
}

// particle and machine snapshots every `every` steps into DIR/snapshots, and their ParaView
// collection
class Snapshots {
 public:
  Snapshots(const std::filesystem::path& dir, int every) : dir_(dir), every_(every) {
    std::filesystem::create_directories(dir / "snapshots");
  }
  bool on() const { return every_ > 0; }
  // after step k (0: the start)
  void after_step(int k, double t, const DiggingSimulation& sim) {
    if (!on() || k % every_ != 0) return;
    const std::string k_name = std::to_string(taken_.size());
    const Snapshot snap{t, "snapshots/particles_" + k_name + ".vtp",
                        "snapshots/machine_" + k_name + ".vtp"};
    write_file_atomically((dir_ / snap.particles).string(), particles_vtp(sim.particles()));
    write_file_atomically((dir_ / snap.machine).string(), machine_vtp(sim.loader()));
    taken_.push_back(snap);
  }
  // the snapshots still to come, at the first one's size, must fit on the output's file system
  // (type G's zone particles grow, so there it is a lower bound)
  void check_room_for_all(int steps_total, double interval) const {
    if (!on() || taken_.empty()) return;
    const auto size = [&](const std::string& file) {
      return static_cast<double>(std::filesystem::file_size(dir_ / file));
    };
    const double each = size(taken_[0].particles) + size(taken_[0].machine);
    const int still_to_come = steps_total / every_;
    std::ostringstream what;
    what << "--snapshot-interval " << interval << ": " << still_to_come << " more snapshots of "
         << each / 1e6 << " MB each";
    check_room(each * still_to_come, std::filesystem::space(dir_).available, what.str(),
               "take fewer (a longer --snapshot-interval) or none (0)");
  }
  // DIR/particles.pvd
  void finish() const {
    if (on()) write_file_atomically((dir_ / "particles.pvd").string(), pvd_collection(taken_));
  }

 private:
  std::filesystem::path dir_;
  int every_;
  std::vector<Snapshot> taken_;
};

// how many particles a run simulated, over its steps: at type G the zone's and the bucket's,
// which come and go (paper Table 3 bounds them per level); at type D the pile's, constant
struct ParticleTally {
  size_t most = 0;
  double sum = 0.0;
  double resting_sum = 0.0;  // of those riding with the bucket (type G, rest_in_bucket)
  long steps = 0;
  void add(size_t n, int resting) {
    most = std::max(most, n);
    sum += static_cast<double>(n);
    resting_sum += resting;
    ++steps;
  }
  double mean() const { return steps > 0 ? sum / static_cast<double>(steps) : 0.0; }
  double resting_mean() const { return steps > 0 ? resting_sum / static_cast<double>(steps) : 0.0; }
};

// what summary.json tells beyond the contract: the level and its study settings, timing, the
// pile, the particles, the coupling's work, the residuals when recorded, the field values, the
// effects
nlohmann::json dig_details(const RunOptions& o, const vehicle::Scenario& sc,
                           const FidelityPreset& preset, const DiggingOptions& options,
                           const PileBuild& pile, const PileScan& scan,
                           const DiggingSimulation& sim, const ParticleTally& tally,
                           double pile_wall, double dig_wall, const Device& dev,
                           const vehicle::EffectSet& effects) {
  const double sim_time = sim.time();
  // the aggregate's interfaces as the dig set them (type G)
  AggregateParameters interfaces;
  interfaces.damping_time = options.interface_damping_time;
  nlohmann::json details = {
      {"particles",
       static_cast<int>(sim.multiscale() ? sim.particle_count() : pile.particles.size())},
      // the most particles at the end of any step, and their mean over the steps
      {"particles_most", static_cast<long>(tally.most)},
      {"particles_mean", tally.mean()},
      // of them, those riding with the bucket at rest, out of the DEM's rows (their mean over the
      // steps; type G unless --no-rest-in-bucket, else 0)
      {"particles_resting_mean", tally.resting_mean()},
      {"model", sim.multiscale() ? "multiscale (type G)" : "particles (type D)"},
      {"dt_s", preset.dt},
      {"iterations", preset.iterations},
      {"damping_time_s", options.soil.damping_steps * preset.dt},
      {"rolling_resistance", options.soil.rolling},
      {"seed", o.seed},
      {"form_speed_m_s", options.pile.form_speed},
      {"pile_face_held", options.pile.hold_face},
      {"work_total_J", sim.log().work()},
      {"sim_time_s", sim_time},
      {"wall_time_s", dig_wall},
      {"realtime_factor", dig_wall > 0 ? sim_time / dig_wall : 0.0},
      {"pile_build_wall_s", pile_wall},
      {"pile_from_cache", pile.from_cache},
      {"pile_bulk_density", pile.bulk_density},
      {"pile_toe_shift_m", pile.toe_shift},
      {"pile_fill_at_rest", pile.fill_at_rest},
      {"pile_at_rest", pile.at_rest},
      {"pile_rms_speed_m_s", pile.rms_speed},
      {"scan_face_angle_deg", scan.face_angle_deg},
      {"scan_rms_to_profile_m", scan.rms_to_profile_m},
      {"scan_mean_to_profile_m", scan.mean_to_profile_m},
      {"soil_rms_to_profile_m", pile.soil_fit.rms_m},
      {"soil_mean_to_profile_m", pile.soil_fit.mean_m},
      {"coupling",
       {{"steps_with_bucket_contacts", sim.contact_steps()},
        {"mean_passes", sim.mean_passes()},
        {"mean_sweeps", sim.mean_sweeps()},
        {"sweep_tolerance_m_s", applied_sweep_tolerance(options.sweep_tolerance, preset)},
        {"pair_reach", options.pair_reach},
        {"relaxation", options.relaxation},
        {"bucket_sweep", bucket_sweep_name(options.coupling.bucket_sweep)},
        {"seed_diameter", options.seed_diameter},
        {"edge_resistance", options.edge_resistance},
        // how far ahead of the cutting edge the zone's soil turns dynamic [m] (0: the whole wedge)
        {"excavation_reach_m", options.excavation_reach},
        // a zone particle slower than this may merge back into the voxels [m/s] (type G; the
        // default at type D, which has no voxels)
        {"merge_speed_m_s", options.merge_speed},
        // the bucket's resting load rides with it as fixed particles (type G; the default)
        {"rest_in_bucket", options.rest_in_bucket},
        // the zone's particles on its failure plane (true) or its columns' staircase (type G)
        {"failure_plane_floor", options.failure_plane_floor},
        // the voxel surface's avalanche (type G; the defaults at type D, which has none)
        {"repose_angle_deg", options.avalanche.repose_deg},
        {"avalanche_rate_per_s", options.avalanche.rate},
        // the aggregate's interfaces' damping time in use (type G; null at type D)
        {"interface_damping_time_s",
         sim.multiscale() ? nlohmann::json(interface_damping_time(interfaces, preset.dt))
                          : nlohmann::json(nullptr)},
        {"content_inertia", options.content_inertia},
        {"bucket_support", options.bucket_support},
        {"max_passes", sim.max_passes()},
        {"max_residual_m_s", sim.max_residual()},
        {"steps_at_pass_limit", sim.steps_at_pass_limit()},
        {"max_bucket_overlap_rel", sim.max_bucket_overlap_rel()}}},
      {"device", dev.description()},
      {"reconstructed_inputs", true},
      {"effects", effects.to_json()}};
  if (!sim.step_residuals().empty()) {
    // the particle rows' residual at the end of each step with contacts: median and 95th percentile
    std::vector<double> r = sim.step_residuals();
    std::sort(r.begin(), r.end());
    auto quantile = [&](double q) {
      return r[static_cast<size_t>(q * static_cast<double>(r.size() - 1))];
    };
    details["step_residual_m_s"] = {
        {"median", quantile(0.5)}, {"p95", quantile(0.95)}, {"steps", r.size()}};
  }
  if (sc.field_loaded_mass_kg > 0) {
    details["field_loaded_mass_kg"] = sc.field_loaded_mass_kg;
    details["field_work_J"] = sc.field_work_J;
  }
  return details;
}

// figures from the run in memory: the channels, the bucket tip over the scanned pile, power,
// and the rendered side view of the particles at the end
void write_dig_figures(const std::filesystem::path& dir, const sim2real::Run& run,
                       const PileScan& scan, const vehicle::Scenario& sc, const PileProfile& placed,
                       const Particles& final_particles, const vehicle::WheelLoader& loader,
                       const VoxelTerrain* terrain) {
  channel_figure({run}, nullptr)
      .write_png((dir / "channels.png").string(), kFigureWidth, kFigureHeight);
  std::vector<std::pair<double, double>> surface;
  for (const auto& q : scan.points) surface.emplace_back(q.x(), q.y());
  trajectory_figure({run}, nullptr, surface)
      .write_png((dir / "trajectory.png").string(), kFigureWidth, kFigureWidth / 2);
  power_figure({run}, nullptr)
      .write_png((dir / "power.png").string(), kFigureWidth, kFigureHeight / 2);
  Bounds view;
  view.lo = Vec3(sc.pile_toe_x - 4.0, -3.0, 0.0);
  view.hi = Vec3(placed.rear_wall_x, 3.0, 4.0);
  write_render((dir / "side.png").string(), final_particles, loader, view, terrain);
}

// the type-D soil's force on the bucket step by step as CSV (the torque about the bucket's centre
// of mass), then the force by the bucket's face the soil meets: under the bottom, on its inside,
// across the cutting direction (compare a type-G run's aggregate.csv: the support, the held load,
// interface A with the edge)
std::string soil_csv(const std::vector<SoilForceSample>& log) {
  std::ostringstream os;
  os << "t,fx,fy,fz,mx,my,mz,fx_below,fy_below,fz_below,fx_inside,fy_inside,fz_inside,fx_across,"
        "fy_across,fz_across\n";
  os.precision(9);
  const auto vec = [&os](const Vec3& v) { os << ',' << v.x() << ',' << v.y() << ',' << v.z(); };
  for (const SoilForceSample& f : log) {
    os << f.t;
    vec(f.force);
    vec(f.torque);
    vec(f.faces.below);
    vec(f.faces.inside);
    vec(f.faces.across);
    os << '\n';
  }
  return os.str();
}

// the load in the bucket as the dig goes (t, loaded_kg): the summary's loaded_mass_kg (the
// heaped volume's, SAE J742) at every sample
std::string load_csv(const std::vector<std::pair<double, double>>& samples) {
  std::ostringstream os;
  os << "t,loaded_kg\n";
  os.precision(9);
  for (const auto& [t, kg] : samples) os << t << ',' << kg << '\n';
  return os.str();
}

// the type-G aggregate step by step as CSV (ParaView reads it with Table To Points on cx, cy, cz;
// its pose's orientation is the quaternion qx..qw of its principal axes, moments i1 <= i2 <= i3)
std::string aggregate_csv(const std::vector<AggregateSample>& log) {
  std::ostringstream os;
  os << "t,particles,mass,cx,cy,cz,vx,vy,vz,fx_bucket,fy_bucket,fz_bucket,terrain_normal_force,"
        "edge_force,depth_a,depth_b,qx,qy,qz,qw,i1,i2,i3,fx_support,fy_support,fz_support,"
        "held_mass,fx_soil,fy_soil,fz_soil,fx_particles,fy_particles,fz_particles,fx_terrain,"
        "fy_terrain,fz_terrain,vx_zone,vy_zone,vz_zone\n";
  os.precision(9);
  for (const AggregateSample& a : log)
    os << a.t << ',' << a.particles << ',' << a.mass << ',' << a.centre.x() << ',' << a.centre.y()
       << ',' << a.centre.z() << ',' << a.velocity.x() << ',' << a.velocity.y() << ','
       << a.velocity.z() << ',' << a.force_on_bucket.x() << ',' << a.force_on_bucket.y() << ','
       << a.force_on_bucket.z() << ',' << a.terrain_normal_force << ',' << a.edge_force << ','
       << a.depth_a << ',' << a.depth_b << ',' << a.orientation.x() << ',' << a.orientation.y()
       << ',' << a.orientation.z() << ',' << a.orientation.w() << ',' << a.principal_moments.x()
       << ',' << a.principal_moments.y() << ',' << a.principal_moments.z() << ','
       << a.support_force.x() << ',' << a.support_force.y() << ',' << a.support_force.z() << ','
       << a.held_mass << ',' << a.soil_force.x() << ',' << a.soil_force.y() << ','
       << a.soil_force.z() << ',' << a.particle_force.x() << ',' << a.particle_force.y() << ','
       << a.particle_force.z() << ',' << a.terrain_force.x() << ',' << a.terrain_force.y() << ','
       << a.terrain_force.z() << ',' << a.zone_velocity.x() << ',' << a.zone_velocity.y() << ','
       << a.zone_velocity.z() << '\n';
  return os.str();
}

// a pile scenario: build the pile at the level, dig, write everything
void run_digging(const RunOptions& o, const vehicle::Scenario& sc, vehicle::EffectSet& effects) {
  FidelityPreset preset = level_preset(o.fidelity);
  if (o.dt > 0.0) preset.dt = o.dt;
  if (o.iterations > 0) preset.iterations = o.iterations;
  const PileProfile placed = scenario_pile_profile(sc);
  const DiggingOptions options = digging_options(o);
  start_output_folder(o.out);
  const std::filesystem::path dir(o.out);
  const auto start = std::chrono::steady_clock::now();
  Device dev(run_device_choice(preset));
  if (!o.quiet)
    std::cerr << "talus run: " << sc.name << " at " << preset.name << " (D "
              << preset.diameter * 1e3 << " mm, h " << preset.dt * 1e3 << " ms, "
              << preset.iterations << " sweeps) on " << dev.description() << "\n";

  // the pile, settled, and its laser scan before loading (as the field tests measured it)
  PileBuild pile;
  {
    Progress progress("pile " + preset.name, 1.5 * options.pile.max_time, !o.quiet);
    // the pile is the level's own whatever the dig's timestep and sweeps: a convergence study
    // changes the dig alone
    pile = build_scenario_pile(dev, sc, placed, level_preset(o.fidelity), options, &progress);
    progress.finish(std::to_string(pile.particles.size()) + " particles");
  }
  const double pile_wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const PileScan scan = scan_scenario_pile(pile, placed, preset);
  write_file_atomically((dir / "scan.csv").string(), scan_csv(scan));

  // the run, with snapshots at the interval and progress notes; the steps alone are timed for the
  // real-time factor (snapshots and notes, which download the particles, are not)
  if (!effects.empty() && !o.quiet)
    std::cerr << "talus run: effects: " << effects_note(effects) << "\n";
  // a damping-time study changes the dig's contact rows alone (the pile settled with the level's)
  DiggingOptions dig_options = options;
  if (o.damping_time > 0.0) dig_options.soil.damping_steps = o.damping_time / preset.dt;
  DiggingSimulation sim(dev, sc, preset, pile, dig_options, &effects);
  if (sim.multiscale())
    write_file_atomically((dir / "terrain_start.vts").string(),
                          terrain_vts(sim.terrain().voxels()));
  // steps between snapshots, at most one more than the run has (an interval beyond the run, 1e308
  // meaning "never", overflowed the step count and took a snapshot every step)
  const double snapshot_steps =
      std::min(o.snapshot_interval / preset.dt, static_cast<double>(sim.steps_total()) + 1.0);
  Snapshots snapshots(dir, o.snapshot_interval > 0.0
                               ? std::max(1, static_cast<int>(std::lround(snapshot_steps)))
                               : 0);
  snapshots.after_step(0, sim.time(), sim);
  snapshots.check_room_for_all(sim.steps_total(), o.snapshot_interval);
  Progress progress("dig " + sc.name + " " + preset.name, sc.duration, !o.quiet);
  const int note_every =
      std::max(1, static_cast<int>(std::lround(kProgressNoteInterval / preset.dt)));
  // the load in the bucket from the start, a sample every kLoadSampleInterval and at the end
  const int load_every =
      std::max(1, static_cast<int>(std::lround(kLoadSampleInterval / preset.dt)));
  std::vector<std::pair<double, double>> load{{sim.time(), sim.loaded_mass()}};
  ParticleTally tally;
  const double dig_wall = sim.run([&](int k) {
    // asked to stop: between steps, before anything of this step is written
    if (interrupt_requested()) {
      std::ostringstream where;
      where << "the dig " << sc.name << " " << preset.name << " at t = " << sim.time() << " s of "
            << sc.duration << " s";
      throw_if_interrupted(where.str());
    }
    snapshots.after_step(k, sim.time(), sim);
    tally.add(sim.particle_count(), sim.multiscale() ? sim.terrain().last_step().resting : 0);
    // the load, measured once for the sample and the note alike (each measure downloads the
    // particles)
    const bool sample = k % load_every == 0 || sim.done();
    const bool note_due = !o.quiet && k % note_every == 0;
    if (!sample && !note_due) return;
    const double loaded = sim.loaded_mass();
    if (sample) load.emplace_back(sim.time(), loaded);
    if (note_due) {
      std::ostringstream note;
      note << std::fixed << std::setprecision(0);
      if (sim.multiscale())
        note << sim.particle_count() << " particles, ";
      else
        note << sim.split().stats().bucket_contacts << " bucket contacts, ";
      note << loaded << " kg in the bucket";
      progress.update(sim.time(), note.str());
    }
  });
  const Particles final_particles = sim.particles();
  sim2real::Run run = sim2real::dig_run(sc, preset.name, sim);
  progress.finish(std::to_string(static_cast<long>(std::lround(run.summary.loaded_mass_kg))) +
                  " kg loaded");

  // outputs: snapshots' collection, time series and summary, figures
  snapshots.finish();
  run.summary.details = dig_details(o, sc, preset, dig_options, pile, scan, sim, tally, pile_wall,
                                    dig_wall, dev, effects);
  run.dir = dir;
  // (before the run contract, whose summary.json, written last, marks the folder complete)
  write_file_atomically((dir / "load.csv").string(), load_csv(load));
  write_run(o, run);
  write_dig_figures(dir, run, scan, sc, placed, final_particles, sim.loader(),
                    sim.multiscale() ? &sim.terrain().voxels() : nullptr);
  // the type-G terrain's surface at the end, beside the one it started from, for ParaView
  if (sim.multiscale()) {
    write_file_atomically((dir / "terrain.vts").string(), terrain_vts(sim.terrain().voxels()));
    write_file_atomically((dir / "aggregate.csv").string(), aggregate_csv(sim.aggregate_log()));
  } else {
    write_file_atomically((dir / "bucket_soil.csv").string(), soil_csv(sim.soil_log()));
  }
  if (!o.quiet)
    std::cerr << "talus run: " << sc.name << " " << preset.name << ": "
              << run.summary.loaded_mass_kg << " kg loaded, work in the digging phase "
              << run.summary.work_J / 1e3 << " kJ, real-time factor "
              << run.summary.details["realtime_factor"].get<double>() << "; results in " << o.out
              << "\n";
}

}  // namespace

void run_scenario(const RunOptions& o) {
  const vehicle::Scenario sc = o.scenario_data ? *o.scenario_data : vehicle::load_scenario(o.scenario);
  check_output_file(o.json, "--json");
  // the model extensions of the options, in their order (bad input before anything runs)
  const auto effects = vehicle::load_effects(o.effects, o.effect_plugins, sc, "--effect");
  // the level and the sweep are checked for every scenario, though only a pile uses them
  const FidelityPreset level = level_preset(o.fidelity);
  parse_sweep(o.sweep, "--sweep");
  const BucketSweep bucket_sweep = parse_bucket_sweep(o.bucket_sweep, "--bucket-sweep");
  if (bucket_sweep != BucketSweep::Serial && !sc.pile)
    throw InputError("--bucket-sweep " + o.bucket_sweep + ": scenario '" + sc.name +
                     "' has no pile, so no particle-bucket rows to colour; give a pile scenario "
                     "at a D level, or leave it serial");
  check_bucket_sweep(bucket_sweep, level, "--bucket-sweep");
  check_sweep_tolerance(o.sweep_tolerance, level, "--sweep-tolerance");
  if (o.seed_diameter != 1.0 && !sc.pile)
    throw InputError("--seed-diameter " + std::to_string(o.seed_diameter) + ": scenario '" +
                     sc.name +
                     "' has no pile, so no type-G particles to grow; leave it at 1 or run a pile "
                     "scenario (fb35, hd27, rd21)");
  // the type-G studies of the bucket's content and its cutting edge: a pile scenario at a G level
  const auto type_g_only = [&](bool given, const std::string& option, const std::string& what) {
    if (given && !(sc.pile && is_multiscale(level)))
      throw InputError(option + ": scenario '" + sc.name + "' at " + level.name + " has no " +
                       what +
                       "; give a pile scenario with --fidelity G400 (or finer), or leave "
                       "the option out");
  };
  type_g_only(!o.content_inertia, "--no-content-inertia",
              "type-G bucket content to hold by its weight alone");
  type_g_only(!o.bucket_support, "--no-bucket-support",
              "type-G soil to hold the bucket up or give way");
  type_g_only(o.edge_resistance != 1.0, "--edge-resistance " + std::to_string(o.edge_resistance),
              "type-G cutting edge to resist");
  type_g_only(o.excavation_reach != 0.0, "--excavation-reach " + std::to_string(o.excavation_reach),
              "type-G zone to excavate");
  type_g_only(o.merge_speed != kMergeSpeed, "--merge-speed " + std::to_string(o.merge_speed),
              "type-G particles to merge back into voxels");
  type_g_only(!o.rest_in_bucket, "--no-rest-in-bucket",
              "type-G bucket whose resting load to keep in the DEM");
  type_g_only(!o.failure_plane_floor, "--no-failure-plane-floor",
              "type-G zone whose floor to make of voxel columns");
  type_g_only(o.repose_angle != AvalancheOptions{}.repose_deg,
              "--repose-angle " + std::to_string(o.repose_angle),
              "type-G voxel surface to avalanche");
  type_g_only(o.avalanche_rate != AvalancheOptions{}.rate,
              "--avalanche-rate " + std::to_string(o.avalanche_rate),
              "type-G voxel surface to avalanche");
  type_g_only(o.interface_damping_time != 0.0,
              "--interface-damping-time " + std::to_string(o.interface_damping_time),
              "type-G aggregate's interfaces to damp");
  if (o.seed_diameter != 1.0 && !is_multiscale(level))
    throw InputError("--seed-diameter " + std::to_string(o.seed_diameter) + " at " + level.name +
                     ": only the type-G levels (G400 ... G50) grow their zone's particles from "
                     "seeds; give --fidelity G400 (or finer) or leave it at 1");
  if (sc.pile) {
    run_digging(o, sc, effects->set);
  } else {
    // a payload the machine cannot hold on its wheels even with its boom low is refused
    const vehicle::MachineDescription machine = vehicle::parse_machine(vehicle::machine_file(sc));
    vehicle::check_payload_holds(sc, vehicle::WheelLoader(machine, sc.payload));
    // above the rated load it runs, with a word on stderr (not silenced by --quiet: it is about
    // the result, not progress)
    if (const std::string w = vehicle::payload_warning(sc, machine); !w.empty())
      std::cerr << "talus run: warning: " << w << "\n";
    run_vehicle_only(o, sc, effects->set);
  }
}

void add_run_command(CLI::App& app, const std::string& command_line) {
  auto opts = std::make_shared<RunOptions>();
  opts->command_line = command_line;
  auto* cmd = app.add_subcommand("run", "replay a scenario's feedforward inputs on the wheel loader (digging in "
                                        "a particle pile for fb35, hd27, rd21)");
  cmd->add_option("--scenario", opts->scenario, "scenario name (data/scenarios/NAME.json: fb35, hd27, rd21, "
                                                "flat-lift) or path")->required();
  cmd->add_option("--fidelity", opts->fidelity,
                  "level for pile scenarios: particles D400, D200, D100, D50, or the multiscale "
                  "terrain G400, G200, G100, G50")
      ->capture_default_str();
  cmd->add_option("--out", opts->out, "output folder for timeseries.csv, summary.json and, with a pile, "
                                      "scan.csv, snapshots/, particles.pvd and PNG figures")->required();
  cmd->add_option("--json", opts->json, "also write the summary to this file ('-' for stdout)");
  cmd->add_option("--snapshot-interval", opts->snapshot_interval,
                  "simulated seconds between particle snapshots "
                  "(.vtp); 0 for none")
      ->capture_default_str()
      ->check(finite_number())
      ->check(non_negative_number());
  cmd->add_option("--sweep", opts->sweep, "particle sweeps: pgs or jacobi")->capture_default_str();
  cmd->add_option("--seed", opts->seed, "random seed of the pile's particle sizes and jitter")->capture_default_str();
  cmd->add_flag("--quiet", opts->quiet, "no progress on stderr");
  cmd->add_flag(
      "!--no-pile-cache", opts->pile_cache,
      "build the pile even when the pile cache holds it, and do not save it "
      "($TALUS_CACHE_DIR, else $XDG_CACHE_HOME/talus or ~/.cache/talus; docs/embedding.md)");
  cmd->add_option("--rolling", opts->rolling,
                  "study: the gravel's rolling resistance mu_r instead of the paper's 0.02 "
                  "(docs/soil.md)")
      ->check(number_in(0.0, kMaxContactCoefficient, ""));
  cmd->add_option("--dt", opts->dt, "study: timestep [s] instead of the level's")
      ->check(number_in(kMinTimestep, kMaxTimestep, "s"));
  cmd->add_option("--iterations", opts->iterations, "study: sweeps per step instead of the level's")
      ->check(CLI::Range(1, 100000));
  cmd->add_option("--damping-time", opts->damping_time,
                  "study: SPOOK damping time of the dig's particle contacts instead of two of "
                  "its steps, so that --dt changes the step alone (docs/validation.md; at a G "
                  "level the zone's particles only, not the aggregate's interfaces) [s]")
      ->check(number_in(kMinDampingTime, kMaxDampingTime, "s"));
  cmd->add_option("--sweep-tolerance", opts->sweep_tolerance,
                  "end a step's sweeps once the particle rows' RMS residual is below this, the "
                  "level's sweeps the cap; 0 = always the level's, as the paper's presets "
                  "(docs/dem.md); a D level's (a G level's zone always runs its level's) [m/s]")
      ->capture_default_str()
      // a residual above 1 m/s is no convergence at all (the bucket moves at about 1 m/s)
      ->check(number_in(0.0, 1.0, "m/s", true));
  add_reach_option(*cmd, opts->pair_reach);
  cmd->add_option("--relaxation", opts->relaxation, kRelaxationHelp)
      ->check(relaxation_number())
      ->capture_default_str();
  cmd->add_option("--bucket-sweep", opts->bucket_sweep, kBucketSweepHelp)->capture_default_str();
  cmd->add_option("--edge-resistance", opts->edge_resistance,
                  "study, type G: a factor on the cutting edge's penetration resistance, in [0, "
                  "10]; 1 = the law as it stands, 0 = none (docs/multiscale.md \"Penetration "
                  "resistance\": the law is talus's own and moves a dig most)")
      ->check(number_in(0.0, kMaxEdgeResistance, ""))
      ->capture_default_str();
  cmd->add_option("--interface-damping-time", opts->interface_damping_time,
                  "study, type G: the SPOOK damping time of the aggregate's interfaces A and B [s] "
                  "instead of two of the level's steps (0, the default); at G200 it sets HD27's "
                  "breakout force (docs/validation.md \"HD27's breakout follows the interfaces' "
                  "damping time\")")
      ->check(number_in(kMinDampingTime, kMaxDampingTime, "s", true))
      ->capture_default_str();
  cmd->add_option("--excavation-reach", opts->excavation_reach,
                  "study, type G: the zone's soil turns into particles only within this distance "
                  "ahead of the cutting edge [m]; 0 = the whole wedge (the default; "
                  "docs/validation.md \"The zone's excavation reach\")")
      ->check(non_negative_number())
      ->capture_default_str();
  cmd->add_option("--merge-speed", opts->merge_speed,
                  "study, type G: a zone particle slower than this may merge back into the "
                  "voxels [m/s], above 0; 0.1 = the zone's activation speed (the default; the "
                  "reference engine merges below about 4 m/s: docs/multiscale.md \"How many "
                  "particles\")")
      ->check(positive_number())
      ->capture_default_str();
  cmd->add_flag("--rest-in-bucket,!--no-rest-in-bucket", opts->rest_in_bucket,
                "type G: while the bucket digs nothing, a particle at rest in it for 0.2 s rides "
                "with it as a fixed particle, out of the DEM's rows, until the gravity it feels "
                "in the bucket's frame changes by 0.1 g or the bucket digs again (the default); "
                "--no-rest-in-bucket, a study: every particle in the DEM (docs/multiscale.md "
                "\"The bucket's resting load\")")
      ->capture_default_str();
  cmd->add_option("--repose-angle", opts->repose_angle,
                  "study, type G: the voxel surface's angle of repose, to which it avalanches "
                  "[deg], in [5, 60] (docs/validation.md \"D100's face creeps from t = 0\")")
      ->check(number_in(kMinReposeAngle, kMaxReposeAngle, "deg"))
      ->capture_default_str();
  cmd->add_option("--avalanche-rate", opts->avalanche_rate,
                  "study, type G: how fast the surface's slope above the repose angle decays "
                  "[1/s], in [0, 1000]; 6.3 = the reference engine's (terrain/avalanche.hpp)")
      ->check(number_in(0.0, kMaxAvalancheRate, "1/s"))
      ->capture_default_str();
  cmd->add_option("--seed-diameter", opts->seed_diameter,
                  "study, type G: the zone's particles appear at this fraction of their full "
                  "diameter and grow as the excavated soil feeds them, in [0.1, 1]; 1 = at full "
                  "size (docs/multiscale.md \"Growth\": smaller seeds load more soil)")
      ->check(seed_fraction())
      ->capture_default_str();
  cmd->add_flag("--content-inertia,!--no-content-inertia", opts->content_inertia,
                "type G: the soil the bucket holds is a body welded to it, so the machine feels "
                "its inertia as well as its weight (the default); --no-content-inertia, a study: "
                "its weight alone (docs/multiscale.md \"The bucket's content\")")
      ->capture_default_str();
  cmd->add_flag("--failure-plane-floor,!--no-failure-plane-floor", opts->failure_plane_floor,
                "type G: the zone's particles stand on its failure plane (the default); "
                "--no-failure-plane-floor, a study: on the staircase its excavated voxel columns "
                "make (docs/multiscale.md \"The zone's floor is its failure plane\")")
      ->capture_default_str();
  cmd->add_flag("--bucket-support,!--no-bucket-support", opts->bucket_support,
                "type G: the resting soil holds the bucket's bottom up, solved with the machine "
                "(the default); --no-bucket-support, a study: the soil under the bucket gives "
                "way to any force (docs/multiscale.md \"The terrain's support under the bucket\")")
      ->capture_default_str();
  cmd->add_option("--form-speed", opts->form_speed,
                  "study, with --free-face: speed the pile's formwork withdraws at before it "
                  "settles, 0 = removed at once [m/s]")
      // slower than 10 mm/s it takes hours to clear the face (build_pile refuses it too)
      ->check(number_in(0.01, 10.0, "m/s", true));
  cmd->add_flag("--hold-face,!--free-face", opts->hold_face,
                "the formwork holds the pile's face while it settles and goes when the dig starts, "
                "so the face stands at its profile at t = 0 (the default); --free-face: it goes "
                "before the pile settles (issue 11's earlier piles; docs/validation.md)");
  cmd->add_flag("--residuals", opts->residuals, "record the particle rows' residual at the end of every step "
                "(summary: step_residual_m_s median and p95)");
  cmd->add_option("--effect", opts->effects,
                  "a model extension, NAME or NAME:key=value,key=value (repeatable, applied in order): "
                  "engine_power_sharing, hydraulic_lag, pump_flow_limit, cylinder_friction, wheel_slip_sensor, "
                  "tyre_rolling_resistance, sensor_bias, sensor_delay, or a plug-in's (docs/effects.md)")
      ->expected(1)->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  cmd->add_option("--effect-plugin", opts->effect_plugins,
                  "a shared library with more effects (vehicle/effect_abi.h; repeatable)")
      ->expected(1)->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  cmd->callback([opts] { run_scenario(*opts); });
}

}  // namespace talus::app
