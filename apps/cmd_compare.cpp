// `talus compare` and `talus table`: sim-to-real error rows in the paper's format (docs/metrics.md).
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "apps/commands.hpp"
#include "host/error.hpp"
#include "host/files.hpp"
#include "sim2real/table.hpp"
#include "sim2real/timeseries.hpp"

namespace talus::app {

namespace {

namespace fs = std::filesystem;
using namespace talus::sim2real;

// options shared by both subcommands
struct MetricFlags {
  double force_constant_N = kDefaultForceConstantN;
  std::string force_norm = "max";
  double dig_start_s = 0.0;
  double dig_end_s = 0.0;
  double l_norm_m = 0.0;
  int decimals = 2;  // the paper prints two decimals
  CLI::Option* dig_start = nullptr;
  CLI::Option* dig_end = nullptr;
  CLI::Option* l_norm = nullptr;

  CompareOptions options() const {
    CompareOptions o;
    o.force_constant_N = force_constant_N;
    o.force_norm = force_norm == "constant" ? ForceNorm::force_constant
                                            : ForceNorm::max_abs_reference;
    if (*dig_start) o.dig_start_s = dig_start_s;
    if (*dig_end) o.dig_end_s = dig_end_s;
    if (*l_norm) o.l_norm_m = l_norm_m;
    return o;
  }
};

void add_metric_flags(CLI::App* cmd, MetricFlags& f) {
  cmd->add_option("--force-constant", f.force_constant_N,
                  "force constant of the vehicle that forces are divided by [N] "
                  "(default: operating weight 15175 kg * 9.80665 m/s^2)")
      // the weight of a wheel loader: a compact 2 t machine (20 kN) to the largest, 262 t (2.6 MN)
      ->check(number_in(1e3, 3e6, "N"));
  cmd->add_option("--force-norm", f.force_norm,
                  "force error normaliser: 'max' = max |reference| (paper default), "
                  "'constant' = one force constant")
      ->check(CLI::IsMember({"max", "constant"}));
  f.dig_start = cmd->add_option("--dig-start", f.dig_start_s,
                                "start of the digging window [s] (default: reference summary)")
                      ->check(finite_number());
  f.dig_end = cmd->add_option("--dig-end", f.dig_end_s,
                              "end of the digging window [s] (default: reference summary)")
                    ->check(finite_number());
  f.l_norm = cmd->add_option("--l-norm", f.l_norm_m,
                             "trajectory normaliser L_norm [m] (default: extent of the "
                             "reference bucket-tip trajectory)")
                 // a bucket's path: centimetres (a near-zero one made every error astronomical)
                 // to a hundred metres (a whole loading cycle's travel is 10-30 m)
                 ->check(number_in(0.01, 100.0, "m"));
  cmd->add_option("--decimals", f.decimals, "decimal places of the printed table")
      ->check(CLI::Range(0, 17));
}

// the reference run for a simulated run: DIR itself when it is a run, else DIR/<scenario>
fs::path reference_dir_for(const fs::path& ref, const Run& sim) {
  if (fs::exists(ref / kSummaryFile)) return ref;
  if (!sim.summary.scenario) {
    throw InputError((sim.dir / kSummaryFile).string() +
                     ": field 'scenario': missing, and " + ref.string() +
                     " is not a run directory; give the scenario or point --ref at one run");
  }
  return ref / *sim.summary.scenario;
}

nlohmann::json to_json(const std::string& name, const Comparison& c) {
  return {{"name", name},
          {"E_x", c.e.e_x},
          {"E_v", c.e.e_v},
          {"E_tr", c.e.e_tr},
          {"E_l", c.e.e_l},
          {"E_t", c.e.e_t},
          {"E_M", c.e.e_m},
          {"E_W", c.e.e_w},
          {"mean", c.mean},
          {"dtw_distance_m", c.dtw_distance_m},
          {"N", c.n_reference},
          {"n_simulated", c.n_simulated},
          {"L_norm_m", c.l_norm_m},
          {"E_x_mee", c.e_x_mee},
          {"window_start_s", c.window_start_s},
          {"window_end_s", c.window_end_s},
          {"force_constant_N", c.force_constant_N}};
}

}  // namespace

void add_compare_command(CLI::App& app) {
  // compare: one simulated run against one reference run
  {
    struct Args {
      std::string sim, ref, json;
      MetricFlags flags;
    };
    auto args = std::make_shared<Args>();
    auto* cmd = app.add_subcommand(
        "compare", "sim-to-real errors of one simulated run against a measured run");
    cmd->add_option("--sim", args->sim, "simulated run directory (timeseries.csv, summary.json)")
        ->required();
    cmd->add_option("--ref", args->ref, "reference (measured) run directory")->required();
    cmd->add_option("--json", args->json, "also write the row, raw DTW distance, N and L_norm");
    add_metric_flags(cmd, args->flags);
    cmd->callback([args] {
      const Run sim = load_run(args->sim);
      const Run ref = load_run(args->ref);
      const Comparison c = compare_runs(sim, ref, args->flags.options());
      const std::string name = sim.label();
      std::cout << table_markdown({{name, c.e, c.mean}}, args->flags.decimals);
      if (!args->json.empty()) {
        write_file_atomically(args->json, to_json(name, c).dump(2) + "\n");
      }
    });
  }

  // table: many simulated runs, one row each
  {
    struct Args {
      std::vector<std::string> runs;
      std::string ref, csv, md;
      MetricFlags flags;
    };
    auto args = std::make_shared<Args>();
    auto* cmd = app.add_subcommand(
        "table", "error table in the paper's format over several simulated runs");
    cmd->add_option("runs", args->runs, "simulated run directories")->required();
    cmd->add_option("--ref", args->ref,
                    "reference run directory, or a folder of them named by scenario "
                    "(REF/FB35, REF/HD27, ...)")
        ->required();
    cmd->add_option("--csv", args->csv, "write the table as CSV (the paper's column names)");
    cmd->add_option("--md", args->md, "write the table as Markdown");
    add_metric_flags(cmd, args->flags);
    cmd->callback([args] {
      std::vector<TableRow> rows;
      for (const auto& dir : args->runs) {
        const Run sim = load_run(dir);
        const Run ref = load_run(reference_dir_for(args->ref, sim));
        const Comparison c = compare_runs(sim, ref, args->flags.options());
        rows.push_back({sim.label(), c.e, c.mean});
      }
      std::cout << table_markdown(rows, args->flags.decimals);
      if (!args->csv.empty()) write_table_csv(args->csv, rows);
      if (!args->md.empty()) write_table_markdown(args->md, rows, args->flags.decimals);
    });
  }
}

}  // namespace talus::app
