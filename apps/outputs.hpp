// What every soil-test command writes last (talus soil, talus cut, talus repose): the particles at
// the end (particles.csv with x,y,z,r,vx,vy,vz; particles.vtp for ParaView; side.png) and the
// summary (DIR/summary.json, and with --json FILE a copy there, '-' for stdout). Each file is
// written to a temporary name and renamed (io/output), the summary last.
#pragma once
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>

#include "host/files.hpp"
#include "io/image.hpp"
#include "io/output.hpp"
#include "solvers/particles.hpp"

namespace talus::app {

inline void write_particles_and_summary(const std::string& dir, const Particles& particles,
                                        const nlohmann::json& summary, const std::string& json) {
  write_file_atomically(dir + "/particles.csv", particles_csv(particles));
  write_file_atomically(dir + "/particles.vtp", particles_vtp(particles));
  side_view(particles).write_png(dir + "/side.png");
  write_json(dir + "/summary.json", summary);
  if (json == "-")
    std::cout << summary.dump(2) << "\n";
  else if (!json.empty())
    write_json(json, summary);
}

}  // namespace talus::app
