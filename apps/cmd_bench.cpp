// talus bench dem: DEM throughput per fidelity level on the default pile, and the 10k settling
// case that LIGGGHTS and Bullet were run on (shared/peers). Medians over several steps.
// talus bench dig: the cost of the coupled step of a scenario's dig, stage by stage
// (digging/dig_cost.hpp).
#include <algorithm>
#include <chrono>
#include <iostream>
#include <sstream>

#include "apps/commands.hpp"
#include "digging/dig_cost.hpp"
#include "host/device.hpp"
#include "host/files.hpp"
#include "io/plot.hpp"
#include "terrain/pile.hpp"
#include "terrain/scenes.hpp"
#include "terrain/settle.hpp"

namespace talus::app {

namespace {

// --one-group-rows of both benchmarks: the threshold is a device's speed question (with colours
// the same bits; a CPU device walks such a system in one work-item, see --serial-lanes, and a
// larger one in runs, see --sweep-parts)
const char* const kOneGroupRowsHelp =
    "PGS sweeps systems of at most this many rows in one work-group, larger ones a launch per "
    "colour or, on a CPU device, in runs (0: never)";
const char* const kSerialLanesHelp =
    "on a CPU device a system the one work-group sweeps is walked by one work-item without "
    "colours, its rows interleaved from this many blocks of contacts (0: coloured as on a GPU); "
    "the timed world's, not the pile's it is built from";

const char* const kSweepPartsHelp =
    "on a CPU device a larger system is cut into this many parts by particle index, walked side "
    "by side by a work-item each, then the contacts across them level by level (0: one per "
    "compute unit)";

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  for (std::string item; std::getline(ss, item, sep);)
    if (!item.empty()) out.push_back(item);
  return out;
}

// the sweeps' study flags of bench dem and bench dig (DemSettings: one_group_rows, pair_reach,
// relaxation), registered, applied and reported in one place
struct SolverStudy {
  int one_group_rows = kPgsOneGroupRows;
  int serial_lanes = kSerialLanes;
  int sweep_parts = 0;
  // the reach's default is the command's: bench dig digs (DiggingOptions), bench dem settles a bed
  // (DemSettings, as the piles are)
  bool pair_reach;
  double relaxation = 1.0;

  explicit SolverStudy(bool default_pair_reach) : pair_reach(default_pair_reach) {}

