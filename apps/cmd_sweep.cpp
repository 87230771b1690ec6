// `talus sweep --scenario fb35 --fidelity D200[,D100] --samples 50 --out DIR`: the force-feedback
// loading cycle (SPEC §5, paper §7) at evenly spaced points s of the controller's search line, at
// one or more fidelity levels; loaded mass M, cycle time T, work W, productivity M/T and efficiency
// M/W against s as CSV and PNG, and with two levels the domain gap, shift and performance drop.
//
// The cycles are independent, so they scale out through MPI (Open MPI from Debian): under
// `mpirun -np N talus sweep ...` rank r runs the samples i with i mod N = r and rank 0 collects
// them. For a cluster without a shared MPI job, `--shard K/N` runs one share and writes
// DIR/LEVEL/shard-K.csv, and `--collect` merges the shards into the results
// (scripts/sweep-slurm.sh does both as a Slurm job array).
#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "apps/commands.hpp"
#include "apps/outputs.hpp"
#include "digging/feedback_sweep.hpp"
#include "host/error.hpp"
#include "host/files.hpp"
#include "host/progress.hpp"
#include "io/plot.hpp"
#include "vehicle/data_file.hpp"
#include "vehicle/scenario.hpp"

namespace talus::app {

namespace {

// the figure's size [px]
constexpr int kFigureWidth = 1200, kFigureHeight = 1400;
// the values of one sample travelling between ranks, in this order
constexpr int kFields = 7;

struct SweepOptions {
  std::string command_line;  // as typed, recorded in summary.json with the version and commit
  std::string scenario = "fb35";
  std::vector<std::string> fidelities = {"D200"};
  int samples = 50;
  std::string out;
  std::string shard;  // "K/N"
  bool collect = false;
  double approach = 5.0;    // m, paper §7.1
  double max_time = 40.0;   // s per cycle
  unsigned seed = 1;
  bool quiet = false;
  bool traces = false;  // each cycle's time series as LEVEL/cycle-I.csv
  bool pile_cache = true;  // piles through the pile cache (--no-pile-cache)
  std::string json;
};

// MPI for the whole command: initialised once, finalised on every way out
class MpiSession {
 public:
  MpiSession() {
    int ready = 0;
    MPI_Initialized(&ready);
    if (!ready) MPI_Init(nullptr, nullptr);
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
  }
  ~MpiSession() {
    int done = 0;
    MPI_Finalized(&done);
    if (!done) MPI_Finalize();
  }
  int rank() const { return rank_; }
  int size() const { return size_; }

