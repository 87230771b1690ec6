// `talus synth --scenario S --fidelity F [--effect NAME:k=v ...] [--effect-plugin lib.so ...]
//  --noise SPEC --seed N --out DIR [--answer-key FILE]`: field-like data for the sim-to-real loop
// (issue 6). The scenario runs with the effects, its sensor channels get Gaussian noise, and DIR
// becomes a measured run (sim2real/measured.hpp: timeseries.csv, summary.json, metadata.json)
// with nothing in it that tells which effects made it. The answer key (effects, parameters,
// noise, seed) goes to a separate file outside DIR, which the loop never reads.
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>

#include "apps/commands.hpp"
#include "apps/run.hpp"
#include "host/error.hpp"
#include "host/files.hpp"
#include "sim2real/measured.hpp"
#include "vehicle/data_file.hpp"
#include "vehicle/scenario.hpp"

namespace talus::app {

namespace {

namespace fs = std::filesystem;

struct SynthOptions {
  RunOptions run;
  std::string noise = "default";
  std::string answer_key;
  unsigned noise_seed = 1;
  double vary_inputs = 0.0;  // the operator's variation between repetitions (0: the scenario's inputs)
};

// how far a repetition's commands may shift in time at --vary-inputs 1 [s]: an operator repeats a
// cycle to within a fraction of a second (a guess; the paper publishes one run per test)
constexpr double kTimingShiftPerVariation = 1.0;

// one repetition of the scenario by an operator who varies: each target-speed series scaled by
// 1 + v u and its inner breakpoints shifted by v u' kTimingShiftPerVariation (u, u' uniform in
// [-1, 1], drawn per series), kept inside (0, duration) and in order
vehicle::Scenario varied_inputs(vehicle::Scenario sc, double v, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (vehicle::PiecewiseLinear* series : {&sc.drive, &sc.lift, &sc.tilt}) {
    auto points = series->points();
    const double scale = 1.0 + v * u(rng);
    double shift = v * u(rng) * kTimingShiftPerVariation;
    if (points.size() > 2) {
      // the inner points move together; the first and last stay
      const double first = points[1].first, last = points[points.size() - 2].first;
      const double lo = -0.5 * std::max(0.0, first - points.front().first);
      const double hi = 0.5 * std::max(0.0, std::min(sc.duration, points.back().first) - last);
      shift = std::clamp(shift, lo, hi);
    }
    for (size_t i = 0; i < points.size(); ++i) {
      points[i].second *= scale;
      if (i > 0 && i + 1 < points.size()) points[i].first += shift;
    }
    *series = vehicle::PiecewiseLinear(points);
  }
  return sc;
}

// the sensor noise of `--noise default`, one standard deviation per channel in its SI unit:
// load-cell and pressure-derived forces about 1 % of their range, a wheel-revolution speed
// sensor a few cm/s, draw-wire extensions a millimetre, potentiometer angles a fifth of a degree,
// laser positions a couple of centimetres, power (computed from forces and speeds) about 1 kW, a
// percent of the engine's (orders of magnitude of the paper's instrumentation, Table 1; no
// per-sensor data is published)
const std::map<std::string, double>& default_noise() {
  static const std::map<std::string, double> sigma = {
      {"f_lift", 5e3},    {"f_tilt", 3e3},      {"f_traction", 2e3}, {"v_drive", 0.02},
      {"d_lift", 1e-3},   {"d_tilt", 1e-3},     {"boom_deg", 0.2},   {"bucket_deg", 0.2},
      {"pitch_deg", 0.1}, {"x_vehicle", 0.02},  {"bucket_tip_x", 0.02}, {"bucket_tip_z", 0.02},
      {"power", 1e3}};
  return sigma;
}

// "none", "default", or channel=sigma pairs separated by commas ("default,f_lift=1e4" adds to
// the defaults); InputError naming the bad part
std::map<std::string, double> parse_noise(const std::string& spec) {
  std::map<std::string, double> sigma;
  std::stringstream in(spec);
  std::string part;
  while (std::getline(in, part, ',')) {
    if (part == "none") continue;
    if (part == "default") {
      for (const auto& [k, v] : default_noise()) sigma[k] = v;
      continue;
    }
    const auto eq = part.find('=');
    const std::string channel = part.substr(0, eq);
    bool known = false;
    for (size_t c = 1; c < sim2real::kChannelCount; ++c) known = known || channel == sim2real::kChannelNames[c];
    if (eq == std::string::npos || !known)
      throw InputError("--noise: '" + part + "' is not none, default or CHANNEL=SIGMA with a channel of the "
                       "contract (f_lift, f_tilt, f_traction, v_drive, d_lift, ...)");
    double value = 0.0;
    try {
      value = std::stod(part.substr(eq + 1));
    } catch (const std::exception&) {
      throw InputError("--noise: '" + part + "': the standard deviation is not a number");
    }
    if (!(value >= 0.0) || !std::isfinite(value))
      throw InputError("--noise: '" + part + "': the standard deviation must be a finite number >= 0");
    sigma[channel] = value;
  }
  return sigma;
}

sim2real::Series2 points(const vehicle::PiecewiseLinear& f) {
  sim2real::Series2 out;
  for (const auto& p : f.points()) out.push_back(p);
  return out;
}

// scan.csv of a run (x,z per line after a header); a single ground point when there is none
sim2real::Series2 read_scan(const fs::path& file) {
  sim2real::Series2 out;
  std::ifstream in(file);
  std::string line;
  std::getline(in, line);
  while (std::getline(in, line)) {
    const auto comma = line.find(',');
    if (comma == std::string::npos) continue;
    out.emplace_back(std::stod(line.substr(0, comma)), std::stod(line.substr(comma + 1)));
  }
  std::sort(out.begin(), out.end());
  if (out.empty()) out.emplace_back(0.0, 0.0);
  return out;
}

void synth(const SynthOptions& o) {
  // everything checked before the simulation: noise, scenario, answer key outside the data
  const std::map<std::string, double> sigma = parse_noise(o.noise);
  const vehicle::Scenario sc = varied_inputs(vehicle::load_scenario(o.run.scenario), o.vary_inputs, o.noise_seed ^ 0x5eedu);
  const fs::path out = fs::absolute(o.run.out).lexically_normal();
  const fs::path key = fs::absolute(o.answer_key.empty() ? out.string() + ".answer.json" : o.answer_key).lexically_normal();
  const auto rel = key.lexically_relative(out);
  if (!rel.empty() && *rel.begin() != "..")
    throw InputError("--answer-key: " + key.string() + " lies inside the data folder " + out.string() +
                     "; put it elsewhere (the loop must not be able to read it)");

  // the simulation, in a work folder next to the output
  RunOptions run = o.run;
  const fs::path work = out.string() + ".work-" + std::to_string(::getpid());
  run.out = work.string();
  run.snapshot_interval = 0.0;
  run.scenario_data = std::make_shared<const vehicle::Scenario>(sc);
  run_scenario(run);

  // the channels with noise; mass and work as the sensors measured them
  sim2real::Run r = sim2real::load_run(work);
  std::mt19937_64 rng(o.noise_seed);
  for (size_t c = 1; c < sim2real::kChannelCount; ++c) {
    const auto it = sigma.find(sim2real::kChannelNames[c]);
    if (it == sigma.end() || it->second == 0.0) continue;
    std::normal_distribution<double> noise(0.0, it->second);
    for (double& x : r.series.columns[c]) x += noise(rng);
  }
  sim2real::RunSummary summary;
  summary.loaded_mass_kg = r.summary.loaded_mass_kg;
  summary.work_J = r.summary.work_J;
  summary.scenario = sc.name;
  summary.fidelity = "field";
  summary.dig_start_s = r.summary.dig_start_s;
  summary.dig_end_s = r.summary.dig_end_s;
  sim2real::MeasuredMetadata meta;
  meta.scenario = sc.name;
  meta.machine = sc.machine;
  meta.sample_rate_hz = 100.0;
  meta.pile_toe_x_m = sc.pile_toe_x;
  meta.pile_scan = read_scan(work / "scan.csv");
  meta.drive = points(sc.drive);
  meta.lift = points(sc.lift);
  meta.tilt = points(sc.tilt);
  meta.loaded_mass_kg = summary.loaded_mass_kg;
  meta.work_J = summary.work_J;
  const nlohmann::json simulated = nlohmann::json::parse(std::ifstream(work / sim2real::kSummaryFile));

  // the measured run, and the answer key elsewhere
  make_output_dir(out.string());
  sim2real::save_timeseries(out / sim2real::kTimeseriesFile, r.series);
  sim2real::save_summary(out / sim2real::kSummaryFile, summary);
  sim2real::save_metadata(out / sim2real::kMetadataFile, meta);
  nlohmann::json noise_json = nlohmann::json::object();
  for (const auto& [k, v] : sigma) noise_json[k] = v;
  const nlohmann::json answer = {{"data", out.string()},
                                 {"scenario", sc.name},
                                 {"fidelity", o.run.fidelity},
                                 {"effects", simulated.value("effects", nlohmann::json::array())},
                                 {"effect_plugins", o.run.effect_plugins},
                                 {"noise_sigma", noise_json},
                                 {"noise_seed", o.noise_seed},
                                 {"vary_inputs", o.vary_inputs},
                                 {"pile_seed", o.run.seed}};
  write_json(key.string(), answer);
  fs::remove_all(work);
  if (!o.run.quiet)
    std::cerr << "talus synth: measured run in " << out.string() << " (timeseries.csv, summary.json, metadata.json); "
              << "answer key in " << key.string() << "\n";
}

}  // namespace

void add_synth_command(CLI::App& app) {
  auto o = std::make_shared<SynthOptions>();
  auto* cmd = app.add_subcommand("synth", "field-like data from a scenario with effects and sensor noise; the "
                                          "answer key goes to a separate file");
  cmd->add_option("--scenario", o->run.scenario, "scenario name or path (fb35, hd27, rd21, flat-lift)")->required();
  cmd->add_option("--fidelity", o->run.fidelity, "particle level for pile scenarios")->capture_default_str();
  cmd->add_option("--effect", o->run.effects, "an effect NAME:param=value,... (repeatable; docs/effects.md)");
  cmd->add_option("--effect-plugin", o->run.effect_plugins, "a shared library with more effects (repeatable)");
  cmd->add_option("--noise", o->noise, "sensor noise: none, default, or CHANNEL=SIGMA,... (SI units; "
                                       "'default,f_lift=1e4' changes one)")->capture_default_str();
  cmd->add_option("--seed", o->noise_seed, "random seed of the noise")->capture_default_str();
  cmd->add_option("--vary-inputs", o->vary_inputs, "vary the operator's inputs like a repetition of the test: "
                                                   "each series scaled by up to this fraction and shifted by up to "
                                                   "this many seconds (drawn from --seed; metadata.json records them)")
      ->capture_default_str()->check(finite_number())->check(CLI::Range(0.0, 0.5));
  cmd->add_option("--pile-seed", o->run.seed, "random seed of the pile's particles")->capture_default_str();
  cmd->add_option("--out", o->run.out, "the measured-run folder to write")->required();
  cmd->add_option("--answer-key", o->answer_key, "where the answer key goes (default: OUT.answer.json, beside OUT)");
  cmd->add_flag("--quiet", o->run.quiet, "no progress on stderr");
  cmd->callback([o] { synth(*o); });
}

}  // namespace talus::app
