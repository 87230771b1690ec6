// talus soil: the calibration tests of the gravel (issue 11) at a fidelity level's particle size,
// timestep and sweeps, with the geometry fixed in particle diameters so the levels compare:
//   repose   heap test (terrain/heap): repose_angle_deg, bulk_density
//   shear    direct shear (terrain/shear_test): peak_friction_deg, critical_friction_deg, dilatancy_deg
//   collapse planar column collapse (terrain/collapse_test): aspect_ratio, runout_ratio
// Writes DIR/summary.json, DIR/particles.csv (x,y,z,r,vx,vy,vz at the end), particles.vtp and
// side.png; the shear test also shear.csv and shear.png (stress ratio and platen rise against travel).
#include <chrono>
#include <iostream>
#include <sstream>

#include "apps/commands.hpp"
#include "apps/outputs.hpp"
#include "host/device.hpp"
#include "host/error.hpp"
#include "host/files.hpp"
#include "io/image.hpp"
#include "io/plot.hpp"
#include "terrain/collapse_test.hpp"
#include "terrain/heap.hpp"
#include "terrain/pile.hpp"
#include "terrain/shear_test.hpp"
#include "terrain/soil_sample.hpp"

namespace talus::app {

namespace {

struct SoilOptions {
  std::string test;
  std::string level = "D200";
  std::string out;
  std::string json;
  Material material = gravel();
  unsigned seed = 1;
  double aspect = 1.0;
  double normal_stress = ShearOptions{}.normal_stress;
  bool quiet = false;
};

// the shear series as CSV and as a two-panel figure
void write_shear_outputs(const std::string& dir, const ShearResult& r, double diameter) {
  std::ostringstream csv;
  csv << "travel_m,travel_D,shear_stress_Pa,normal_stress_Pa,stress_ratio,platen_rise_m\n";
  Figure fig;
  fig.x_label = "shear travel [D]";
  Series ratio, rise;
  for (const ShearSample& x : r.series) {
    const double q = x.normal_stress > 0.0 ? x.shear_stress / x.normal_stress : 0.0;
    csv << x.travel << ',' << x.travel / diameter << ',' << x.shear_stress << ',' << x.normal_stress << ',' << q
        << ',' << x.platen_z << '\n';
    ratio.x.push_back(x.travel / diameter);
    ratio.y.push_back(q);
    rise.x.push_back(x.travel / diameter);
    rise.y.push_back(x.platen_z / diameter);
  }
  write_file_atomically(dir + "/shear.csv", csv.str());
  ratio.colour = series_colour(0);
  rise.colour = series_colour(1);
  char title[160];
  std::snprintf(title, sizeof title, "peak %.1f deg, critical state %.1f deg, dilatancy %.1f deg",
                r.peak_friction_deg, r.critical_friction_deg, r.dilatancy_deg);
  fig.add_panel("tau / sigma", title).series.push_back(ratio);
  fig.add_panel("platen rise [D]").series.push_back(rise);
  fig.write_png(dir + "/shear.png", 900, 700);
}

}  // namespace

void add_soil_command(CLI::App& app, const std::string& command_line) {
  auto opt = std::make_shared<SoilOptions>();
  auto* cmd = app.add_subcommand("soil", "calibration tests of the gravel at a level's particle size: "
                                         "heap (repose), direct shear, planar column collapse");
  cmd->add_option("--test", opt->test, "repose, shear or collapse")
      ->required()
      ->check(CLI::IsMember({"repose", "shear", "collapse"}));
  cmd->add_option("--level", opt->level, "fidelity level whose D, timestep and sweeps the test uses (D400, D200, D100, D50)")
      ->capture_default_str();
  cmd->add_option("--out", opt->out, "output folder (summary.json, particles.csv, particles.vtp, side.png)")->required();
  cmd->add_option("--json", opt->json, "also write the summary to this file ('-' for stdout)");
  cmd->add_option("--rolling", opt->material.rolling,
                  "rolling resistance mu_r, torque <= mu_r R* lambda_n (default: the paper's 0.02; "
                  "docs/soil.md)")
      ->check(number_in(0.0, kMaxContactCoefficient, ""))
      ->capture_default_str();
  cmd->add_option("--friction", opt->material.friction, "Coulomb friction between grains")
      ->check(number_in(0.0, kMaxContactCoefficient, ""))
      ->capture_default_str();
  cmd->add_option("--seed", opt->seed, "random seed of the particle sizes and jitter")->capture_default_str();
  cmd->add_option("--aspect", opt->aspect, "collapse: column height over length asked for")->check(finite_number())
      ->check(CLI::Range(0.1, 3.0))
      ->capture_default_str();
  // from a few grains' weight (1 kPa) to a 50 m column of gravel (0.85 MPa at 1727 kg/m^3)
  cmd->add_option("--normal-stress", opt->normal_stress, "shear: the platen's normal stress [Pa]")
      ->check(number_in(1e3, 1e6, "Pa"))
      ->capture_default_str();
  cmd->add_flag("--quiet", opt->quiet, "no progress on stderr");
  cmd->callback([opt, command_line] {
    const FidelityPreset& level = fidelity_preset(opt->level);
    start_output_folder(opt->out);
    check_output_file(opt->json, "--json");
    const auto t0 = std::chrono::steady_clock::now();
    Device dev;
    Progress progress("soil " + opt->test + " " + level.name, 0.0, !opt->quiet);
    nlohmann::json j = {{"test", opt->test},
                        {"level", level.name},
                        {"diameter_m", level.diameter},
                        {"dt_s", level.dt},
                        {"iterations", level.iterations},
                        {"friction", opt->material.friction},
                        {"rolling_resistance", opt->material.rolling},
                        {"seed", opt->seed}};
    Particles final_state;
    if (opt->test == "repose") {
      // the heap column of terrain/heap in diameters: 12 x 12 x 22 sites
      HeapOptions h;
      h.diameter = level.diameter;
      h.dt = level.dt;
      h.iterations = level.iterations;
      h.seed = opt->seed;
      h.wall_travel = 10.0 * level.diameter;
      h.wall_speed = 2.0 * level.diameter;  // 0.2 m/s at D = 0.1 m, the protocol of docs/dem.md's table
      const HeapResult r = run_heap_test(dev, opt->material, h, &progress);
      j["repose_angle_deg"] = r.repose_angle_deg;
      j["repose_spread_deg"] = r.repose_spread_deg;
      j["bulk_density"] = r.bulk_density;
      j["particles"] = r.particles;
      j["sim_time_s"] = r.sim_time;
      // a heap of the paper's spheres: 21 deg (docs/soil.md; the paper's 32 deg is its soil's
      // internal friction, held by the shear test); the field's bulk density
      j["anchor"] = {{"repose_angle_deg", 21.0}, {"bulk_density", 1727.0}};
      final_state = r.final_state;
    } else if (opt->test == "shear") {
      ShearOptions s = at_level<ShearOptions>(level);
      s.seed = opt->seed;
      s.normal_stress = opt->normal_stress;
      const ShearResult r = run_shear_test(dev, opt->material, s, &progress);
      j["peak_friction_deg"] = r.peak_friction_deg;
      j["critical_friction_deg"] = r.critical_friction_deg;
      j["dilatancy_deg"] = r.dilatancy_deg;
      j["peak_travel_D"] = r.peak_travel / level.diameter;
      j["bulk_density"] = r.bulk_density;
      j["normal_stress_Pa"] = s.normal_stress;
      j["shear_speed_m_s"] = s.speed;
      j["particles"] = r.particles;
      j["sim_time_s"] = r.sim_time;
      j["anchor"] = {{"internal_friction_deg", 32.0}, {"dilatancy_deg", 8.0}, {"bulk_density", 1727.0}};
      write_shear_outputs(opt->out, r, level.diameter);
      final_state = r.final_state;
    } else {
      CollapseOptions c = at_level<CollapseOptions>(level);
      c.seed = opt->seed;
      c.aspect = opt->aspect;
      const CollapseResult r = run_collapse_test(dev, opt->material, c, &progress);
      j["aspect_ratio"] = r.aspect_ratio;
      j["runout_ratio"] = r.runout_ratio;
      j["initial_length_m"] = r.initial_length;
      j["initial_height_m"] = r.initial_height;
      j["final_length_m"] = r.final_length;
      j["final_height_m"] = r.final_height;
      j["particles"] = r.particles;
      j["sim_time_s"] = r.sim_time;
      // Lube et al. 2005 / Lajeunesse et al. 2005, planar, a below 2-3: (L - L0)/L0 = lambda a
      j["anchor"] = {{"runout_ratio_low", 1.2 * r.aspect_ratio}, {"runout_ratio_high", 1.8 * r.aspect_ratio}};
      final_state = r.final_state;
    }
    progress.finish();
    j["wall_s"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    j["device"] = dev.description();
    add_provenance(j, command_line);
    write_particles_and_summary(opt->out, final_state, j, opt->json);
  });
}

}  // namespace talus::app
