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

#include "apps/commands.hpp"
#include "host/device.hpp"
#include "host/error.hpp"
#include "host/files.hpp"
#include "io/plot.hpp"
#include "sim2real/diagnose.hpp"

namespace talus::app {

namespace {

namespace fs = std::filesystem;
using namespace talus::sim2real;

// residual cells listed per run in the printed signature
constexpr std::size_t kSignatureCells = 6;
// the figures' size [px], as talus run's
constexpr int kFigureWidth = 1400, kFigureHeight = 1000;
// a scan further than this from the simulated pile's is worth a warning [m]: about one D400
// particle diameter
constexpr double kScanWarning = 0.1;

struct DiagnoseArgs {
  std::vector<std::string> data;
  std::vector<std::string> plugins;
  std::string fidelity = "D400";
  std::string json, out;
  int max_effects = 2;
  int validation = -1;
  unsigned pile_seed = 1;
  bool quiet = false;
};

// the largest residual cells of a run, with what each moves with
std::string signature_text(const Residuals& res, const Run& measured, const Run& simulated) {
  std::vector<ResidualCell> cells = res.cells;
  std::sort(cells.begin(), cells.end(), [](const auto& a, const auto& b) { return a.excess > b.excess; });
  std::ostringstream s;
  s << "| channel | phase | RMS residual | mean residual | noise σ | excess | moves most with (r) |\n"
    << "|---|---|---|---|---|---|---|\n";
  std::size_t shown = 0;
  for (const auto& c : cells) {
    if (shown == kSignatureCells || c.excess <= 0.0) break;
    const auto r = residual_series(simulated, measured, c.channel);
    const Correlate k = strongest_correlate(r, measured);
    s << "| " << kChannelNames[c.channel] << " | " << res.phases[c.phase].name << " | " << std::setprecision(3) << c.rms
      << " | " << c.mean << " | " << c.sigma << " | " << std::setprecision(2) << std::fixed << c.excess
      << std::defaultfloat << " | " << k.quantity << " (" << std::setprecision(2) << k.r << ") |\n";
    ++shown;
  }
  if (shown == 0) s << "| (every channel within noise) | | | | | | |\n";
  return s.str();
}

void diagnose_command(const DiagnoseArgs& a) {
  // every run loads and checks before anything is simulated
  std::vector<MeasuredRun> runs;
  for (const auto& dir : a.data) runs.push_back(load_measured_run(dir));
  DiagnoseOptions options;
  options.replay.fidelity = a.fidelity;
  options.replay.pile_seed = a.pile_seed;
  options.replay.progress = !a.quiet;
  options.max_effects = a.max_effects;
  options.validation_runs = a.validation;
  options.plugins = vehicle::load_effect_plugins(a.plugins);
  if (!a.out.empty()) make_output_dir(a.out);
  const bool piles = std::any_of(runs.begin(), runs.end(), [](const MeasuredRun& r) { return measured_scenario(r).pile; });
  std::unique_ptr<Device> device = piles ? std::make_unique<Device>() : nullptr;

  const Diagnosis d = diagnose(runs, options, device.get(), [&](const std::string& line) {
    if (!a.quiet) std::cerr << "talus diagnose: " << line << "\n";
  });

  // the report: where the residual lay, what was found, the errors before and after
  std::ostringstream report;
  report << "# talus diagnose\n\n";
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const bool cal = std::find(d.calibration.begin(), d.calibration.end(), i) != d.calibration.end();
    const bool val = std::find(d.validation.begin(), d.validation.end(), i) != d.validation.end();
    report << "## " << runs[i].run.label() << " (" << d.runs[i] << "; "
           << (cal && val ? "calibration and validation" : cal ? "calibration" : "validation") << ")\n\n"
           << "Baseline residual, largest cells (excess = ln max(MSE / (" << kNoiseAllowance
           << " σ²), 1); run total " << std::setprecision(3) << d.residuals_before[i].excess << "):\n\n"
           << signature_text(d.residuals_before[i], runs[i].run, d.simulated_before[i]) << "\n";
    if (d.scan_rms_m[i] && *d.scan_rms_m[i] > kScanWarning)
      report << "Warning: the measured pile scan lies " << *d.scan_rms_m[i] << " m (RMS) from the simulated pile's; "
             << "the residual includes that difference.\n\n";
  }
  report << "## Effects\n\n";
  if (d.found.empty()) {
    report << (d.unexplained ? "None added: no candidate explains " + std::to_string(int(100 * kMinExplained)) +
                                   " % of the residual. UNEXPLAINED.\n"
                             : "None added: the baseline residual is within the noise of the data.\n");
  } else {
    for (const auto& f : d.found)
      report << "- " << f.spec << " (explains " << std::setprecision(3) << 100.0 * f.explained
             << " % of the excess of the " << f.explained_on << " runs)\n";
    report << (d.unexplained ? "\nAn excess beyond noise remains: UNEXPLAINED in part.\n" : "\nWhat remains is within noise.\n");
  }
  report << "\nExcess per run: before " << std::setprecision(3) << d.excess_before << ", after " << d.excess_after
         << " (noise alone leaves less than " << kSignificantExcess << "); " << d.simulations << " simulations in "
         << std::setprecision(3) << d.wall_s << " s.\n\n## Error before\n\n";
  std::vector<TableRow> before = d.error_before, after = d.error_after;
  before.push_back(mean_row(d.error_before, "mean over runs"));
  after.push_back(mean_row(d.error_after, "mean over runs"));
  report << table_markdown(before, 3) << "\n## Error after\n\n" << table_markdown(after, 3);
  // the report on stdout, unless the JSON goes there
  (a.json == "-" ? std::cerr : std::cout) << report.str();

