// Subcommands of the `talus` command-line tool. Each file apps/cmd_*.cpp adds one
// CLI11 subcommand; apps/talus.cpp wires them up and turns errors into exit codes.
#pragma once
#include <CLI/CLI.hpp>
#include <cmath>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>

#include "host/device.hpp"
#include "host/error.hpp"
#include "host/files.hpp"
#include "solvers/dem_settings.hpp"
#include "terrain/multiscale_terrain.hpp"
#include "terrain/pile.hpp"

namespace talus::app {

// exit codes (sysexits-like): 0 success, 1 runtime failure, 2 bad usage or bad input
inline constexpr int kExitFailure = 1;
inline constexpr int kExitUsage = 2;

// the device choice of a run at these levels (terrain/pile device_choice_for), with PoCL's
// in-thread device listed where the choice prefers it: the tool sets POCL_DEVICES only then, just
// before the run makes its Device (its first OpenCL call), so every other run keeps PoCL's own
// list of drivers (host/device.hpp list_pocl_in_thread_device)
template <class Levels>
DeviceChoice run_device_choice(const Levels& levels) {
  DeviceChoice choice = device_choice_for(levels);
  if (choice.in_host_thread) list_pocl_in_thread_device();
  return choice;
}

// --reach of run, bench dig and bench dem (DemSettings::pair_reach): "pair" or "fastest", the
// default the caller's (digs: each pair's since 2026-11-29; bench dem: the fastest's, as piles)
inline CLI::Option* add_reach_option(CLI::App& cmd, bool& pair_reach) {
  // the words alone (a bool option with a transformer also took 0 and 1)
  return cmd
      .add_option_function<std::string>(
          "--reach", [&pair_reach](const std::string& reach) { pair_reach = reach == "pair"; },
          "speculative reach of particle pairs: 'pair' (each pair's own, 2 h times its closing "
          "speed + |g| h: no speculative rows in a bed at rest) or 'fastest' (the fastest "
          "particle's, 2 h v_max, for every pair; docs/dem.md)")
      ->check(CLI::IsMember({"pair", "fastest"}).description(""))
      ->type_name("pair|fastest")
      ->default_str(pair_reach ? "pair" : "fastest");
}

// --relaxation of run, bench dig and bench dem (DemSettings::relaxation)
inline const char* const kRelaxationHelp =
    "study: the relaxation omega of the particle rows' PGS sweeps, in [0.01, 2): each row's step "
    "is omega times Gauss-Seidel's (projected SOR; 1 = plain PGS, docs/dem.md \"Relaxation\")";

// --bucket-sweep of run and bench dig (CouplingSettings::bucket_sweep)
inline const char* const kBucketSweepHelp =
    "how a type-D step sweeps its bucket rows: 'serial' (one chain, the bucket moving with each "
    "row) or 'coloured' (a particle's rows in different colours, a colour's rows at once against "
    "the bucket split among them; for GPUs, where the chain's latency dominates; docs/digging.md)";

// a numeric option that must be a finite number: CLI11's range checks let NaN through (every
// comparison with it is false), and a NaN timestep or rolling resistance would run silently
inline CLI::Validator finite_number() {
  return CLI::Validator(
      [](std::string& text) {
        if (finite_number_in(text)) return std::string();
        return "must be a finite number, got '" + text + "'";
      },
      "FINITE");
}

// an output file given by `flag` checked writable before anything runs; empty (not asked for)
// and "-" (standard output) pass
inline void check_output_file(const std::string& path, const std::string& flag) {
  if (!path.empty() && path != "-") check_writable(path, flag);
}

// a numeric option that must be finite and above zero (or at least zero): CLI11's own range
// checks print their bound, DBL_MAX, as a 309-digit number
inline CLI::Validator signed_number(bool allow_zero) {
  return CLI::Validator(
      [allow_zero](std::string& text) {
        const std::optional<double> x = finite_number_in(text);
        if (x && (*x > 0.0 || (allow_zero && *x == 0.0))) return std::string();
        return std::string(allow_zero ? "must be a finite number at least 0"
                                      : "must be a finite number above 0") +
               ", got '" + text + "'";
      },
      allow_zero ? "NON-NEGATIVE" : "POSITIVE");
}
inline CLI::Validator positive_number() { return signed_number(false); }
inline CLI::Validator non_negative_number() { return signed_number(true); }

// a type-G seed's diameter as a fraction of its full one, in [0.1, 1]
// (MultiscaleOptions::seed_diameter, kMinSeedDiameter)
inline CLI::Validator seed_fraction() {
  return CLI::Validator(
      [](std::string& text) {
        const std::optional<double> x = finite_number_in(text);
        if (x && *x >= kMinSeedDiameter && *x <= 1.0) return std::string();
        return "must be a fraction from 0.1 to 1 (1: particles at full size); got '" + text + "'";
      },
      "[0.1, 1]");
}

// a PGS relaxation, 0.01 <= omega < 2 (solvers/dem_settings relaxation_in_range)
inline CLI::Validator relaxation_number() {
  return CLI::Validator(
      [](std::string& text) {
        const std::optional<double> x = finite_number_in(text);
        if (x && relaxation_in_range(*x)) return std::string();
        return "must be a number from 0.01 to below 2, 1 for plain projected Gauss-Seidel; got '" +
               text + "'";
      },
      "[0.01, 2)");
}

// the contact coefficients a study may ask for (Coulomb friction, rolling resistance μ_r): 0 to 2,
// beyond which a grain neither slides nor rolls any less (the gravel: 0.3 and 0.02; talus's former
// blocked rolling: 1.0)
inline constexpr double kMaxContactCoefficient = 2.0;

// timesteps a study may ask for [s]: from 0.1 ms (a 15 s dig is then 150,000 steps, hours at D200;
// below it the step count runs to days or overflows) to 50 ms, G400's and the coarsest preset's
// (SPEC §2.6)
inline constexpr double kMinTimestep = 1e-4;
inline constexpr double kMaxTimestep = 0.05;
// (the SPOOK damping times a study may ask for, kMinDampingTime and kMaxDampingTime: solvers/
// dem_settings.hpp, where the type-G interfaces' study reads them too)

// a numeric option within a physical range [lo, hi] in `unit` (or exactly 0, where 0 means "off"):
// beyond such a range a timestep or speed overflows the step count, runs for days or answers
// nonsense with exit 0 (docs/reliability.md gives each flag's range and why)
inline CLI::Validator number_in(double lo, double hi, const std::string& unit,
                                bool zero_allowed = false) {
  const std::string range = (zero_allowed ? "0 or " : "") + std::string("from ") +
                            message_number(lo) + " to " + message_number(hi) +
                            (unit.empty() ? "" : " " + unit);
  return CLI::Validator(
      [lo, hi, zero_allowed, range](std::string& text) {
        const std::optional<double> x = finite_number_in(text);
        if (x && ((*x >= lo && *x <= hi) || (zero_allowed && *x == 0.0))) return std::string();
        return "must be a finite number " + range + ", got '" + text + "'";
      },
      "[" + range + "]");
}

// commands that write a folder get the command line as typed, recorded in its summary.json
void add_pile_command(CLI::App& app, const std::string& command_line);  // build and settle a pile
void add_repose_command(CLI::App& app,
                        const std::string& command_line);  // heap test: angle of repose
void add_bench_command(CLI::App& app);   // DEM throughput benchmarks
// the command line as typed, each argument quoted when it holds a space or a quote (for
// summaries that record how they were made)
inline std::string command_line(int argc, char** argv) {
  std::string line;
  for (int i = 0; i < argc; ++i) {
    const std::string arg = argv[i];
    const bool quote = arg.empty() || arg.find_first_of(" \t'\"") != std::string::npos;
    std::string escaped;
    for (char c : arg) escaped += c == '\'' ? std::string("'\\''") : std::string(1, c);
    line += (i > 0 ? " " : "") + (quote ? "'" + escaped + "'" : arg);
  }
  return line;
}

// vehicle scenarios; `command_line` is recorded in every summary.json the command writes
void add_run_command(CLI::App& app, const std::string& command_line);
void add_compare_command(CLI::App& app); // sim-to-real error rows and tables (compare, table)
void add_synth_command(
    CLI::App& app,
    const std::string& command_line);  // field-like data with effects and noise (sim-to-real loop)
void add_diagnose_command(CLI::App& app);  // the sim-to-real loop: residual -> missing effect
void add_sweep_command(
    CLI::App& app,
    const std::string& command_line);    // force-feedback sweep along the search line (MPI)
void add_plot_command(CLI::App& app);    // paper-style PNG figures of runs
void add_soil_command(
    CLI::App& app,
    const std::string& command_line);  // calibration tests of the gravel: repose, shear, collapse
void add_cut_command(
    CLI::App& app,
    const std::string& command_line);  // quasi-static cutting test against the earthmoving equation

}  // namespace talus::app
