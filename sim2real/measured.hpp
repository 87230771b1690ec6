// A measured run (SPEC §6, issue 6 "Measured data"): what a field test hands the sim-to-real
// loop, in one directory:
//   timeseries.csv  the channel contract at 100 Hz (sim2real/timeseries.hpp: t [s], forces [N],
//                   drive speed [m/s], extensions [m], angles [deg], positions [m], power [W])
//   summary.json    loaded_mass_kg, work_J, scenario, fidelity ("field"), dig_start_s, dig_end_s
//   metadata.json   {"format": "talus-measured-run", "version": 1, "scenario": "HD27",
//                    "machine": "wa320", "sample_rate_hz": 100, "pile_toe_x_m": 5.0,
//                    "pile_scan": [[x, z], ...],                 (the laser scan before loading, m)
//                    "operator_inputs": {"drive": [[t, v], ...], "lift": [...], "tilt": [...]},
//                                                                (target speeds, s and m/s)
//                    "loaded_mass_kg": 2700, "work_J": 127000}
// The loader checks every field and the consistency between the files (sample rate against the
// time column, mass and work against the summary) and rejects a malformed run with one
// talus::InputError naming the file, the line or field, and the fix. The synthetic runs of
// `talus synth` are written in this format; their answer key never is (it goes elsewhere).
#pragma once
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "sim2real/timeseries.hpp"

namespace talus::sim2real {

// the channel contract's sample rate [Hz] (SPEC §2.4, docs/measured-data.md): a measured run
// states it and must be at it, since the metrics compare its samples with the simulation's one for
// one; synthetic runs are written at it
inline constexpr double kContractRateHz = 100.0;

inline constexpr const char* kMetadataFile = "metadata.json";
inline constexpr const char* kMeasuredFormat = "talus-measured-run";
inline constexpr int kMeasuredVersion = 1;

using Series2 = std::vector<std::pair<double, double>>;

struct MeasuredMetadata {
  std::string scenario;        // the scenario the inputs belong to, e.g. "HD27"
  std::string machine;         // machine data file name, e.g. "wa320"
  double sample_rate_hz = kContractRateHz;
  double pile_toe_x_m = 0.0;   // where the pile's toe lies in the machine's frame
  Series2 pile_scan;           // (x, z) [m], x increasing
  Series2 drive, lift, tilt;   // operator target speeds (t [s], v [m/s]), t increasing
  double loaded_mass_kg = 0.0;
  double work_J = 0.0;
};

struct MeasuredRun {
  Run run;  // timeseries.csv and summary.json
  MeasuredMetadata meta;
};

// the three files of `dir`, checked; InputError naming file, line or field, and the fix
MeasuredRun load_measured_run(const std::filesystem::path& dir);
MeasuredMetadata load_metadata(const std::filesystem::path& file);
// writes metadata.json (a temporary name, then renamed)
void save_metadata(const std::filesystem::path& file, const MeasuredMetadata& meta);

}  // namespace talus::sim2real
