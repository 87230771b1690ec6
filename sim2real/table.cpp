#include "sim2real/table.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "host/error.hpp"
#include "host/files.hpp"

namespace talus::sim2real {

namespace fs = std::filesystem;

namespace {

// the paper's CSV column names (reference/paper-*-table.csv), in ErrorColumns order
constexpr const char* kCsvHeader =
    "name,RMA-traj,RMA-V,RMA-TR,RMA-L,RMA-T,load_mass,work,E-score";
// the column symbols of the paper's Tables 4 and 5
constexpr const char* kMarkdownHeader = "| simulation | E_x | E_v | E_tr | E_l | E_t | E_M | E_W | mean |";
// digits that round-trip a double exactly
constexpr int kRoundTripDigits = 17;

std::string format_fixed(double v, int decimals) {
  if (std::isnan(v)) return "n/a";  // an undefined column (sim2real/metrics.hpp loaded_mass_error)
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(decimals);
  out << v;
  return out.str();
}

std::string format_exact(double v) {
  std::ostringstream out;
  out.precision(kRoundTripDigits);
  out << v;
  return out.str();
}

// the reference channel scaled by 1/scale, and the same for the simulated one
std::vector<double> scaled(const std::vector<double>& f, double scale) {
  std::vector<double> out(f.size());
  for (std::size_t n = 0; n < f.size(); ++n) out[n] = f[n] / scale;
  return out;
}

Trajectory bucket_tip(const TimeSeries& s) {
  Trajectory x(static_cast<Eigen::Index>(s.size()), 2);
  for (std::size_t n = 0; n < s.size(); ++n) {
    x(static_cast<Eigen::Index>(n), 0) = s[Channel::bucket_tip_x][n];
    x(static_cast<Eigen::Index>(n), 1) = s[Channel::bucket_tip_z][n];
  }
  return x;
}

// picks a phase mark: explicit option, reference summary, simulated summary, fallback
double pick(const std::optional<double>& option, const std::optional<double>& reference,
            const std::optional<double>& simulated, double fallback) {
  if (option) return *option;
  if (reference) return *reference;
  if (simulated) return *simulated;
  return fallback;
}

}  // namespace

Comparison compare_runs(const Run& simulated, const Run& reference, const CompareOptions& opt) {
  if (!(opt.force_constant_N > 0.0) || !std::isfinite(opt.force_constant_N)) {
    throw InputError("force constant must be a positive number of newtons, got " +
                     format_exact(opt.force_constant_N));
  }
  const auto& tr = reference.series[Channel::t];
  const auto& ts = simulated.series[Channel::t];

  // the digging window: both runs replay the same inputs on the same time axis, so one window
  // applies to both; the reference's marks win because the paper cut the measured data
  Comparison c;
  c.force_constant_N = opt.force_constant_N;
  c.window_start_s = pick(opt.dig_start_s, reference.summary.dig_start_s,
                          simulated.summary.dig_start_s, std::max(tr.front(), ts.front()));
  c.window_end_s = pick(opt.dig_end_s, reference.summary.dig_end_s, simulated.summary.dig_end_s,
                        std::min(tr.back(), ts.back()));
  if (!(c.window_start_s < c.window_end_s)) {
    throw InputError("digging window [" + format_exact(c.window_start_s) + ", " +
                     format_exact(c.window_end_s) + "] s is empty; check dig_start_s/dig_end_s");
  }
  for (const Run* run : {&reference, &simulated}) {
    const auto& t = run->series[Channel::t];
    if (c.window_start_s < t.front() || c.window_end_s > t.back()) {
      throw InputError((run->dir / kTimeseriesFile).string() + ": field 't': covers [" +
                       format_exact(t.front()) + ", " + format_exact(t.back()) +
                       "] s, but the digging window is [" + format_exact(c.window_start_s) +
                       ", " + format_exact(c.window_end_s) + "] s");
    }
  }
  const TimeSeries ref = select_window(reference.series, c.window_start_s, c.window_end_s);
  const TimeSeries sim_own = select_window(simulated.series, c.window_start_s, c.window_end_s);
  if (ref.size() < 2 || sim_own.size() < 1) {
    throw InputError("digging window [" + format_exact(c.window_start_s) + ", " +
                     format_exact(c.window_end_s) + "] s holds too few samples to compare");
  }
  // the simulated run on the reference time base, for the sample-by-sample measures
  const TimeSeries sim = resample(simulated.series, ref[Channel::t]);
  c.n_reference = ref.size();
  c.n_simulated = sim_own.size();

  // scalar channels: normalised MAE; a reference channel that is zero throughout cannot
  // normalise and is reported by name
  auto mae = [&](Channel ch, double scale, bool is_force) {
    const auto r = scaled(ref[ch], scale);
    const auto s = scaled(sim[ch], scale);
    const double norm =
        (is_force && opt.force_norm == ForceNorm::force_constant) ? 1.0 : max_abs(r);
    if (!(norm > 0.0)) {
      throw InputError((reference.dir / kTimeseriesFile).string() + ": field '" +
                       kChannelNames[static_cast<std::size_t>(ch)] +
                       "': zero throughout the digging window, cannot normalise the error");
    }
    return normalised_mae(s, r, norm);
  };
  c.e.e_v = mae(Channel::v_drive, 1.0, false);
  c.e.e_tr = mae(Channel::f_traction, opt.force_constant_N, true);
  c.e.e_l = mae(Channel::f_lift, opt.force_constant_N, true);
  c.e.e_t = mae(Channel::f_tilt, opt.force_constant_N, true);

  // bucket-tip trajectory [x, z]: DTW on each run's own samples (the paper's E_x), and MEE on
  // the common time base as a supplementary number
  const Trajectory x_ref = bucket_tip(ref);
  const Trajectory x_sim_own = bucket_tip(sim_own);
  c.l_norm_m = opt.l_norm_m ? *opt.l_norm_m : trajectory_extent(x_ref);
  if (!(c.l_norm_m > 0.0)) {
    throw InputError((reference.dir / kTimeseriesFile).string() +
                     ": fields 'bucket_tip_x', 'bucket_tip_z': the bucket tip does not move in "
                     "the digging window, so L_norm is zero; pass an explicit L_norm");
  }
  c.dtw_distance_m = dtw_distance(x_ref, x_sim_own);
  c.e.e_x = normalised_dtw(c.dtw_distance_m, c.n_reference, c.l_norm_m);
  c.e_x_mee = normalised_mee(bucket_tip(sim), x_ref, c.l_norm_m);

  // scalars of the whole cycle
  c.e.e_m = loaded_mass_error(simulated.summary.loaded_mass_kg, reference.summary.loaded_mass_kg);
  c.e.e_w = relative_error(simulated.summary.work_J, reference.summary.work_J);
  c.mean = paper_mean(c.e);
  return c;
}

std::string table_csv(const std::vector<TableRow>& rows) {
  std::ostringstream out;
  out << kCsvHeader << "\n";
  for (const auto& row : rows) {
    out << row.name;
    for (double v : row.e.as_array()) out << "," << format_exact(v);
    out << "," << format_exact(row.mean) << "\n";
  }
  return out.str();
}

std::string table_markdown(const std::vector<TableRow>& rows, int decimals) {
  std::ostringstream out;
  out << kMarkdownHeader << "\n|---|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const auto& row : rows) {
    out << "| " << row.name;
    for (double v : row.e.as_array()) out << " | " << format_fixed(v, decimals);
    out << " | " << format_fixed(row.mean, decimals) << " |\n";
  }
  return out.str();
}