 private:
  int rank_ = 0, size_ = 1;
};

double sample_s(int i, int samples) { return samples > 1 ? double(i) / (samples - 1) : 0.0; }

// full double precision (17 digits), so shards merged by --collect equal a single run's results
std::string results_csv(const std::vector<CycleResult>& results) {
  std::ostringstream s;
  s << std::setprecision(17)
    << "s,loaded_mass_kg,cycle_time_s,work_J,productivity_kg_s,efficiency_kg_per_kJ,completed,fill_start_s,"
       "breakout_s\n";
  for (const auto& r : results)
    s << r.s << ',' << r.loaded_mass_kg << ',' << r.cycle_time_s << ',' << r.work_J << ',' << r.productivity() << ','
      << 1e3 * r.efficiency() << ',' << (r.completed ? 1 : 0) << ',' << r.fill_start_s << ',' << r.breakout_s << '\n';
  return s.str();
}

std::vector<CycleResult> read_results_csv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot read this shard; run its --shard first");
  std::string line;
  std::getline(in, line);
  std::vector<CycleResult> out;
  for (int n = 2; std::getline(in, line); ++n) {
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream row(line);
    CycleResult r;
    double productivity = 0.0, efficiency = 0.0;
    int completed = 0;
    if (!(row >> r.s >> r.loaded_mass_kg >> r.cycle_time_s >> r.work_J >> productivity >> efficiency >> completed >>
          r.fill_start_s >> r.breakout_s))
      throw InputError(path + ": line " + std::to_string(n) + " is not nine numbers; rerun that shard");
    // each value what a cycle can give: a point of the search line, a load, times and work
    // (a hand-edited or damaged shard merged a negative mass into the results)
    const auto check = [&](const char* field, double v, double lo, double hi) {
      if (!(v >= lo && v <= hi))
        throw InputError(path + ": line " + std::to_string(n) + ": field '" + field + "' is " +
                         message_number(v) + ", outside " + message_number(lo) + "-" +
                         message_number(hi) + "; rerun that shard");
    };
    constexpr double kMost = 1e12;  // finite: no cycle's mass [kg], time [s] or work [J] nears it
    check("s", r.s, 0.0, 1.0);
    check("loaded_mass_kg", r.loaded_mass_kg, 0.0, kMost);
    check("cycle_time_s", r.cycle_time_s, 0.0, kMost);
    check("work_J", r.work_J, -kMost, kMost);
    check("completed", completed, 0.0, 1.0);
    check("fill_start_s", r.fill_start_s, -kMost, kMost);
    check("breakout_s", r.breakout_s, -kMost, kMost);
    r.completed = completed != 0;
    out.push_back(r);
  }
  return out;
}

// the pile for a level: built once per process, scanned, placed `approach` in front of the bucket
CyclePile build_level_pile(Device& dev, const SweepOptions& o, const FidelityPreset& preset,
                           const DiggingOptions& options, bool verbose) {
  Progress progress("pile " + preset.name, 1.5 * options.pile.max_time, verbose);
  CyclePile cycle = build_cycle_pile(dev, vehicle::load_scenario(o.scenario), o.approach,
                                     o.max_time, preset, options, &progress);
  progress.finish(std::to_string(cycle.pile.particles.size()) + " particles");
  return cycle;
}

// the samples this process runs: those with i mod count = index
std::vector<CycleResult> run_share(Device& dev, const SweepOptions& o, const FidelityPreset& preset, int index,
                                   int count, bool verbose) {
  DiggingOptions options;
  options.pile.seed = o.seed;
  // every rank reads the same saved pile; on a miss each builds it and saves it atomically
  options.pile_cache.enabled = o.pile_cache;
  options.pile_cache.note = [](const std::string& line) {
    std::cerr << "talus sweep: " << line << "\n";
  };
  const CyclePile cycle = build_level_pile(dev, o, preset, options, verbose);
  std::vector<CycleResult> results;
  for (int i = index; i < o.samples; i += count) {
    const double s = sample_s(i, o.samples);
    vehicle::SensorLog trace;
    results.push_back(
        run_feedback_cycle(dev, cycle, preset, options, s, o.traces ? &trace : nullptr));
    if (o.traces) {
      const auto path = std::filesystem::path(o.out) / preset.name / ("cycle-" + std::to_string(i) + ".csv");
      write_file_atomically(path.string(), vehicle::sensor_csv(trace.samples()));
    }
    const CycleResult& r = results.back();
    if (verbose)
      std::cerr << "  " << preset.name << " s = " << std::fixed << std::setprecision(3) << s << ": M "
                << std::setprecision(0) << r.loaded_mass_kg << " kg, T " << std::setprecision(1) << r.cycle_time_s
                << " s, W " << std::setprecision(0) << r.work_J / 1e3 << " kJ" << (r.completed ? "" : " (time limit)")
                << "\n";
  }
  return results;
}

// every rank's samples summed into rank 0 (each sample computed by exactly one rank)
std::vector<CycleResult> gather(const MpiSession& mpi, const std::vector<CycleResult>& mine, int samples) {
  std::vector<double> local(static_cast<size_t>(samples) * kFields, 0.0), all(local.size(), 0.0);
  for (size_t k = 0; k < mine.size(); ++k) {
    const int i = mpi.rank() + static_cast<int>(k) * mpi.size();
    const CycleResult& r = mine[k];
    const double v[kFields] = {r.s, r.loaded_mass_kg, r.cycle_time_s, r.work_J, r.completed ? 1.0 : 0.0,
                               r.fill_start_s, r.breakout_s};
    std::copy(v, v + kFields, local.begin() + static_cast<long>(i) * kFields);
  }
  MPI_Reduce(local.data(), all.data(), static_cast<int>(all.size()), MPI_DOUBLE, MPI_SUM, 0, MPI_COMM_WORLD);
  std::vector<CycleResult> out(samples);
  for (int i = 0; i < samples; ++i) {
    const double* v = all.data() + static_cast<long>(i) * kFields;
    out[i] = {v[0], v[1], v[2], v[3], v[4] != 0.0, v[5], v[6]};
  }
  return out;
}

// M, T, W, M/T and M/W against s, one line per level
void write_figure(const std::string& path, const std::vector<std::pair<std::string, std::vector<CycleResult>>>& levels) {
  Figure f;
  f.x_label = "search parameter s [-]";
  for (const char* label : {"loaded mass M [t]", "cycle time T [s]", "work W [kJ]", "productivity M/T [kg/s]",
                            "efficiency M/W [kg/kJ]"})
    f.add_panel(label);
  for (size_t l = 0; l < levels.size(); ++l) {
    std::vector<Series> series(5);
    for (auto& s : series) {
      s.colour = series_colour(l);
      s.markers = true;
      s.label = levels[l].first;
    }
    for (const CycleResult& r : levels[l].second) {
      if (!r.completed) continue;
      const double y[5] = {r.loaded_mass_kg / 1e3, r.cycle_time_s, r.work_J / 1e3, r.productivity(),
                           1e3 * r.efficiency()};
      for (int k = 0; k < 5; ++k) {
        series[k].x.push_back(r.s);
        series[k].y.push_back(y[k]);
      }
    }
    for (int k = 0; k < 5; ++k) f.panels[k].series.push_back(series[k]);
  }
  f.write_png(path, kFigureWidth, kFigureHeight);
}

// rank 0 (or --collect): the results per level, the figure, the summary
void report(const SweepOptions& o, const std::vector<std::pair<std::string, std::vector<CycleResult>>>& levels) {
  nlohmann::json summary = {{"scenario", o.scenario}, {"samples", o.samples}, {"levels", nlohmann::json::array()}};
  for (const auto& [name, results] : levels) {
    write_file_atomically((std::filesystem::path(o.out) / name / "sweep.csv").string(), results_csv(results));
    const SweepOptimum best = best_productivity(results);
    int completed = 0;
    for (const auto& r : results) completed += r.completed;
    summary["levels"].push_back({{"fidelity", name},
                                 {"completed", completed},
                                 {"best_productivity_kg_s", best.productivity},
                                 {"best_s", best.s}});
  }
  if (levels.size() >= 2) {
    // the first level is the one a controller is tuned in, the second where it is used
    const DomainTransfer d = domain_transfer(levels[0].second, levels[1].second);
    summary["domain_transfer"] = {{"from", levels[0].first},
                                  {"to", levels[1].first},
                                  {"domain_gap_kg_s", d.gap_kg_s},
                                  {"domain_gap_rel", d.gap_rel},
                                  {"domain_shift", d.shift},
                                  {"performance_drop_rel", d.drop_rel}};
  }
  write_figure((std::filesystem::path(o.out) / "sweep.png").string(), levels);
  add_provenance(summary, o.command_line);
  write_json((std::filesystem::path(o.out) / "summary.json").string(), summary);
  if (o.json == "-") std::cout << summary.dump(2) << "\n";
  else if (!o.json.empty()) write_json(o.json, summary);
  if (!o.quiet) std::cerr << "talus sweep: results in " << o.out << " (sweep.png, summary.json, LEVEL/sweep.csv)\n";
}

std::pair<int, int> parse_shard(const std::string& text) {
  int k = -1, n = -1;
  char slash = 0;
  std::istringstream in(text);
  if (!(in >> k >> slash >> n) || slash != '/' || n < 1 || k < 0 || k >= n || !in.eof())
    throw InputError("--shard: '" + text + "' is not K/N with 0 <= K < N (e.g. 3/10)");
  return {k, n};
}

void sweep(const SweepOptions& o) {
  if (o.samples < 1) throw InputError("--samples: must be at least 1");
  std::vector<const FidelityPreset*> presets;
  for (const auto& f : o.fidelities) presets.push_back(&level_preset(f));
  start_output_folder(o.out);
  check_output_file(o.json, "--json");
  for (const auto* p : presets) make_output_dir((std::filesystem::path(o.out) / p->name).string());

  // --collect: merge the shards written by --shard runs
  if (o.collect) {
    std::vector<std::pair<std::string, std::vector<CycleResult>>> levels;
    for (const auto* p : presets) {
      std::vector<CycleResult> all;
      for (const auto& e : std::filesystem::directory_iterator(std::filesystem::path(o.out) / p->name)) {
        if (e.path().filename().string().rfind("shard-", 0) != 0) continue;
        for (const auto& r : read_results_csv(e.path().string())) all.push_back(r);
      }
      std::sort(all.begin(), all.end(), [](const CycleResult& a, const CycleResult& b) { return a.s < b.s; });
      if (static_cast<int>(all.size()) != o.samples)
        throw InputError(o.out + "/" + p->name + ": the shards hold " + std::to_string(all.size()) + " samples, not " +
                         std::to_string(o.samples) + "; run the missing shards (--shard K/N) first");
      levels.emplace_back(p->name, all);
    }
    report(o, levels);
    return;
  }

  // --shard K/N: one share, written for a later --collect
  if (!o.shard.empty()) {
    const auto [k, n] = parse_shard(o.shard);
    Device dev(run_device_choice(presets));
    for (const auto* p : presets) {
      const auto results = run_share(dev, o, *p, k, n, !o.quiet);
      write_file_atomically((std::filesystem::path(o.out) / p->name / ("shard-" + std::to_string(k) + ".csv")).string(),
                            results_csv(results));
    }
    return;
  }

  // MPI ranks (one rank when run without mpirun)
  MpiSession mpi;
  Device dev(run_device_choice(presets));
  if (mpi.rank() == 0 && !o.quiet)
    std::cerr << "talus sweep: " << o.samples << " cycles per level on " << mpi.size() << " rank(s), " << dev.description()
              << "\n";
  std::vector<std::pair<std::string, std::vector<CycleResult>>> levels;
  try {
    for (const auto* p : presets) {
      const auto mine = run_share(dev, o, *p, mpi.rank(), mpi.size(), !o.quiet && mpi.rank() == 0);
      levels.emplace_back(p->name, gather(mpi, mine, o.samples));
    }
    if (mpi.rank() == 0) report(o, levels);
  } catch (const std::exception& e) {
    // one failing rank would leave the others waiting in the reduction: end the whole job
    if (mpi.size() > 1) {
      std::cerr << "talus sweep: rank " << mpi.rank() << ": " << e.what() << "\n";
      MPI_Abort(MPI_COMM_WORLD, kExitFailure);
    }
    throw;
  }
}

}  // namespace