  void add_flags(CLI::App& cmd) {
    cmd.add_option("--one-group-rows", one_group_rows, kOneGroupRowsHelp)
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
    cmd.add_option("--serial-lanes", serial_lanes, kSerialLanesHelp)
        ->check(CLI::Range(0, kMaxSerialLanes))
        ->capture_default_str();
    cmd.add_option("--sweep-parts", sweep_parts, kSweepPartsHelp)
        ->check(CLI::Range(0, kMaxSweepParts))
        ->capture_default_str();
    add_reach_option(cmd, pair_reach);
    cmd.add_option("--relaxation", relaxation, kRelaxationHelp)
        ->check(relaxation_number())
        ->capture_default_str();
  }
  void apply(DemSettings& s) const {
    s.one_group_rows = one_group_rows;
    s.serial_lanes = serial_lanes;
    s.sweep_parts = sweep_parts;
    s.pair_reach = pair_reach;
    s.relaxation = relaxation;
  }
  void apply(DiggingOptions& o) const {
    o.one_group_rows = one_group_rows;
    o.serial_lanes = serial_lanes;
    o.sweep_parts = sweep_parts;
    o.pair_reach = pair_reach;
    o.relaxation = relaxation;
  }
  template <class Json>
  void describe(Json& j) const {
    j["one_group_rows"] = one_group_rows;
    j["serial_lanes"] = serial_lanes;
    j["sweep_parts"] = sweep_parts;
    j["pair_reach"] = pair_reach;
    j["relaxation"] = relaxation;
  }
};

// the default pile at a level, settled briefly, then timed with the preset's dt and N_it
nlohmann::json bench_level(Device& dev, const FidelityPreset& preset, int steps,
                           const SolverStudy& study, bool quiet) {
  PileBuildOptions build;
  build.min_time = 0.5;
  build.max_time = 1.0;
  // a bed to time, not a pile to dig: the formwork goes at once and the bed settles free, as in
  // every benchmark before the held face became the default pile (bench/RESULTS.md stays
  // comparable)
  build.form_speed = 0.0;
  build.hold_face = false;
  Progress progress("bench " + preset.name + " (settling)", build.max_time, !quiet);
  PileBuild pile = build_pile(dev, default_pile_profile(), preset, gravel(), build, &progress);
  progress.finish();
  DemSettings settings;
  settings.dt = preset.dt;
  settings.iterations = preset.iterations;
  study.apply(settings);
  DemWorld world(dev, gravel(), settings, pile.bounds, pile.geoms);
  world.set_particles(pile.particles);
  world.step();  // contacts exist from here on, warm start as in a run
  std::vector<double> step_s, sweep_s, contacts, boundary;
  for (int i = 0; i < steps; ++i) {
    auto t0 = std::chrono::steady_clock::now();
    world.step();
    dev.finish();
    step_s.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    sweep_s.push_back(world.stats().sweep_seconds);
    contacts.push_back(world.stats().contacts);
    boundary.push_back(world.stats().boundary_rows / std::max(1.0, 1.0 * world.stats().contacts));
  }
  double ms = 1e3 * median(step_s);
  double n_contacts = median(contacts);
  nlohmann::json j = {{"level", preset.name},
                      {"particles", world.size()},
                      {"contacts", n_contacts},
                      {"colours", world.stats().colours},
                      {"boundary_share", median(boundary)},
                      {"iterations", preset.iterations},
                      {"dt_s", preset.dt},
                      {"steps_timed", steps},
                      {"ms_per_step", ms},
                      {"ms_sweeps_per_step", 1e3 * median(sweep_s)},
                      {"contact_updates_per_s", n_contacts * preset.iterations / median(sweep_s)},
                      {"realtime_factor", preset.dt / median(step_s)}};
  // the last step's runs (a CPU device's layout of a large system): each part's rows, the
  // boundary's last; the slowest part sets a sweep's time
  if (world.buffers().row_layout == RowLayout::Runs) {
    j["sweep_parts_used"] = world.buffers().run_parts;
    const std::vector<int>& start = world.buffers().colour_start;
    std::vector<int> rows;
    for (size_t k = 0; k + 1 < start.size(); ++k) rows.push_back(start[k + 1] - start[k]);
    j["run_rows"] = rows;
  }
  study.describe(j);
  return j;
}

nlohmann::json bench_settle10k(Device& dev, double dt, int iterations, unsigned seed,
                               const SolverStudy& study, bool quiet) {
  Scene scene = settle10k_scene(seed);
  if (dt > 0) scene.settings.dt = dt;
  if (iterations > 0) scene.settings.iterations = iterations;
  study.apply(scene.settings);
  DemWorld world(dev, scene.material, scene.settings, scene.bounds, scene.geoms);
  world.set_particles(scene.particles);
  const double sim_time = 0.5;  // [s], as the peers
  int steps = std::max(1, static_cast<int>(std::lround(sim_time / scene.settings.dt)));
  Progress progress("bench settle10k", sim_time, !quiet);
  std::vector<double> sweep_s, contacts;
  int colouring_kept = 0;
  auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < steps; ++i) {
    world.step();
    sweep_s.push_back(world.stats().sweep_seconds);
    contacts.push_back(world.stats().contacts);
    colouring_kept += world.stats().colouring_kept ? 1 : 0;
    progress.update(world.time());
  }
  dev.finish();
  double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  progress.finish();
  Particles p = world.particles();
  // bed height: the 99th percentile of particle tops (robust to a few rattlers)
  std::vector<double> tops;
  for (size_t i = 0; i < p.size(); ++i) tops.push_back(p.position[i].z() + p.radius[i]);
  std::sort(tops.begin(), tops.end());
  double d = 2.0 * p.radius[0];
  nlohmann::json j = {
      {"level", "settle10k"},
      {"particles", p.size()},
      {"contacts", contacts.back()},
      {"iterations", scene.settings.iterations},
      {"dt_s", scene.settings.dt},
      {"seed", seed},
      {"steps", steps},
      {"colouring_kept_steps", colouring_kept},
      {"sim_time_s", sim_time},
      {"wall_s", wall},
      {"wall_s_per_sim_s", wall / sim_time},
      {"ms_per_step", 1e3 * wall / steps},
      {"contact_updates_per_s", median(contacts) * scene.settings.iterations / median(sweep_s)},
      {"bed_height_m", tops[static_cast<size_t>(0.99 * (tops.size() - 1))]},
      {"max_overlap_rel", max_overlap(p, scene.geoms) / d},
      {"rms_speed_m_s", rms_speed(p)}};
  study.describe(j);
  return j;
}

