// `talus diagnose --data DIR... [--fidelity F] [--json FILE] [--out DIR]`: the sim-to-real loop
// (issue 6, sim2real/diagnose.hpp, docs/sim2real.md). Simulates each measured run's inputs with the
// baseline model, shows where the residual lies (channel, phase, what it moves with), searches the
// candidate effects for the one the model lacks, and prints the paper's error table before and
// after adding what it found, or says "unexplained".
#include <algorithm>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>
#include <system_error>

#include "apps/commands.hpp"
#include "host/device.hpp"
#include "host/error.hpp"
#include "host/files.hpp"
#include "io/plot.hpp"
#include "sim2real/diagnose.hpp"
#include "sim2real/report.hpp"
#include "terrain/pile.hpp"

namespace talus::app {

namespace {

namespace fs = std::filesystem;
using namespace talus::sim2real;

// the --out folder's completion mark: the machine-readable diagnosis, written last
constexpr const char* kDiagnosisFile = "diagnosis.json";

struct DiagnoseArgs {
  std::vector<std::string> data;
  std::vector<std::string> plugins;
  std::vector<std::string> candidates;
  bool candidates_given = false;
  std::string fidelity = "D400";
  std::string json, out;
  int max_effects = 2;
  int validation = -1;
  unsigned pile_seed = 1;
  int pile_ensemble = 1;
  int threads = 0;
  bool quiet = false;
  bool discover = false;
};

void diagnose_command(const DiagnoseArgs& a) {
  // every run loads and checks before anything is simulated
  std::vector<MeasuredRun> runs;
  for (const auto& dir : a.data) runs.push_back(load_measured_run(dir));
  DiagnoseOptions options;
  options.replay.fidelity = a.fidelity;
  options.replay.pile_seed = a.pile_seed;
  options.replay.pile_ensemble = a.pile_ensemble;
  options.replay.progress = !a.quiet;
  options.max_effects = a.max_effects;
  options.validation_runs = a.validation;
  options.plugins = vehicle::load_effect_plugins(a.plugins);
  // the candidates named are checked before the --out folder is touched
  if (a.candidates_given && a.candidates.empty())
    throw InputError(
        "--candidates: no label given; fix: name one or more candidates (engine_power_sharing,...) "
        "or drop the option");
  chosen_candidates(candidate_set(options.plugins), a.candidates);
  options.candidates = a.candidates;
  options.discover = a.discover;
  options.threads = a.threads;
  check_output_file(a.json, "--json");
  // --out: diagnosis.json is written last and marks the folder complete, so a previous
  // diagnosis's goes before anything runs (a diagnosis killed midway leaves a folder without it)
  if (!a.out.empty()) {
    make_output_dir(a.out);
    std::error_code ec;
    fs::remove(fs::path(a.out) / kDiagnosisFile, ec);
    if (ec)
      throw InputError("--out " + a.out + ": cannot remove the previous " + kDiagnosisFile + " (" +
                       ec.message() + ")");
  }
  const bool piles = std::any_of(runs.begin(), runs.end(), [](const MeasuredRun& r) { return measured_scenario(r).pile; });
  std::unique_ptr<Device> device =
      piles ? std::make_unique<Device>(run_device_choice(level_preset(a.fidelity))) : nullptr;

  const Diagnosis d = diagnose(runs, options, device.get(), [&](const std::string& line) {
    if (!a.quiet) std::cerr << "talus diagnose: " << line << "\n";
  });

  // the report: where the residual lay, what was found, the errors before and after
  const std::string report = diagnosis_report(d, runs);
  // the report on stdout, unless the JSON goes there
  (a.json == "-" ? std::cerr : std::cout) << report;

  // machine-readable results and figures
  const nlohmann::json j = diagnosis_json(d);
  if (a.json == "-") {
    std::cout << j.dump(2) << "\n";
  } else if (!a.json.empty()) {
    write_json(a.json, j);
  }
  if (!a.out.empty()) {
    const fs::path out(a.out);
    write_file_atomically(out / "report.md", report);
    write_table_csv(out / "errors-before.csv", error_table(d.error_before));
    write_table_csv(out / "errors-after.csv", error_table(d.error_after));
    for (std::size_t i = 0; i < runs.size(); ++i) {
      const std::string name = std::to_string(i) + "-" + runs[i].run.label() + "-channels.png";
      channel_figure({d.simulated_before[i], d.simulated_after[i]}, &runs[i].run)
          .write_png((out / name).string(), kFigureWidth, kFigureHeight);
    }
    write_json((out / kDiagnosisFile).string(), j);
  }
}

}  // namespace

void add_diagnose_command(CLI::App& app) {
  auto a = std::make_shared<DiagnoseArgs>();
  auto* cmd = app.add_subcommand("diagnose", "find the physical effect the model lacks from measured runs, and the "
                                             "error before and after adding it (docs/sim2real.md)");
  cmd->add_option("--data", a->data, "measured run folders (metadata.json, timeseries.csv, summary.json; "
                                     "docs/measured-data.md); the last third are held out for validation")
      ->required()->expected(1, -1)->check(CLI::ExistingDirectory);
  cmd->add_option("--fidelity", a->fidelity,
                  "level for pile scenarios (particles D400, D200, D100, D50; multiscale G400, "
                  "G200, G100, G50)")
      ->capture_default_str();
  cmd->add_option("--json", a->json, "write effects_found, error_before, error_after, unexplained and the details "
                                     "('-' for stdout)");
  cmd->add_option("--out", a->out, "also write diagnosis.json, report.md, errors-before/after.csv and per-run "
                                   "channel figures (measured, baseline, with effects) here");
  cmd->add_option("--max-effects", a->max_effects,
                  "rounds that add effects, at most (a round adds one effect, a pair or a set of "
                  "three)")
      ->capture_default_str()
      ->check(CLI::Range(1, 5));
  cmd->add_option("--validation", a->validation,
                  "how many of the runs (the last ones) to hold out for validation "
                  "(default: a third, at least one of two or more)")
      ->check(non_negative_number());
  cmd->add_option("--effect-plugin", a->plugins, "a shared library whose effects join the candidates (repeatable)")
      ->expected(1)->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  auto* candidates =
      cmd->add_option("--candidates", a->candidates,
                      "search only these candidate effects, by label (comma-separated, "
                      "quoted for the shell: 'engine_power_sharing,sensor_bias[f_lift]'; "
                      "docs/sim2real.md); default: all")
          ->delimiter(',')
          ->expected(1, -1);
  cmd->add_option("--pile-seed", a->pile_seed, "random seed of the simulated pile's particles")->capture_default_str();
  cmd->add_option(
         "--pile-ensemble", a->pile_ensemble,
         "dig N piles per simulation (seeds pile-seed, pile-seed + 1, ...) and compare their "
         "mean: a smoother objective where the grains' arrangement scatters the dig; with 2 or "
         "more, residuals are judged against the piles' own spread as well as the sensor noise "
         "(docs/sim2real.md); N times the cost. Three piles rank candidates, but their spread is "
         "too rough to call what is left unexplained: use more for the verdict (eight were enough "
         "on effect-free G400 data, docs/sim2real.md)")
      ->capture_default_str()
      ->check(CLI::Range(1, sim2real::kMaxPileEnsemble));
  cmd->add_flag(
      "--discover", a->discover,
      "fit a learned correction (a sparse model of the residual, docs/discovery.md) even when the "
      "candidates leave nothing beyond noise; by default it is fitted only when they do");
  cmd->add_option("--threads", a->threads,
                  "simulations of the machine alone run at once (default 0: every hardware thread; "
                  "runs on a pile share the device and run one at a time); any count gives the "
                  "same diagnosis")
      ->capture_default_str()
      // a bound far above any host's hardware threads, that catches a typo before threads start
      ->check(CLI::Range(0, 1024));
  cmd->add_flag("--quiet", a->quiet, "no progress on stderr");
  cmd->callback([a, candidates] {
    a->candidates_given = candidates->count() > 0;
    diagnose_command(*a);
  });
}

}  // namespace talus::app
