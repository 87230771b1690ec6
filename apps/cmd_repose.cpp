// talus repose: the heap test of the gravel (terrain/heap.hpp), angle of repose and bulk density.
#include <chrono>
#include <iostream>

#include "apps/commands.hpp"
#include "apps/outputs.hpp"
#include "host/device.hpp"
#include "host/files.hpp"
#include "io/image.hpp"
#include "io/output.hpp"
#include "terrain/heap.hpp"

namespace talus::app {

void add_repose_command(CLI::App& app, const std::string& command_line) {
  struct Options {
    std::string out;
    HeapOptions heap;
    Material material = gravel();
    bool quiet = false;
  };
  auto opt = std::make_shared<Options>();
  auto* cmd = app.add_subcommand("repose", "heap test: angle of repose and bulk density of the gravel");
  cmd->add_option("--out", opt->out, "output folder (particles.csv, particles.vtp, side.png, summary.json)")->required();
  // from fine gravel (10 mm) to a boulder (1 m): the levels' grains are 50-400 mm
  cmd->add_option("--diameter", opt->heap.diameter, "mean particle diameter D [m]")
      ->check(number_in(0.01, 1.0, "m"));
  cmd->add_option("--columns", opt->heap.columns, "column width in particles")->check(CLI::Range(4, 200));
  cmd->add_option("--layers", opt->heap.layers, "column height in particles")->check(CLI::Range(4, 400));
  cmd->add_option("--iterations", opt->heap.iterations, "PGS sweeps per step")->check(CLI::Range(1, 100000));
  cmd->add_option("--dt", opt->heap.dt, "timestep [s]")
      ->check(number_in(kMinTimestep, kMaxTimestep, "s"));
  cmd->add_option("--seed", opt->heap.seed, "random seed of the particle sizes and jitter");
  cmd->add_option("--friction", opt->material.friction,
                  "Coulomb friction (default: the gravel's 0.3)")
      ->check(number_in(0.0, kMaxContactCoefficient, ""));
  cmd->add_option("--rolling", opt->material.rolling,
                  "rolling resistance mu_r, torque <= mu_r R* lambda_n (default: the paper's 0.02; "
                  "docs/soil.md)")
      ->check(number_in(0.0, kMaxContactCoefficient, ""));
  cmd->add_option("--wall-speed", opt->heap.wall_speed,
                  "speed the walls retreat at before removal, 0 = at once [m/s]")
      // slower than 10 mm/s the walls take hours to clear the heap (the pile's formwork has the
      // same floor, terrain/pile.cpp); faster than 10 m/s they throw it
      ->check(number_in(0.01, 10.0, "m/s", true));
  cmd->add_flag("--quiet", opt->quiet, "no progress on stderr");
  cmd->callback([opt, command_line] {
    start_output_folder(opt->out);
    auto t0 = std::chrono::steady_clock::now();
    Device dev;
    double wall_time = opt->heap.wall_speed > 0 ? opt->heap.wall_travel / opt->heap.wall_speed : 0.0;
    Progress progress("repose", opt->heap.max_fill_time + wall_time + opt->heap.max_runout_time, !opt->quiet);
    HeapResult r = run_heap_test(dev, opt->material, opt->heap, &progress);
    double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    progress.finish();
    write_file_atomically(opt->out + "/particles.csv", particles_csv(r.final_state));
    write_file_atomically(opt->out + "/particles.vtp", particles_vtp(r.final_state));
    side_view(r.final_state).write_png(opt->out + "/side.png");
    nlohmann::json j = {{"repose_angle_deg", r.repose_angle_deg},
                        {"repose_spread_deg", r.repose_spread_deg},
                        {"sectors", r.sectors},
                        {"bulk_density", r.bulk_density},
                        {"heap_height_m", r.heap_height},
                        {"particles", r.particles},
                        {"diameter_m", opt->heap.diameter},
                        {"friction", opt->material.friction},
                        {"rolling_resistance", opt->material.rolling},
                        {"wall_speed_m_s", opt->heap.wall_speed},
                        {"sim_time_s", r.sim_time},
                        {"wall_s", wall},
                        {"device", dev.description()},
                        {"anchor", {{"repose_angle_deg", 21.0}, {"bulk_density", 1727.0}}}};
    add_provenance(j, command_line);
    write_json(opt->out + "/summary.json", j);
    std::cout << j.dump(2) << "\n";
  });
}

}  // namespace talus::app