// the stages keep the order they ran in (an ordered object)
nlohmann::ordered_json dig_cost_json(const DigCost& c, const std::string& device) {
  nlohmann::ordered_json stages = nlohmann::ordered_json::object();
  for (const auto& [name, ms] : c.stages) stages[name] = ms;
  return {{"device", device},
          {"scenario", c.scenario},
          {"level", c.level},
          {"particles", c.particles},
          {"dt_s", c.dt},
          {"iterations", c.iterations},
          {"seconds", c.seconds},
          {"steps", c.steps},
          {"ms_per_step", c.ms_per_step},
          {"profiled_ms_per_step", c.profiled_ms_per_step},
          {"realtime_factor", c.realtime_factor},
          {"stages", stages},
          {"contacts", c.contacts},
          {"boundary_rows", c.boundary_rows},
          {"sweep_parts_used", c.sweep_parts_used},
          {"bucket_contacts", c.bucket_contacts},
          {"passes", c.passes},
          {"sweeps", c.sweeps},
          {"sweep_tolerance_m_s", c.sweep_tolerance},
          {"loaded_mass_kg", c.loaded_mass_kg}};
}

// the cost of a scenario's coupled dig at one level
void add_bench_dig(CLI::App& bench) {
  struct Options {
    std::string scenario = "hd27";
    std::string level = "D400";
    double seconds = 1.0;
    std::string json;
    unsigned seed = 1;
    bool quiet = false;
    bool pile_cache = true;  // the pile through the pile cache (--no-pile-cache)
    double sweep_tolerance = kDigSweepTolerance;  // [m/s] DiggingOptions::sweep_tolerance
    SolverStudy study{DiggingOptions{}.pair_reach};
    std::string bucket_sweep = "serial";  // CouplingSettings::bucket_sweep
  };
  auto opt = std::make_shared<Options>();
  auto* dig = bench.add_subcommand("dig",
                                   "cost of the coupled dig per step, stage by stage: digs SECONDS "
                                   "from the scenario's dig_start");
  dig->add_option("--scenario", opt->scenario,
                  "scenario with a pile (data/scenarios/NAME.json or a path)")
      ->capture_default_str();
  dig->add_option("--level", opt->level,
                  "fidelity level: particles D400, D200, D100, D50, or the multiscale terrain "
                  "G400, G200, G100, G50")
      ->capture_default_str();
  // a dig from its start: the scenarios dig for 5-15 s, the soak for ten minutes
  dig->add_option("--seconds", opt->seconds, "simulated seconds measured from dig_start [s]")
      ->check(number_in(0.01, 600.0, "s"))
      ->capture_default_str();
  dig->add_option("--seed", opt->seed, "seed of the pile's particles")->capture_default_str();
  dig->add_option("--json", opt->json, "also write the result as JSON to this file");
  dig->add_option("--sweep-tolerance", opt->sweep_tolerance,
                  "end a step's sweeps once the particle rows' RMS residual is below this, the "
                  "level's sweeps the cap; 0 = always the level's, as the paper's presets "
                  "(docs/dem.md); a D level's (a G level's zone always runs its level's) [m/s]")
      ->check(number_in(0.0, 1.0, "m/s", true))
      ->capture_default_str();
  opt->study.add_flags(*dig);
  dig->add_option("--bucket-sweep", opt->bucket_sweep, kBucketSweepHelp)->capture_default_str();
  dig->add_flag("--quiet", opt->quiet, "no progress on stderr");
  dig->add_flag(
      "!--no-pile-cache", opt->pile_cache,
      "build the pile even when the pile cache holds it, and do not save it (docs/embedding.md)");
  dig->callback([opt] {
    // inputs and the output path are checked before the pile is built
    const vehicle::Scenario scenario = vehicle::load_scenario(opt->scenario);
    if (!scenario.pile)
      throw InputError(scenario.path + ": scenario '" + scenario.name +
                       "' has no pile; talus bench dig needs one (fb35, hd27, rd21)");
    // a type-D pile, or a type-G terrain built from the pile's profile (issue 14)
    const FidelityPreset& preset = level_preset(opt->level);
    check_dig_seconds(scenario, opt->seconds);
    const BucketSweep bucket_sweep = parse_bucket_sweep(opt->bucket_sweep, "--bucket-sweep");
    check_bucket_sweep(bucket_sweep, preset, "--bucket-sweep");
    check_sweep_tolerance(opt->sweep_tolerance, preset, "--sweep-tolerance");
    if (!opt->json.empty()) check_writable(opt->json, "--json");
    Device dev(run_device_choice(preset));
    DiggingOptions options;
    options.pile.seed = opt->seed;
    options.sweep_tolerance = opt->sweep_tolerance;
    opt->study.apply(options);
    options.coupling.bucket_sweep = bucket_sweep;
    options.pile_cache.enabled = opt->pile_cache;
    options.pile_cache.note = [](const std::string& line) {
      std::cerr << "talus bench dig: " << line << "\n";
    };
    PileBuild pile;
    {
      Progress progress("pile " + preset.name, 1.5 * options.pile.max_time, !opt->quiet);
      pile = build_scenario_pile(dev, scenario, scenario_pile_profile(scenario), preset, options,
                                 &progress);
      progress.finish(std::to_string(pile.particles.size()) + " particles");
    }
    Progress progress("bench dig " + scenario.name + " " + preset.name,
                      scenario.dig_start + opt->seconds, !opt->quiet);
    const DigCost cost =
        measure_dig_cost(dev, scenario, preset, pile, options, opt->seconds, &progress);
    progress.finish();
    nlohmann::ordered_json j = dig_cost_json(cost, dev.description());
    opt->study.describe(j);
    j["bucket_sweep"] = bucket_sweep_name(bucket_sweep);
    if (!opt->json.empty()) write_file_atomically(opt->json, j.dump(2) + "\n");
    std::cout << j.dump(2) << "\n";
  });
}

