// `talus plot --runs DIR... [--ref DIR] [--pile-profile FILE] --out DIR`: the paper-style figures
// (with --ref also resolution.png: mean error and real-time factor against particle size)
// of recorded runs (docs/plots.md): channels.png, trajectory.png and power.png in --out.
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "apps/commands.hpp"
#include "host/files.hpp"
#include "io/plot.hpp"
#include "sim2real/table.hpp"
#include "sim2real/timeseries.hpp"
#include "terrain/pile.hpp"

namespace talus::app {

namespace {

// image sizes [px]: wide enough for a page-width figure, each stacked panel about 230 px tall
constexpr int kWidthPx = 1200;
constexpr int kChannelsHeightPx = 1800;  // seven panels
constexpr int kTrajectoryHeightPx = 700;
constexpr int kPowerPanelPx = 300;       // power.png grows with the number of runs
constexpr int kPowerMarginPx = 150;      // legend and x axis
constexpr int kResolutionHeightPx = 900; // two panels: error and real-time factor

struct PlotArgs {
  std::vector<std::string> runs;
  std::string ref, pile_profile, out;
};

void plot(const PlotArgs& a) {
  // load everything first: bad input fails before any figure is written
  std::vector<sim2real::Run> runs;
  for (const std::string& dir : a.runs) runs.push_back(sim2real::load_run(dir));
  std::optional<sim2real::Run> ref;
  if (!a.ref.empty()) ref = sim2real::load_run(a.ref);
  std::vector<std::pair<double, double>> profile;
  if (!a.pile_profile.empty()) {
    for (const Vec3& p : load_pile_profile(a.pile_profile).points) profile.emplace_back(p.x(), p.z());
  }
  const sim2real::Run* reference = ref ? &*ref : nullptr;

  make_output_dir(a.out);
  const std::string out = a.out + "/";
  channel_figure(runs, reference).write_png(out + "channels.png", kWidthPx, kChannelsHeightPx);
  trajectory_figure(runs, reference, profile)
      .write_png(out + "trajectory.png", kWidthPx, kTrajectoryHeightPx);
  const int power_panels = static_cast<int>(runs.size()) + (reference ? 1 : 0);
  power_figure(runs, reference)
      .write_png(out + "power.png", kWidthPx, kPowerMarginPx + kPowerPanelPx * power_panels);
  std::cerr << "talus plot: wrote channels.png, trajectory.png and power.png to " << a.out << "\n";

  // against a reference: the mean error and the real-time factor of each run against its particle
  // size (runs whose fidelity names a size, e.g. D200 or G100)
  if (!reference) return;
  std::vector<ResolutionPoint> points;
  for (const sim2real::Run& r : runs) {
    const std::string fidelity = r.summary.fidelity.value_or("");
    const size_t digits = fidelity.find_first_of("0123456789");
    if (digits == std::string::npos || digits == 0) continue;
    const nlohmann::json summary = nlohmann::json::parse(std::ifstream(r.dir / sim2real::kSummaryFile));
    const double realtime = summary.value("realtime_factor", 0.0);
    const sim2real::Comparison c = sim2real::compare_runs(r, *reference, sim2real::CompareOptions{});
    points.push_back({r.summary.scenario.value_or(r.label()), fidelity, std::stod(fidelity.substr(digits)), c.mean,
                      realtime});
  }
  if (points.empty()) return;
  resolution_figure(points).write_png(out + "resolution.png", kWidthPx, kResolutionHeightPx);
  std::cerr << "talus plot: wrote resolution.png (" << points.size() << " runs against the reference)\n";
}

}  // namespace

void add_plot_command(CLI::App& app) {
  auto args = std::make_shared<PlotArgs>();
  auto* cmd = app.add_subcommand(
      "plot", "paper-style PNG figures of runs: channel overlays, bucket-tip trajectory, power split");
  cmd->add_option("--runs", args->runs, "simulated run directories (timeseries.csv, summary.json)")
      ->required();
  cmd->add_option("--ref", args->ref, "reference (measured) run directory, drawn dashed black");
  cmd->add_option("--pile-profile", args->pile_profile,
                  "pile profile drawn under the trajectories (format of data/piles/default.json)");
  cmd->add_option("--out", args->out, "output folder for channels.png, trajectory.png, power.png")
      ->required();
  cmd->callback([args] { plot(*args); });
}

}  // namespace talus::app