void write_table_csv(const fs::path& file, const std::vector<TableRow>& rows) {
  write_file_atomically(file, table_csv(rows));
}

void write_table_markdown(const fs::path& file, const std::vector<TableRow>& rows, int decimals) {
  write_file_atomically(file, table_markdown(rows, decimals));
}

std::vector<TableRow> read_table_csv(const fs::path& file) {
  std::ifstream in(file);
  if (!in) throw InputError(file.string() + ": cannot open the error table");
  std::string line;
  std::size_t line_no = 0;
  std::vector<TableRow> rows;
  const char* names[] = {"RMA-traj", "RMA-V", "RMA-TR", "RMA-L", "RMA-T", "load_mass", "work",
                         "E-score"};
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    if (line_no == 1) {
      if (line != kCsvHeader) {
        throw InputError(file.string() + ":1: field 'header': expected '" + kCsvHeader + "'");
      }
      continue;
    }
    std::vector<std::string> cells;
    std::istringstream split(line);
    for (std::string cell; std::getline(split, cell, ',');) cells.push_back(cell);
    if (cells.size() != 9) {
      throw InputError(file.string() + ":" + std::to_string(line_no) +
                       ": field 'row': expected 9 fields, got " + std::to_string(cells.size()));
    }
    double v[8];
    for (int k = 0; k < 8; ++k) {
      const std::string& cell = cells[static_cast<std::size_t>(k + 1)];
      char* end = nullptr;
      v[k] = std::strtod(cell.c_str(), &end);
      // the loaded mass's error may be undefined, nan, where the measured bucket came back empty
      // (sim2real/metrics.hpp loaded_mass_error), as table_csv writes it; nothing else may
      const bool undefined_mass = k == 5 && std::isnan(v[k]);
      if (cell.empty() || end != cell.c_str() + cell.size() ||
          (!std::isfinite(v[k]) && !undefined_mass)) {
        throw InputError(file.string() + ":" + std::to_string(line_no) + ": field '" + names[k] +
                         "': '" + cell + "' is not a finite number" +
                         (k == 5 ? " (or nan, an undefined loaded-mass error)" : ""));
      }
    }
    rows.push_back({cells[0], {v[0], v[1], v[2], v[3], v[4], v[5], v[6]}, v[7]});
  }
  return rows;
}

}  // namespace talus::sim2real