// the legend's name of a device from `talus bench dem`'s "device" string: the device's own name
// without the platform and the sizes ("NVIDIA CUDA / NVIDIA H100 80GB HBM3 (132 compute units,
// ...)" -> "NVIDIA H100 80GB HBM3")
std::string device_label(const std::string& description) {
  std::string name = description;
  if (auto slash = name.find(" / "); slash != std::string::npos) name = name.substr(slash + 3);
  if (auto paren = name.find(" ("); paren != std::string::npos) name = name.substr(0, paren);
  return name;
}

// the levels of one `talus bench dem --json` file as points of the throughput figure (the 10k
// settling case has no level and is left out); InputError naming the file and the field
std::vector<ThroughputPoint> throughput_points(const std::string& path, const std::string& label) {
  const nlohmann::json j = read_json_file(path, "a `talus bench dem --json` result to plot");
  const std::string fix = "; plot a file written by `talus bench dem --json`";
  if (!j.is_object() || !j.contains("results") || !j.at("results").is_array())
    throw InputError(path + ": no 'results' array" + fix);
  std::string device = label;
  if (device.empty())
    device = j.contains("device") && j.at("device").is_string()
                 ? device_label(j.at("device").get<std::string>())
                 : path;
  std::vector<ThroughputPoint> points;
  for (size_t k = 0; k < j.at("results").size(); ++k) {
    const nlohmann::json& r = j.at("results")[k];
    const std::string where = path + ": results[" + std::to_string(k) + "]";
    if (!r.is_object() || !r.contains("level") || !r.at("level").is_string())
      throw InputError(where + ": no 'level' name" + fix);
    const std::string level = r.at("level").get<std::string>();
    if (level == "settle10k") continue;
    const FidelityPreset& preset = fidelity_preset(level);
    auto positive = [&](const char* key) {
      if (!r.contains(key) || !r.at(key).is_number() || !(r.at(key).get<double>() > 0.0))
        throw InputError(where + " (" + level + "): '" + key + "' must be a positive number" + fix);
      return r.at(key).get<double>();
    };
    points.push_back({level, 1e3 * preset.diameter, positive("contact_updates_per_s"),
                      positive("realtime_factor"), device});
  }
  if (points.empty())
    throw InputError(path + ": no level to plot (only the 10k settling case)" + fix);
  return points;
}

