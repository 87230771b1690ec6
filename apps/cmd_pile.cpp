// talus pile: build and settle the default pile (or a scanned profile) at a fidelity level.
#include <algorithm>
#include <chrono>
#include <iostream>

#include "apps/commands.hpp"
#include "apps/outputs.hpp"
#include "host/device.hpp"
#include "host/files.hpp"
#include "io/image.hpp"
#include "io/output.hpp"
#include "terrain/pile.hpp"
#include "terrain/settle.hpp"

namespace talus::app {

void add_pile_command(CLI::App& app, const std::string& command_line) {
  struct Options {
    std::string level = "D200";
    std::string out;
    std::string profile;
    PileBuildOptions build;
    bool quiet = false;
  };
  auto opt = std::make_shared<Options>();
  auto* cmd = app.add_subcommand("pile", "build and settle the gravel pile in its container");
  cmd->add_option("--level", opt->level, "fidelity level: D400, D200, D100, D50 (paper Table 3)")
      ->capture_default_str();
  cmd->add_option("--out", opt->out, "output folder (particles.csv, particles.vtp, side.png, scan.csv, summary.json)")->required();
  cmd->add_option("--profile", opt->profile, "pile profile JSON (default: data/piles/default.json)");
  cmd->add_option("--seed", opt->build.seed, "random seed of sizes and jitter");
  // at least the settling's minimum (PileBuildOptions::min_time, 1 s); ten minutes at most
  cmd->add_option("--max-time", opt->build.max_time, "longest settling time [s]")
      ->check(number_in(1.0, 600.0, "s"));
  cmd->add_option(
         "--form-speed", opt->build.form_speed,
         "with --free-face: speed the formwork withdraws at before the pile settles, 0 = removed "
         "at once [m/s]")
      // slower than 10 mm/s it takes hours to clear the face (build_pile refuses it too)
      ->check(number_in(0.01, 10.0, "m/s", true))
      ->capture_default_str();
  cmd->add_flag("--hold-face,!--free-face", opt->build.hold_face,
                "the formwork holds the face while the pile settles and is left out of the pile's "
                "container, so the face stands at its profile when a dig starts (the default); "
                "--free-face: it goes before the pile settles");
  cmd->add_option("--settle-iterations", opt->build.settle_iterations,
                  "study: sweeps per step while filling and settling, above the level's N_it too "
                  "(default: the level's N_it, at most 100)")
      ->check(CLI::Range(1, 100000));
  cmd->add_flag("--quiet", opt->quiet, "no progress on stderr");
  cmd->callback([opt, command_line] {
    const FidelityPreset& preset = fidelity_preset(opt->level);
    PileProfile profile = opt->profile.empty() ? default_pile_profile() : load_pile_profile(opt->profile);
    start_output_folder(opt->out);
    auto t0 = std::chrono::steady_clock::now();
    Device dev;
    // the fill settles for half the time, then the pile for the whole (terrain/pile.cpp)
    Progress progress("pile " + preset.name, 1.5 * opt->build.max_time, !opt->quiet);
    PileBuild pile = build_pile(dev, profile, preset, gravel(), opt->build, &progress);
    double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    progress.finish(std::to_string(pile.particles.size()) + " particles");
    write_file_atomically(opt->out + "/particles.csv", particles_csv(pile.particles));
    write_file_atomically(opt->out + "/particles.vtp", particles_vtp(pile.particles));
    side_view(pile.particles).write_png(opt->out + "/side.png");
    // the laser scan of the settled surface, as measured in the field before loading
    PileScan scan = scan_pile(pile.particles, profile, preset.diameter);
    write_file_atomically(opt->out + "/scan.csv", scan_csv(scan));
    int n = static_cast<int>(pile.particles.size());
    nlohmann::json j = {
        {"level", preset.name},
        {"diameter_m", preset.diameter},
        {"particles", n},
        {"paper_particles", preset.paper_particles},
        {"particles_vs_paper", double(n) / preset.paper_particles},
        {"bulk_density", pile.bulk_density},
        {"toe_shift_m", pile.toe_shift},
        {"fill_time_s", pile.fill_time},
        {"fill_at_rest", pile.fill_at_rest},
        {"fill_rms_speed_m_s", pile.fill_rms_speed},
        {"settle_iterations", pile.settle_iterations},
        {"settle_time_s", pile.settle_time},
        {"at_rest", pile.at_rest},
        {"rms_speed_m_s", pile.rms_speed},
        {"max_overlap_rel", max_overlap(pile.particles, pile.geoms) / preset.diameter},
        {"scan_points", scan.points.size()},
        {"scan_face_angle_deg", scan.face_angle_deg},
        {"scan_rms_to_profile_m", scan.rms_to_profile_m},
        {"scan_mean_to_profile_m", scan.mean_to_profile_m},
        {"soil_rms_to_profile_m", pile.soil_fit.rms_m},
        {"soil_mean_to_profile_m", pile.soil_fit.mean_m},
        {"profile", profile.name},
        {"profile_volume_m3", profile.volume()},
        {"wall_s", wall},
        // the DEM's device memory after settling, in all and per particle (a dig adds the bucket's)
        {"device_bytes", pile.device_bytes},
        {"device_bytes_per_particle", double(pile.device_bytes) / std::max(n, 1)},
        {"largest_buffer_bytes", pile.largest_buffer_bytes},
        {"device", dev.description()}};
    add_provenance(j, command_line);
    write_json(opt->out + "/summary.json", j);
    std::cout << j.dump(2) << "\n";
  });
}

}  // namespace talus::app
