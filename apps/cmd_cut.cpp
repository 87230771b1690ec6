// talus cut: the quasi-static cutting test (terrain/cutting_test) at a fidelity level: a flat
// vertical blade pushed at constant depth through a level bed, its mean horizontal force against
// the fundamental earthmoving equation. Writes DIR/summary.json (force_N, fee_force_N, the force
// series), DIR/cut.csv, DIR/cut.png, DIR/particles.csv (x,y,z,r,vx,vy,vz), particles.vtp, side.png.
// At a type-G level the bed is the multiscale terrain's voxels and the blade meets the soil through
// the aggregate (terrain/cutting_test's run_multiscale_cutting_test); the particles are the zone's.
#include <chrono>
#include <iostream>
#include <sstream>

#include "apps/commands.hpp"
#include "apps/outputs.hpp"
#include "host/device.hpp"
#include "host/files.hpp"
#include "io/image.hpp"
#include "io/plot.hpp"
#include "terrain/aggregate.hpp"
#include "terrain/cutting_test.hpp"
#include "terrain/pile.hpp"
#include "terrain/soil_sample.hpp"

namespace talus::app {

void add_cut_command(CLI::App& app, const std::string& command_line) {
  struct Options {
    std::string level = "D200";
    std::string out;
    std::string json;
    CuttingOptions cut;
    Material material = gravel();
    bool quiet = false;
  };
  auto opt = std::make_shared<Options>();
  auto* cmd = app.add_subcommand("cut", "quasi-static cutting of a level bed by a flat blade, against the "
                                        "fundamental earthmoving equation");
  cmd->add_option("--level", opt->level,
                  "fidelity level whose D, timestep and sweeps the test uses: D400 ... D50 cut "
                  "particles, G400 ... G50 "
                  "the multiscale terrain (the equation then takes phi + psi = 40 deg, and --phi "
                  "and --rolling do not apply)")
      ->capture_default_str();
  cmd->add_option("--depth", opt->cut.depth, "cutting depth below the bed's mean surface [m]")
      ->check(finite_number())
      ->check(positive_number())
      ->capture_default_str();
  cmd->add_option("--out", opt->out, "output folder (summary.json, cut.csv, cut.png, particles.csv, ...)")->required();
  cmd->add_option("--json", opt->json, "also write the summary to this file ('-' for stdout)");
  // quasi-static (10 mm/s) to faster than a loader drives into a pile
  cmd->add_option("--speed", opt->cut.speed, "blade speed [m/s]")
      ->check(number_in(0.01, 2.0, "m/s"))
      ->capture_default_str();
  // the bed is built as long as the travel: up to twice a bucket's fill length in the field runs
  cmd->add_option("--travel", opt->cut.travel, "blade travel [m]")
      ->check(number_in(0.1, 6.0, "m"))
      ->capture_default_str();
  cmd->add_option("--phi", opt->cut.internal_friction_deg, "internal friction angle of the soil for the equation [deg]")->check(finite_number())
      ->check(CLI::Range(1.0, 80.0))
      ->capture_default_str();
  cmd->add_option("--rolling", opt->material.rolling, "rolling resistance mu_r of the gravel")
      ->check(number_in(0.0, kMaxContactCoefficient, ""))
      ->capture_default_str();
  cmd->add_option("--seed", opt->cut.seed, "random seed of the bed")->capture_default_str();
  cmd->add_option("--interface-damping-time", opt->cut.interface_damping_time,
                  "study, type G: the SPOOK damping time of the aggregate's interfaces [s] instead "
                  "of two of the level's steps (0, the default), as talus run's")
      ->check(number_in(kMinDampingTime, kMaxDampingTime, "s", true))
      ->capture_default_str();
  cmd->add_flag("--quiet", opt->quiet, "no progress on stderr");
  cmd->callback([opt, command_line] {
    // a type-D level cuts a bed of particles, a type-G one the voxels through the aggregate
    const FidelityPreset& level = level_preset(opt->level);
    const bool multiscale = is_multiscale(level);
    const CuttingOptions c = at_level(level, opt->cut);
    check_cutting_options(c);  // bad input leaves no output folder behind
    if (!multiscale && c.interface_damping_time != 0.0)
      throw InputError("--interface-damping-time at " + level.name +
                       ": only the type-G levels cut through an aggregate with interfaces; give "
                       "--level G400 (or finer) or leave the option out");
    start_output_folder(opt->out);
    check_output_file(opt->json, "--json");
    const auto t0 = std::chrono::steady_clock::now();
    Device dev(run_device_choice(level));
    Progress progress("cut " + level.name, 0.0, !opt->quiet);
    const BulkSoil soil;
    const CuttingResult r = multiscale ? run_multiscale_cutting_test(dev, level, c, soil, &progress)
                                       : run_cutting_test(dev, opt->material, c, &progress);
    progress.finish();

    std::ostringstream csv;
    csv << "travel_m,force_x_N,force_z_N,surcharge_m,fee_force_N\n";
    Series force, fee;
    nlohmann::json travel = nlohmann::json::array(), fx = nlohmann::json::array(), fz = nlohmann::json::array(),
                   heap = nlohmann::json::array(), fe = nlohmann::json::array();
    for (const CuttingSample& x : r.series) {
      csv << x.travel << ',' << x.force_x << ',' << x.force_z << ',' << x.surcharge << ',' << x.fee_force << '\n';
      travel.push_back(x.travel);
      fx.push_back(x.force_x);
      fz.push_back(x.force_z);
      heap.push_back(x.surcharge);
      fe.push_back(x.fee_force);
      force.x.push_back(x.travel);
      force.y.push_back(1e-3 * x.force_x);
      fee.x.push_back(x.travel);
      fee.y.push_back(1e-3 * x.fee_force);
    }
    write_file_atomically(opt->out + "/cut.csv", csv.str());
    force.colour = series_colour(0);
    force.label = "blade (talus " + level.name + ")";
    fee.colour = Rgb{0, 0, 0};
    fee.style = LineStyle::dashed;
    fee.label = multiscale ? "equation, the aggregate's load" : "equation, measured heap";
    Figure fig;
    fig.x_label = "blade travel [m]";
    char title[160];
    std::snprintf(title, sizeof title, "depth %.2f m: steady %.2f kN, equation %.2f kN", c.depth, 1e-3 * r.force,
                  1e-3 * r.fee_force);
    Panel& p = fig.add_panel("horizontal force [kN]", title);
    p.series = {force, fee};
    p.shaded.push_back(Range{0.0, r.steady_from});
    fig.write_png(opt->out + "/cut.png", 900, 500);

    // the aggregate's interfaces as the type-G cut set them
    AggregateParameters interfaces;
    interfaces.damping_time = c.interface_damping_time;
    nlohmann::json j = {
        {"level", level.name},
        {"diameter_m", level.diameter},
        {"dt_s", level.dt},
        {"iterations", level.iterations},
        {"depth_m", c.depth},
        {"width_m", r.width},
        {"speed_m_s", c.speed},
        // the aggregate's interfaces' damping time in use (type G; null for particles)
        {"interface_damping_time_s",
         multiscale ? nlohmann::json(interface_damping_time(interfaces, level.dt))
                    : nlohmann::json(nullptr)},
        {"force_N", r.force},
        {"force_spread_N", r.force_spread},
        {"fee_force_N", r.fee_force},
        {"fee_force_level_bed_N", r.fee_force_level},
        {"force_over_fee", r.fee_force > 0.0 ? r.force / r.fee_force : 0.0},
        {"fee_failure_angle_deg", r.fee_failure_angle_deg},
        {"model", multiscale ? "multiscale (type G)" : "particles (type D)"},
        {"internal_friction_deg",
         multiscale ? soil.effective_friction_deg() : c.internal_friction_deg},
        {"edge_force_N", r.edge_force},
        {"blade_friction", c.blade_friction},
        {"bed_density", r.bed_density},
        {"steady_from_m", r.steady_from},
        {"rolling_resistance", opt->material.rolling},
        {"seed", c.seed},
        {"particles", r.particles},
        {"sim_time_s", r.sim_time},
        {"wall_s", std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count()},
        {"device", dev.description()},
        {"series",
         {{"travel_m", travel},
          {"force_x_N", fx},
          {"force_z_N", fz},
          {"surcharge_m", heap},
          {"fee_force_N", fe}}}};
    add_provenance(j, command_line);
    write_particles_and_summary(opt->out, r.final_state, j, opt->json);
  });
}

}  // namespace talus::app
