#include "embed/talus.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <system_error>
#include <utility>

#include "digging/digging.hpp"
#include "digging/feedback_sweep.hpp"
#include "digging/saved_state.hpp"
#include "host/binary.hpp"
#include "host/data_files.hpp"
#include "host/device.hpp"
#include "host/files.hpp"
#include "host/progress.hpp"
#include "host/version.hpp"
#include "terrain/multiscale_terrain.hpp"
#include "terrain/pile.hpp"
#include "vehicle/data_file.hpp"
#include "vehicle/effect.hpp"
#include "vehicle/effect_plugin.hpp"
#include "vehicle/force_feedback.hpp"
#include "vehicle/scenario.hpp"
#include "vehicle/sensors.hpp"
#include "vehicle/wheel_loader.hpp"

namespace talus {

namespace fs = std::filesystem;

namespace {

// the reading's field of each contract channel, in the contract's order (kSensorChannels): the
// header spells the fields for users, and tests/embed holds them to the contract's names
constexpr std::array<double SensorReading::*, vehicle::kChannelCount> kReadingFields = {
    &SensorReading::t,
    &SensorReading::f_lift,
    &SensorReading::f_tilt,
    &SensorReading::f_traction,
    &SensorReading::v_drive,
    &SensorReading::d_lift,
    &SensorReading::d_tilt,
    &SensorReading::boom_deg,
    &SensorReading::bucket_deg,
    &SensorReading::pitch_deg,
    &SensorReading::x_vehicle,
    &SensorReading::bucket_tip_x,
    &SensorReading::bucket_tip_z,
    &SensorReading::power};

SensorReading to_reading(const vehicle::SensorSample& s) {
  SensorReading r;
  for (std::size_t c = 0; c < vehicle::kChannelCount; ++c)
    r.*kReadingFields[c] = s.*vehicle::kSensorChannels[c].field;
  return r;
}

std::string lower_case(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

// the data folders in the facade's order: $TALUS_DATA_DIR (the person running decides), the
// program's data_dir (the installed package's by default), then ./data and beside the program
std::vector<std::string> data_roots(const std::string& data_dir) {
  std::vector<std::string> roots = data_search_paths();
  if (!data_dir.empty()) {
    const bool from_env = std::getenv("TALUS_DATA_DIR") != nullptr;
    roots.insert(roots.begin() + (from_env ? 1 : 0), data_dir);
  }
  return roots;
}

// name_or_path when it is a file, else data/<subdir>/<name>.json (the name in any case) in the
// first root that has it; empty when none has
std::string resolve(const std::string& name_or_path, const std::string& subdir,
                    const std::vector<std::string>& roots) {
  std::error_code ec;
  if (fs::is_regular_file(name_or_path, ec)) return name_or_path;
  for (const std::string& name : {name_or_path, lower_case(name_or_path)}) {
    for (const std::string& root : roots) {
      const fs::path p = fs::path(root) / subdir / (name + ".json");
      if (fs::is_regular_file(p, ec)) return p.string();
    }
  }
  return {};
}

// the shipped scenarios' names in the first root that has scenarios, for an error message
std::string known_scenarios(const std::vector<std::string>& roots) {
  for (const std::string& root : roots) {
    std::error_code ec;
    std::vector<std::string> names;
    for (const auto& entry : fs::directory_iterator(fs::path(root) / "scenarios", ec))
      if (entry.path().extension() == ".json") names.push_back(entry.path().stem().string());
    if (names.empty()) continue;
    std::sort(names.begin(), names.end());
    std::string list;
    for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
    return list;
  }
  return {};
}

// the scenario of the options, its machine and pile profile found where the options say (the
// layers below search only $TALUS_DATA_DIR, ./data and beside the program)
vehicle::Scenario load_options_scenario(const SimulationOptions& options) {
  const std::vector<std::string> roots = data_roots(options.data_dir);
  const std::string path = resolve(options.scenario, "scenarios", roots);
  if (path.empty()) {
    std::string searched;
    for (const std::string& root : roots)
      searched += (searched.empty() ? "" : ", ") + root + "/scenarios";
    const std::string known = known_scenarios(roots);
    throw InputError(
        "SimulationOptions::scenario '" + options.scenario + "': no such file, and no " +
        options.scenario + ".json in " + searched + "; give a shipped scenario's name" +
        (known.empty() ? std::string(" or a path")
                       : " (" + known + ") or the path of a scenario file") +
        (known.empty() ? "; no data folder was found: set SimulationOptions::data_dir or "
                         "TALUS_DATA_DIR to the folder holding talus's data"
                       : ""));
  }
  vehicle::Scenario sc = vehicle::load_scenario(path);
  // what the scenario names is found in the same folders; what is not is left to the layers
  // below, whose errors name the scenario's field
  if (const std::string machine = resolve(sc.machine, "machines", roots); !machine.empty())
    sc.machine = machine;
  if (sc.pile) {
    if (const std::string pile = resolve(sc.pile_profile, "piles", roots); !pile.empty())
      sc.pile_profile = pile;
  }
  return sc;
}

// the level of the options, InputError naming the option and the known levels
FidelityPreset options_level(const SimulationOptions& options) {
  try {
    return level_preset(options.level);
  } catch (const InputError& e) {
    throw InputError(std::string("SimulationOptions::level: ") + e.what() + "; give one of them");
  }
}

// a data file by name and content, for a saved state's key: "name hash", the hash FNV-1a of its
// bytes, so a state is refused after the file it was made from has changed
std::string content_id(const std::string& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return path + " (not a file)";
  std::ostringstream id;
  id << fs::path(path).filename().string() << " " << std::hex
     << fnv1a64(read_file_bytes(path, "a data file of the scenario"));
  return id.str();
}

// what a saved state is keyed by: every option that changes what the constructor builds, one
// "name=value" line each (digging/saved_state.hpp)
std::string state_key(const SimulationOptions& options, const vehicle::Scenario& scenario,
                      const FidelityPreset& preset) {
  std::ostringstream key;
  key.precision(17);
  key << "scenario=" << scenario.name << " " << content_id(scenario.path) << "\n";
  key << "machine=" << content_id(vehicle::machine_file(scenario)) << "\n";
  if (scenario.pile) {
    key << "pile=" << content_id(vehicle::find_data_file(scenario.pile_profile, "piles")) << "\n";
    key << "level=" << preset.name << "\n";
    key << "seed=" << options.seed << "\n";
  }
  key << "loading_cycle=" << (options.loading_cycle ? 1 : 0) << "\n";
  // the model extensions as given, and the plug-ins by content
  for (const std::string& effect : options.effects) key << "effect=" << effect << "\n";
  for (const std::string& plugin : options.effect_plugins)
    key << "effect_plugin=" << content_id(plugin) << "\n";
  if (options.loading_cycle)
    key << "cycle=" << options.cycle_approach << " m, " << options.cycle_max_time << " s, s "
        << options.cycle_s << "\n";
  return key.str();
}

}  // namespace

// the run behind the facade: a dig (pile scenarios), the paper's loading cycle on a pile, or the
// machine alone on flat ground, each stepped through the same loop as `talus run` (digging/
// digging.hpp, sim2real's replay) or `talus sweep` (digging/feedback_sweep.hpp)
struct Simulation::Impl {
  vehicle::Scenario scenario;
  FidelityPreset preset;
  // the model extensions (the options' effects; empty: the identity). Declared before the runs
  // that hold them, so it outlives them
  std::unique_ptr<vehicle::LoadedEffects> effects;
  // a pile: the device and either the coupled dig on it or the loading cycle around such a dig
  std::unique_ptr<Device> device;
  std::unique_ptr<DiggingSimulation> replay;
  std::unique_ptr<LoadingCycle> cycle;
  double cycle_s = 0.0;
  // the machine alone: its own steps and the 100 Hz log
  std::unique_ptr<vehicle::WheelLoader> loader;
  vehicle::SensorLog log{100.0};
  vehicle::SensorSample sensors;
  double time = 0.0;
  long steps_done = 0;
  bool pile_from_cache = false;
  // what a saved state must have been made from (state_key, with the particle count)
  std::string state_key;

