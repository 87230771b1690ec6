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
#include "apps/outputs.hpp"
#include "apps/run.hpp"
#include "host/error.hpp"
#include "host/files.hpp"
#include "sim2real/measured.hpp"
#include "sim2real/synthetic.hpp"
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
  const std::map<std::string, double> sigma = sim2real::parse_sensor_noise(o.noise, "--noise");
  const vehicle::Scenario sc =
      sim2real::varied_inputs(vehicle::load_scenario(o.run.scenario), o.vary_inputs, o.noise_seed ^ 0x5eedu);
  const fs::path out = fs::absolute(o.run.out).lexically_normal();
  const fs::path key = fs::absolute(o.answer_key.empty() ? out.string() + ".answer.json" : o.answer_key).lexically_normal();
  const auto rel = key.lexically_relative(out);
  if (!rel.empty() && *rel.begin() != "..")
    throw InputError("--answer-key: " + key.string() + " lies inside the data folder " + out.string() +
                     "; put it elsewhere (the loop must not be able to read it)");
  // the key's folder is made now (as the run's would be), then the key checked writable
  std::error_code made;
  fs::create_directories(key.parent_path(), made);
  check_output_file(key.string(), "--answer-key");
  // the data folder without a previous summary: summary.json, written last, marks it complete
  start_output_folder(out.string());

  // the simulation, in a work folder next to the output
  RunOptions run = o.run;
  const fs::path work = out.string() + ".work-" + std::to_string(::getpid());
  run.out = work.string();
  run.snapshot_interval = 0.0;
  run.scenario_data = std::make_shared<const vehicle::Scenario>(sc);
  run_scenario(run);

  // the channels with noise; mass and work as the sensors measured them
  sim2real::Run r = sim2real::load_run(work);
  sim2real::add_sensor_noise(r.series, sigma, o.noise_seed);
  sim2real::RunSummary summary;
  summary.loaded_mass_kg = r.summary.loaded_mass_kg;
  summary.work_J = r.summary.work_J;
  summary.scenario = sc.name;
  summary.fidelity = "field";
  summary.dig_start_s = r.summary.dig_start_s;
  summary.dig_end_s = r.summary.dig_end_s;
  const sim2real::MeasuredMetadata meta = sim2real::synthetic_metadata(sc, read_scan(work / "scan.csv"), summary);
  const nlohmann::json effects = r.summary.details.value("effects", nlohmann::json::array());

  // the measured run, and the answer key elsewhere
  sim2real::save_timeseries(out / sim2real::kTimeseriesFile, r.series);
  sim2real::save_metadata(out / sim2real::kMetadataFile, meta);
  sim2real::save_summary(out / sim2real::kSummaryFile, summary);
  nlohmann::json noise_json = nlohmann::json::object();
  for (const auto& [k, v] : sigma) noise_json[k] = v;
  const nlohmann::json answer = {{"data", out.string()},
                                 {"scenario", sc.name},
                                 {"fidelity", o.run.fidelity},
                                 {"effects", effects},
                                 {"effect_plugins", o.run.effect_plugins},
                                 {"noise_sigma", noise_json},
                                 {"noise_seed", o.noise_seed},
                                 {"vary_inputs", o.vary_inputs},
                                 {"pile_seed", o.run.seed}};
  // the provenance goes with the key, not the data: the command line names the effects the loop
  // must find
  nlohmann::json key_json = answer;
  add_provenance(key_json, o.run.command_line);
  write_json(key.string(), key_json);
  fs::remove_all(work);
  if (!o.run.quiet)
    std::cerr << "talus synth: measured run in " << out.string() << " (timeseries.csv, summary.json, metadata.json); "
              << "answer key in " << key.string() << "\n";
}

}  // namespace

void add_synth_command(CLI::App& app, const std::string& command_line) {
  auto o = std::make_shared<SynthOptions>();
  o->run.command_line = command_line;
  auto* cmd = app.add_subcommand("synth", "field-like data from a scenario with effects and sensor noise; the "
                                          "answer key goes to a separate file");
  cmd->add_option("--scenario", o->run.scenario, "scenario name or path (fb35, hd27, rd21, flat-lift)")->required();
  cmd->add_option("--fidelity", o->run.fidelity,
                  "level for pile scenarios (D400 ... D50, G400 ... G50)")
      ->capture_default_str();
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
