// Error rows in the format of the paper's Tables 4 and 5 (columns E_x, E_v, E_tr, E_l, E_t, E_M,
// E_W, mean), the comparison of a simulated run with a measured one that fills such a row, and
// the tables written as CSV (the paper's own column names, so reference/paper-*-table.csv and
// talus output read the same way) and as Markdown.
#pragma once
#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "sim2real/metrics.hpp"
#include "sim2real/timeseries.hpp"

namespace talus::sim2real {

// one force constant of the vehicle that all forces are divided by (paper §6 "Processing of time
// series"): talus uses the operating weight of the WA320-7 class machine, m g with
// m = 15 175 kg (SPEC §2.4) and standard gravity 9.80665 m/s², ≈ 148.8 kN
inline constexpr double kOperatingMassKg = 15175.0;
inline constexpr double kStandardGravity = 9.80665;
inline constexpr double kDefaultForceConstantN = kOperatingMassKg * kStandardGravity;

// how a force error is normalised after the division by the force constant
enum class ForceNorm {
  max_abs_reference,  // f_norm = max |f̂| (the paper's default; the force constant cancels)
  force_constant,     // f_norm = 1 force constant (errors in units of m g)
};

struct CompareOptions {
  double force_constant_N = kDefaultForceConstantN;
  ForceNorm force_norm = ForceNorm::max_abs_reference;
  // digging window [s]; when unset, taken from the reference summary, then the simulated one,
  // then the overlap of both time ranges
  std::optional<double> dig_start_s;
  std::optional<double> dig_end_s;
  // trajectory normaliser [m]; when unset, the extent of the reference bucket-tip trajectory
  std::optional<double> l_norm_m;
};

struct Comparison {
  ErrorColumns e;
  double mean = 0.0;               // paper_mean(e)
  double dtw_distance_m = 0.0;     // raw DTW distance d of the bucket-tip trajectories [m]
  std::size_t n_reference = 0;     // N: reference samples in the window (MAE, MEE and DTW)
  std::size_t n_simulated = 0;     // simulated samples in the window (DTW only)
  double l_norm_m = 0.0;           // L_norm used [m]
  double e_x_mee = 0.0;            // trajectory MEE on the common time base (not in the table)
  double window_start_s = 0.0;
  double window_end_s = 0.0;
  double force_constant_N = 0.0;
};

// compares a simulated run with a reference (measured) run in the digging window
Comparison compare_runs(const Run& simulated, const Run& reference, const CompareOptions& options);

struct TableRow {
  std::string name;
  ErrorColumns e;
  double mean = 0.0;  // as computed (paper_mean) or, for a paper table read from disk, as printed
};

// the paper's CSV header: name,RMA-traj,RMA-V,RMA-TR,RMA-L,RMA-T,load_mass,work,E-score
std::string table_csv(const std::vector<TableRow>& rows);
// Markdown with the paper's column symbols, `decimals` places (the paper prints 2)
std::string table_markdown(const std::vector<TableRow>& rows, int decimals = 2);

void write_table_csv(const std::filesystem::path& file, const std::vector<TableRow>& rows);
void write_table_markdown(const std::filesystem::path& file, const std::vector<TableRow>& rows,
                          int decimals = 2);

// reads a table in the paper's CSV format (e.g. reference/paper-D-table.csv); the mean is the
// printed E-score, not recomputed
std::vector<TableRow> read_table_csv(const std::filesystem::path& file);

}  // namespace talus::sim2real