void add_sweep_command(CLI::App& app, const std::string& command_line) {
  auto o = std::make_shared<SweepOptions>();
  o->command_line = command_line;
  auto* cmd = app.add_subcommand("sweep", "force-feedback bucket filling along the controller's search line "
                                          "(paper section 7); runs in parallel under mpirun");
  cmd->add_option("--scenario", o->scenario, "the pile's scenario (its profile): fb35, hd27, rd21 or a path")
      ->capture_default_str();
  cmd->add_option("--fidelity", o->fidelities,
                  "levels, comma-separated (D400 ... D50, G400 ... G50); with two, the "
                  "first is tuned and the second used")
      ->delimiter(',')
      ->capture_default_str();
  cmd->add_option("--samples", o->samples, "points s = 0 .. 1, evenly spaced")->capture_default_str()->check(CLI::Range(1, 10000));
  cmd->add_option("--out", o->out, "output folder: sweep.png, summary.json, LEVEL/sweep.csv")->required();
  cmd->add_option("--shard", o->shard, "run only the samples i with i mod N = K and write LEVEL/shard-K.csv (K/N)");
  cmd->add_flag("--collect", o->collect, "merge the shards in --out into the results instead of simulating");
  cmd->add_option("--approach", o->approach,
                  "distance from the bucket tip to the pile at the start [m]")
      ->capture_default_str()
      // the paper's approach at 8 km/h runs a few metres; as far as a scenario's pile toe may lie
      ->check(number_in(0.1, vehicle::kMaxPileToeX, "m"));
  // a cycle fills in 5-15 s (paper §7); two minutes is far beyond any that completes
  cmd->add_option("--max-time", o->max_time, "time limit of one cycle [s]")
      ->capture_default_str()
      ->check(number_in(1.0, 120.0, "s"));
  cmd->add_option("--seed", o->seed, "random seed of the pile's particle sizes and jitter")->capture_default_str();
  cmd->add_option("--json", o->json, "also write the summary to this file ('-' for stdout)");
  cmd->add_flag("--traces", o->traces, "also write each cycle's 100 Hz time series as LEVEL/cycle-I.csv "
                                      "(sample I, the run contract's columns)");
  cmd->add_flag("--quiet", o->quiet, "no progress on stderr");
  cmd->add_flag(
      "!--no-pile-cache", o->pile_cache,
      "build the pile even when the pile cache holds it, and do not save it (docs/embedding.md)");
  cmd->callback([o] { sweep(*o); });
}

}  // namespace talus::app
