// `talus run --scenario NAME --out DIR`: replay a scenario's feedforward target speeds on the wheel
// loader and write DIR/timeseries.csv (100 Hz sensors, SPEC §2.4) and DIR/summary.json.
// Scenarios with a particle pile need issue 4 and fail with a clear "not yet".
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "apps/commands.hpp"
#include "host/error.hpp"
#include "vehicle/data_file.hpp"
#include "vehicle/scenario.hpp"
#include "vehicle/sensors.hpp"
#include "vehicle/wheel_loader.hpp"

namespace talus::app {

namespace {

struct RunOptions {
  std::string scenario;
  std::string out;
  std::string json;
};

// write a file under a temporary name, then rename it into place
void write_atomically(const std::filesystem::path& path, const std::string& text) {
  const std::filesystem::path tmp = path.string() + ".tmp";
  {
    std::ofstream out(tmp);
    if (!out) throw Error("cannot write " + tmp.string() + "; check that the folder is writable");
    out << text;
    if (!out) throw Error("writing " + tmp.string() + " failed (disk full?)");
  }
  std::filesystem::rename(tmp, path);
}

void run(const RunOptions& o) {
  // the paper's pile scenarios, and any scenario with a pile, need the particles of issue 4
  for (const char* pile_scenario : {"FB35", "HD27", "RD21"}) {
    if (o.scenario == pile_scenario && vehicle::find_data_file(o.scenario, "scenarios").empty()) {
      throw Error("not yet: scenario " + o.scenario + " needs the particle pile (issue 4)");
    }
  }
  const vehicle::Scenario sc = vehicle::load_scenario(o.scenario);
  if (sc.pile) throw Error("not yet: scenario " + sc.name + " needs the particle pile (issue 4)");
  const std::string machine = vehicle::find_data_file(sc.machine, "machines");
  if (machine.empty()) {
    throw InputError(sc.path + ": field 'machine' names '" + sc.machine +
                     "', which is neither a file nor data/machines/" + sc.machine + ".json; fix the name");
  }
  std::filesystem::create_directories(o.out);

  vehicle::WheelLoader loader(machine, sc.payload);
  vehicle::SensorLog log(100.0);
  const int steps = static_cast<int>(std::llround(sc.duration / sc.timestep));
  std::cerr << "talus run: " << sc.name << ", " << sc.duration << " s at h = " << sc.timestep * 1e3 << " ms on "
            << loader.name() << " (" << loader.operating_mass() << " kg with payload)\n";
  const auto start = std::chrono::steady_clock::now();
  log.after_step(loader, 0.0, 0.0);
  const int progress_every = static_cast<int>(std::llround(1.0 / sc.timestep));
  for (int k = 0; k < steps; ++k) {
    // feedforward targets at the start of the step
    const double t = k * sc.timestep;
    loader.set_drive_speed(sc.drive(t));
    loader.set_lift_speed(sc.lift(t));
    loader.set_tilt_speed(sc.tilt(t));
    loader.step(sc.timestep);
    log.after_step(loader, (k + 1) * sc.timestep, sc.timestep);
    if ((k + 1) % progress_every == 0) {
      std::cerr << "\r  t = " << std::fixed << std::setprecision(1) << (k + 1) * sc.timestep << " s" << std::flush;
    }
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::cerr << "\n";

  // outputs: time series and summary, each written to a temporary name then renamed
  std::ostringstream csv;
  csv << std::setprecision(10) << vehicle::sensor_csv_header() << '\n';
  for (const auto& s : log.samples()) vehicle::write_sensor_csv_row(csv, s);
  const std::filesystem::path dir(o.out);
  write_atomically(dir / "timeseries.csv", csv.str());
  nlohmann::json summary = {{"scenario", sc.name},
                            {"work_J", log.work()},
                            {"sim_time_s", steps * sc.timestep},
                            {"wall_time_s", wall},
                            {"realtime_factor", wall > 0 ? steps * sc.timestep / wall : 0.0}};
  write_atomically(dir / "summary.json", summary.dump(2) + "\n");
  if (!o.json.empty()) {
    if (o.json == "-") {
      std::cout << summary.dump(2) << "\n";
    } else {
      write_atomically(o.json, summary.dump(2) + "\n");
    }
  }
  std::cerr << "talus run: wrote " << (dir / "timeseries.csv").string() << " (" << log.samples().size()
            << " samples) and summary.json; work " << log.work() / 1e3 << " kJ, real-time factor "
            << summary["realtime_factor"].get<double>() << "\n";
}

}  // namespace

void add_run_command(CLI::App& app) {
  auto opts = std::make_shared<RunOptions>();
  auto* cmd = app.add_subcommand("run", "replay a scenario's feedforward inputs on the wheel loader");
  cmd->add_option("--scenario", opts->scenario, "scenario name (data/scenarios/NAME.json) or path")->required();
  cmd->add_option("--out", opts->out, "output folder for timeseries.csv and summary.json")->required();
  cmd->add_option("--json", opts->json, "also write the summary to this file ('-' for stdout)");
  cmd->callback([opts] { run(*opts); });
}

}  // namespace talus::app