  // the dig now, whichever owns it (nullptr for the machine alone)
  const DiggingSimulation* dig() const {
    if (cycle) return &cycle->simulation();
    return replay.get();
  }

  void step(const Targets& targets) {
    if (cycle) {
      cycle->step_fill({targets.drive, targets.lift, targets.tilt});
      return;
    }
    if (replay) {
      replay->step(targets.drive, targets.lift, targets.tilt);
      return;
    }
    // the clock counts steps, as the run loop's does, so every run samples the same instants
    const double h = scenario.timestep;
    const double t_end = static_cast<double>(steps_done + 1) * h;
    sensors = vehicle::step_with_effects(
        *loader, effects->set, time, h, t_end, {targets.drive, targets.lift, targets.tilt},
        [&] { loader->step(h); }, &log);
    ++steps_done;
    time = t_end;
  }
  // the state between steps as a payload (digging/saved_state.hpp has the envelope)
  std::string save() const {
    ByteWriter w;
    if (cycle) {
      cycle->save_state(w);
    } else if (replay) {
      replay->save_state(w);
    } else {
      // the machine alone: the clock, the readings and the log, the machine
      w.tag("vehicle");
      w.f64(time);
      w.i64(steps_done);
      vehicle::write_sample(w, sensors);
      log.save_state(w);
      loader->system().save_state(w);
      w.tag("effects");
      effects->set.save_state(w);
      w.tag("end");
    }
    return std::move(w.bytes());
  }
  // a payload read into the run (the parts write into themselves as they read)
  void read_payload(const std::string& payload, const std::string& where) {
    ByteReader r = payload_reader(payload, where);
    if (cycle) {
      cycle->restore_state(r);
    } else if (replay) {
      replay->restore_state(r);
    } else {
      r.expect("vehicle");
      const double t = r.f64("clock");
      const std::int64_t steps = r.i64("clock");
      if (steps < 0) throw InputError(where + ": a negative step count (corrupt)");
      sensors = vehicle::read_sample(r, "sensors");
      log.restore_state(r);
      loader->system().restore_state(r);
      r.expect("effects");
      effects->set.restore_state(r);
      r.expect("end");
      time = t;
      steps_done = static_cast<long>(steps);
    }
    if (r.left() != 0)
      throw InputError(where + ": " + std::to_string(r.left()) +
                       " bytes after the state (corrupt)");
  }
  // a state's bytes (seal_state's) restored. The envelope and the key are checked before anything
  // changes; a payload that passes them and still fails (a file of another build whose layout
  // changed without a new format version) is undone from a copy of the state taken first, so a
  // bad file never leaves the run half-restored
  void restore(const std::string& bytes, const std::string& where) {
    std::string payload;
    const SavedStateHeader header = open_state(bytes, where, &payload);
    if (header.key != state_key)
      throw InputError(
          where + " was saved from another simulation: " + key_difference(header.key, state_key) +
          "; make the Simulation with the options it was saved from");
    const std::string before = save();
    try {
      read_payload(payload, where);
    } catch (...) {
      read_payload(before, "the state before " + where);
      throw;
    }
  }
  double now() const { return dig() ? dig()->time() : time; }
  const vehicle::SensorSample& reading() const { return dig() ? dig()->sensors() : sensors; }
  const vehicle::SensorLog& sensor_log() const { return dig() ? dig()->log() : log; }
};

namespace {
// the loading cycle's options, InputError naming the option
void check_cycle_options(const SimulationOptions& options, const vehicle::Scenario& scenario) {
  if (!scenario.pile)
    throw InputError("SimulationOptions::loading_cycle: scenario '" + options.scenario +
                     "' has no pile; the loading cycle digs in one: give fb35, hd27 or rd21");
  if (!(options.cycle_approach > 0.0 && options.cycle_approach <= 100.0))
    throw InputError(
        "SimulationOptions::cycle_approach: " + std::to_string(options.cycle_approach) +
        " m; give the distance to the pile in (0, 100] m (the paper's is 5 m)");
  if (!(options.cycle_max_time > 0.0 && options.cycle_max_time <= 3600.0))
    throw InputError(
        "SimulationOptions::cycle_max_time: " + std::to_string(options.cycle_max_time) +
        " s; give the cycle's time limit in (0, 3600] s");
  if (!(options.cycle_s >= 0.0 && options.cycle_s <= 1.0))
    throw InputError("SimulationOptions::cycle_s: " + std::to_string(options.cycle_s) +
                     "; give the point on the controller's search line in [0, 1]");
}
}  // namespace

Simulation::Simulation(const SimulationOptions& options) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.scenario = load_options_scenario(options);
  // the level is checked for every scenario, though only a pile uses it (as talus run does)
  m.preset = options_level(options);
  m.state_key = state_key(options, m.scenario, m.preset);
  if (options.loading_cycle) check_cycle_options(options, m.scenario);
  m.effects = vehicle::load_effects(options.effects, options.effect_plugins, m.scenario,
                                    "SimulationOptions::effects");
  if (m.scenario.pile) {
    // the pile built and settled at the level, then the machine settled in front of it
    DiggingOptions dig_options;
    dig_options.pile.seed = options.seed;
    // the cache's lines (a hit, a miss it fills, a folder it cannot write) go to stderr
    dig_options.pile_cache.enabled = options.pile_cache;
    dig_options.pile_cache.note = [](const std::string& line) {
      std::cerr << "talus: " << line << "\n";
    };
    m.device = std::make_unique<Device>(device_choice_for(m.preset));
    Progress progress("pile " + m.preset.name, 1.5 * dig_options.pile.max_time, options.progress);
    if (options.loading_cycle) {
      // the cycle's pile, placed and scanned as `talus sweep` does
      const CyclePile pile =
          build_cycle_pile(*m.device, m.scenario, options.cycle_approach, options.cycle_max_time,
                           m.preset, dig_options, &progress);
      progress.finish(std::to_string(pile.pile.particles.size()) + " particles");
      m.scenario = pile.scenario;
      m.pile_from_cache = pile.pile.from_cache;
      m.cycle_s = options.cycle_s;
      m.cycle = std::make_unique<LoadingCycle>(*m.device, pile, m.preset, dig_options,
                                               vehicle::gains_on_search_line(options.cycle_s),
                                               &m.effects->set);
    } else {
      const PileProfile placed = scenario_pile_profile(m.scenario);
      const PileBuild pile =
          build_scenario_pile(*m.device, m.scenario, placed, m.preset, dig_options, &progress);
      progress.finish(std::to_string(pile.particles.size()) + " particles");
      m.pile_from_cache = pile.from_cache;
      m.replay = std::make_unique<DiggingSimulation>(*m.device, m.scenario, m.preset, pile,
                                                     dig_options, &m.effects->set);
    }
  } else {
    // the machine alone, with a payload it can hold on its wheels
    m.loader = std::make_unique<vehicle::WheelLoader>(vehicle::machine_file(m.scenario),
                                                      m.scenario.payload);
    vehicle::check_payload_holds(m.scenario, *m.loader);
    m.sensors = vehicle::start_with_effects(*m.loader, m.effects->set, m.log, m.scenario);
  }
  m.state_key += "particles=" + std::to_string(particle_count()) + "\n";
}

Simulation::~Simulation() = default;
Simulation::Simulation(Simulation&& other) noexcept = default;
Simulation& Simulation::operator=(Simulation&& other) noexcept = default;

void Simulation::step() {
  if (impl_->cycle) {
    impl_->cycle->step();
    return;
  }
  step(scenario_targets());
}

void Simulation::step(const Targets& targets) { impl_->step(targets); }

Targets Simulation::scenario_targets() const {
  const double t = impl_->now();
  if (impl_->cycle) {
    const LoadingCycle& c = *impl_->cycle;
    const vehicle::CycleTargets own =
        c.cycle().targets(vehicle::read_sensors(c.simulation().loader(), t));
    return {own.drive, own.lift, own.tilt};
  }
  const vehicle::Scenario& sc = impl_->scenario;
  return {sc.drive(t), sc.lift(t), sc.tilt(t)};
}

Targets Simulation::top_speeds() const {
  const vehicle::WheelLoader& loader = impl_->dig() ? impl_->dig()->loader() : *impl_->loader;
  return {loader.top_speed(), loader.lift_spec().max_speed, loader.tilt_spec().max_speed};
}

double Simulation::time() const { return impl_->now(); }

double Simulation::timestep() const {
  return impl_->dig() ? impl_->preset.dt : impl_->scenario.timestep;
}

double Simulation::duration() const { return impl_->scenario.duration; }

bool Simulation::done() const {
  if (impl_->cycle) return impl_->cycle->done();
  if (impl_->replay) return impl_->replay->done();
  // the step count the run loop takes (talus run), so done() agrees with it
  return impl_->steps_done >= std::llround(impl_->scenario.duration / impl_->scenario.timestep);
}

std::string Simulation::cycle_phase() const {
  return impl_->cycle ? vehicle::phase_name(impl_->cycle->phase()) : std::string();
}

CycleSummary Simulation::cycle_summary() const {
  if (!impl_->cycle)
    throw Error("Simulation::cycle_summary: this run replays scenario '" + impl_->scenario.name +
                "'; set SimulationOptions::loading_cycle for the paper's loading cycle");
  const CycleResult r = impl_->cycle->result(impl_->cycle_s);
  CycleSummary c;
  c.loaded_mass = r.loaded_mass_kg;
  c.cycle_time = r.cycle_time_s;
  c.work = r.work_J;
  c.completed = r.completed;
  c.broke_out = impl_->cycle->cycle().broke_out();
  c.fill_start = r.fill_start_s;
  c.fill_end = r.breakout_s;
  return c;
}

double Simulation::work() const { return impl_->sensor_log().work(); }

SensorReading Simulation::sensors() const { return to_reading(impl_->reading()); }

std::map<std::string, double> Simulation::channels() const {
  const vehicle::SensorSample& s = impl_->reading();
  std::map<std::string, double> values;
  for (const vehicle::SensorChannel& c : vehicle::kSensorChannels) values[c.name] = s.*c.field;
  return values;
}

std::vector<SensorReading> Simulation::sensor_log() const {
  const std::vector<vehicle::SensorSample>& samples = impl_->sensor_log().samples();
  std::vector<SensorReading> readings;
  readings.reserve(samples.size());
  for (const vehicle::SensorSample& s : samples) readings.push_back(to_reading(s));
  return readings;
}

const std::vector<std::string>& Simulation::channel_names() {
  static const std::vector<std::string> names(vehicle::kChannelNames.begin(),
                                              vehicle::kChannelNames.end());
  return names;
}

const std::vector<std::string>& Simulation::channel_units() {
  static const std::vector<std::string> units = [] {
    std::vector<std::string> u;
    u.reserve(vehicle::kChannelCount);
    for (const vehicle::SensorChannel& c : vehicle::kSensorChannels) u.emplace_back(c.unit);
    return u;
  }();
  return units;
}

bool Simulation::pile_from_cache() const { return impl_->pile_from_cache; }

double Simulation::loaded_mass() const {
  return impl_->dig() ? impl_->dig()->loaded_mass() : impl_->scenario.payload;
}

bool Simulation::has_particles() const { return impl_->dig() != nullptr; }

std::size_t Simulation::particle_count() const {
  return impl_->dig() ? impl_->dig()->particle_count() : 0;
}

ParticleState Simulation::particles() const {
  ParticleState state;
  if (!impl_->dig()) return state;
  const Particles p = impl_->dig()->particles();
  const std::size_t n = p.size();
  state.position.reserve(3 * n);
  state.velocity.reserve(3 * n);
  state.angular_velocity.reserve(3 * n);
  state.radius = p.radius;
  for (std::size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) {
      state.position.push_back(p.position[i][k]);
      state.velocity.push_back(p.velocity[i][k]);
      state.angular_velocity.push_back(p.omega[i][k]);
    }
  }
  return state;
}