  // machine-readable results and figures
  const nlohmann::json j = diagnosis_json(d);
  if (a.json == "-") {
    std::cout << j.dump(2) << "\n";
  } else if (!a.json.empty()) {
    write_json(a.json, j);
  }
  if (!a.out.empty()) {
    const fs::path out(a.out);
    write_json((out / "diagnosis.json").string(), j);
    write_file_atomically(out / "report.md", report.str());
    write_table_csv(out / "errors-before.csv", before);
    write_table_csv(out / "errors-after.csv", after);
    for (std::size_t i = 0; i < runs.size(); ++i) {
      const std::string name = std::to_string(i) + "-" + runs[i].run.label() + "-channels.png";
      channel_figure({d.simulated_before[i], d.simulated_after[i]}, &runs[i].run)
          .write_png((out / name).string(), kFigureWidth, kFigureHeight);
    }
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
  cmd->add_option("--fidelity", a->fidelity, "particle level for pile scenarios (D400, D200, D100, D50)")->capture_default_str();
  cmd->add_option("--json", a->json, "write effects_found, error_before, error_after, unexplained and the details "
                                     "('-' for stdout)");
  cmd->add_option("--out", a->out, "also write diagnosis.json, report.md, errors-before/after.csv and per-run "
                                   "channel figures (measured, baseline, with effects) here");
  cmd->add_option("--max-effects", a->max_effects, "effects to add at most")->capture_default_str()->check(CLI::Range(1, 5));
  cmd->add_option("--validation", a->validation, "how many of the runs (the last ones) to hold out for validation "
                                                 "(default: a third, at least one of two or more)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--effect-plugin", a->plugins, "a shared library whose effects join the candidates (repeatable)")
      ->expected(1)->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  cmd->add_option("--pile-seed", a->pile_seed, "random seed of the simulated pile's particles")->capture_default_str();
  cmd->add_flag("--quiet", a->quiet, "no progress on stderr");
  cmd->callback([a] { diagnose_command(*a); });
}

}  // namespace talus::app