// talus bench plot: the throughput figure of one or more devices from their JSON files
void add_bench_plot(CLI::App& bench) {
  struct Options {
    std::vector<std::string> files;
    std::vector<std::string> labels;
    std::string out;
  };
  auto opt = std::make_shared<Options>();
  auto* plot = bench.add_subcommand("plot",
                                    "draw the throughput figure of one or more `talus bench dem "
                                    "--json` files, one line per file (device)");
  plot->add_option("files", opt->files, "`talus bench dem --json` result files")
      ->required()
      ->check(CLI::ExistingFile);
  plot->add_option("--labels", opt->labels,
                   "the legend's name of each file, in order (default: its device)")
      ->delimiter(',');
  plot->add_option("--out", opt->out, "the figure (PNG)")->required();
  plot->callback([opt] {
    if (!opt->labels.empty() && opt->labels.size() != opt->files.size())
      throw InputError("--labels: " + std::to_string(opt->labels.size()) + " names for " +
                       std::to_string(opt->files.size()) +
                       " files; give one per file, comma-separated, or none");
    check_writable(opt->out, "--out");
    std::vector<ThroughputPoint> points;
    for (size_t k = 0; k < opt->files.size(); ++k) {
      auto more = throughput_points(opt->files[k], opt->labels.empty() ? "" : opt->labels[k]);
      points.insert(points.end(), more.begin(), more.end());
    }
    throughput_figure(points).write_png(opt->out, kFigureWidth, kFigureHeight);
  });
}

}  // namespace

void add_bench_command(CLI::App& app) {
  struct Options {
    std::string levels = "D400,D200,D100";
    std::string json;
    std::string plot;
    int steps = 5;
    bool no_settle10k = false;
    double settle_dt = 0.0;      // 0: the scene's own (terrain/scenes.cpp)
    int settle_iterations = 0;
    unsigned settle_seed = LatticeBox{}.seed;
    SolverStudy study{DemSettings{}.pair_reach};
    bool quiet = false;
  };
  auto opt = std::make_shared<Options>();
  auto* bench = app.add_subcommand("bench", "throughput benchmarks");
  auto* dem = bench->add_subcommand("dem", "DEM throughput per fidelity level and the 10k settling case");
  bench->require_subcommand(1);
  add_bench_dig(*bench);
  add_bench_plot(*bench);
  dem->add_option("--levels", opt->levels, "comma-separated levels (D400,D200,D100,D50)")->capture_default_str();
  dem->add_option("--json", opt->json, "write the results as JSON to this file");
  dem->add_option(
      "--plot", opt->plot,
      "draw contact updates per second and real-time factor against particle size (PNG)");
  dem->add_option("--steps", opt->steps, "timed steps per level (median reported)")->check(CLI::Range(1, 1000));
  dem->add_flag("--no-settle10k", opt->no_settle10k, "skip the 10k settling case");
  dem->add_option("--settle-dt", opt->settle_dt,
                  "timestep of the 10k settling case [s] (default: the scene's, " +
                      (std::ostringstream() << kSettle10kDt).str() + " s)")
      ->check(number_in(kMinTimestep, kMaxTimestep, "s"));
  dem->add_option("--settle-iterations", opt->settle_iterations,
                  "PGS sweeps of the 10k settling case (default: the scene's, " +
                      std::to_string(kSettle10kSweeps) + ")")
      ->check(CLI::Range(1, 100000));
  dem->add_option("--settle-seed", opt->settle_seed,
                  "seed of the 10k settling case's lattice jitter (default: the peers' inputs')")
      ->capture_default_str();
  opt->study.add_flags(*dem);
  dem->add_flag("--quiet", opt->quiet, "no progress on stderr");
  dem->callback([opt] {
    std::vector<const FidelityPreset*> presets;
    for (auto& name : split(opt->levels, ',')) presets.push_back(&fidelity_preset(name));
    if (!opt->json.empty()) check_writable(opt->json, "--json");
    if (!opt->plot.empty()) check_writable(opt->plot, "--plot");
    Device dev;
    nlohmann::json results = nlohmann::json::array();
    for (auto* preset : presets)
      results.push_back(bench_level(dev, *preset, opt->steps, opt->study, opt->quiet));
    if (!opt->no_settle10k)
      results.push_back(bench_settle10k(dev, opt->settle_dt, opt->settle_iterations,
                                        opt->settle_seed, opt->study, opt->quiet));
    nlohmann::json j = {{"device", dev.description()}, {"results", results}};
    if (!opt->json.empty()) write_json(opt->json, j);
    if (!opt->plot.empty()) {
      // the levels (not the 10k settling case) against their particle size
      std::vector<ThroughputPoint> points;
      for (size_t k = 0; k < presets.size(); ++k)
        points.push_back({presets[k]->name, 1e3 * presets[k]->diameter,
                          results[k].at("contact_updates_per_s").get<double>(),
                          results[k].at("realtime_factor").get<double>(),
                          device_label(dev.description())});
      throughput_figure(points).write_png(opt->plot, kFigureWidth, kFigureHeight);
    }
    std::cout << j.dump(2) << "\n";
  });
}

}  // namespace talus::app