SoilMass Simulation::soil_mass() const {
  SoilMass m;
  const DiggingSimulation* dig = impl_->dig();
  if (!dig) return m;
  if (dig->multiscale()) {
    const MassBalance b = dig->terrain().mass_balance();
    m.solid = b.solid;
    m.pool = b.pool;
    m.particles = b.particles;
    return m;
  }
  const Particles p = dig->particles();
  for (std::size_t i = 0; i < p.size(); ++i) m.particles += p.mass(i);
  return m;
}

std::string Simulation::state() const {
  SavedStateHeader header;
  header.key = impl_->state_key;
  header.commit = git_commit();
  header.device = device();
  return seal_state(header, impl_->save());
}

void Simulation::set_state(const std::string& bytes) {
  impl_->restore(bytes, "the state given to Simulation::set_state");
}

void Simulation::save_state(const std::string& path) const { write_file_atomically(path, state()); }

void Simulation::restore_state(const std::string& path) {
  impl_->restore(read_file_bytes(path, "a saved simulation state"), path);
}

std::string Simulation::scenario_name() const { return impl_->scenario.name; }

std::string Simulation::level() const { return impl_->dig() ? impl_->preset.name : "vehicle"; }

std::string Simulation::device() const {
  return impl_->device ? impl_->device->description() : std::string();
}

}  // namespace talus
