// A run's recorded data: the channel-contract time series (CSV, SI units, 100 Hz) and its
// summary.json. A run directory holds DIR/timeseries.csv and DIR/summary.json; simulated runs and
// measured (reference) runs use the same layout. Loaders reject malformed files with a
// talus::InputError naming file, line and field; writers write a temporary file, then rename.
#pragma once
#include <array>
#include <cstddef>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "vehicle/sensor_channels.hpp"

namespace talus::sim2real {

// the channel contract (names, order, units) is the sensors': vehicle/sensor_channels.hpp
using vehicle::Channel;
using vehicle::kChannelCount;
using vehicle::kChannelNames;

// file names inside a run directory
inline constexpr const char* kTimeseriesFile = "timeseries.csv";
inline constexpr const char* kSummaryFile = "summary.json";

struct TimeSeries {
  std::array<std::vector<double>, kChannelCount> columns;

  std::vector<double>& operator[](Channel c) { return columns[static_cast<std::size_t>(c)]; }
  const std::vector<double>& operator[](Channel c) const {
    return columns[static_cast<std::size_t>(c)];
  }
  std::size_t size() const { return columns[0].size(); }
};

// logged sensor samples as the channel contract's columns, and back
TimeSeries to_timeseries(const std::vector<vehicle::SensorSample>& samples);
std::vector<vehicle::SensorSample> to_samples(const TimeSeries& series);

// summary.json: the scalars of one run
struct RunSummary {
  double loaded_mass_kg = 0.0;          // soil mass in the bucket after the cycle [kg]
  double work_J = 0.0;                  // net mechanical work ∫P dt [J]
  std::optional<std::string> scenario;  // e.g. "FB35"
  std::optional<std::string> fidelity;  // e.g. "D50", "G200", "field"
  std::optional<double> dig_start_s;    // phase marks: start and end of the digging phase [s]
  std::optional<double> dig_end_s;
  // everything else the run reports (particles, timing, coupling, effects, ...): written beside
  // the fields above, read back as it stands; a key of the fields above is an error
  nlohmann::json details = nlohmann::json::object();
};

// the summary as summary.json's object (Error when a detail's key is one of the contract's)
nlohmann::json to_json(const RunSummary& summary);

// a simulation's own spread (issue 17): what the run would scatter by if it were dug again on
// another pile arrangement, or simulated again at parameters within the fit's uncertainty. The
// pile ensemble's mean carries the first (sim2real/replay.hpp, ensemble_mean), the diagnosis adds
// the second to a fitted model's run (sim2real/diagnose.hpp, "sensitivity"), and
// compute_residuals (sim2real/residuals.hpp) adds both to the sensor noise. Held in memory only:
// the run files do not carry it, a measured run never has one
struct RunSpread {
  int members = 0;  // N, the members the run is the mean of (2 or more), or 0: no ensemble
  // per channel at the run's own sample times (t is the run's t): the members' unbiased sample
  // variance [channel unit²], pooled over a short window (ensemble_variance); empty with N = 0
  TimeSeries variance;
  // the simulations at parameters within the fit's uncertainty behind `sensitivity` (1 or more),
  // or 0: none
  int sensitivity_runs = 0;
  // per channel at the run's own sample times: their mean square departure from the run
  // [channel unit²], pooled as the ensemble's (sensitivity_variance), added to the residual's
  // variance as it is; empty with sensitivity_runs = 0
  TimeSeries sensitivity;
  // the degrees of freedom of each estimate per channel (index as kChannelNames, t's entry 0):
  // few members or runs, pooled over a window shorter than their departures last, estimate a
  // variance from a handful of independent numbers, and compute_residuals judges the residual
  // against it by Student's t (ensemble_dof, sensitivity_dof in sim2real/replay.hpp). Empty:
  // exactly known (the Gaussian judgement)
  std::vector<double> variance_dof;
  std::vector<double> sensitivity_dof;
  // how long the departures behind each estimate stay correlated per channel [samples]
  // (ensemble_departure_time, sensitivity_departure_time): a cell's residual under the null holds
  // fewer independent samples where they do (compute_residuals' allowance). Empty: white (τ = 1)
  std::vector<double> variance_tau;
  std::vector<double> sensitivity_tau;
};

struct Run {
  std::filesystem::path dir;
  TimeSeries series;
  RunSummary summary;
  std::optional<RunSpread> spread;  // absent: one simulation, or a measured run

  // a row label: "<scenario>-<fidelity>" when both are known, else the directory name
  std::string label() const;
};

// strict CSV reader: header must hold every contract column (any order; extra columns are
// ignored); every cell a finite number; t strictly increasing
TimeSeries load_timeseries(const std::filesystem::path& file);
void save_timeseries(const std::filesystem::path& file, const TimeSeries& series);

RunSummary load_summary(const std::filesystem::path& file);
void save_summary(const std::filesystem::path& file, const RunSummary& summary);

// DIR/timeseries.csv and DIR/summary.json
Run load_run(const std::filesystem::path& dir);

// the samples with t0 <= t <= t1 (phase selection by phase marks in seconds)
TimeSeries select_window(const TimeSeries& series, double t0, double t1);

// linear interpolation of (t, f) at times t_new; t strictly increasing; every t_new must lie in
// [t.front(), t.back()] (no extrapolation: a simulated run that stops early is an input error)
std::vector<double> interpolate(const std::vector<double>& t, const std::vector<double>& f,
                                const std::vector<double>& t_new);

// every channel of `series` interpolated onto the time base t_new (which becomes its t)
TimeSeries resample(const TimeSeries& series, const std::vector<double>& t_new);

}  // namespace talus::sim2real
