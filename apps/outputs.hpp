// What every command that writes a folder shares (talus run, pile, repose, soil, cut, sweep,
// synth): the folder is started without a previous summary.json, and summary.json is written last
// with the talus and the command line that made it, so it marks the folder as complete. A command
// killed midway leaves a folder without a summary, which nothing can take for a finished one.
// The soil tests write the particles at the end (particles.csv with x,y,z,r,vx,vy,vz;
// particles.vtp for ParaView; side.png) before their summary. Each file is written to a temporary
// name and renamed (io/output).
#pragma once
#include <cstdint>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <system_error>

#include "host/error.hpp"
#include "host/files.hpp"
#include "host/version.hpp"
#include "io/image.hpp"
#include "io/output.hpp"
#include "sim2real/timeseries.hpp"
#include "solvers/particles.hpp"

namespace talus::app {

// the output folder, made and checked writable, without a previous command's summary.json
inline void start_output_folder(const std::string& out) {
  make_output_dir(out);
  std::error_code ec;
  std::filesystem::remove(std::filesystem::path(out) / sim2real::kSummaryFile, ec);
  if (ec)
    throw InputError("--out " + out + ": cannot remove the previous " + sim2real::kSummaryFile +
                     " (" + ec.message() + ")");
}

// refuse output that would not fit before it is written: `bytes` estimated for `what` against the
// `available` bytes of the file system it goes to; the InputError names the estimate, the free
// space and `fix`. (A run whose disk fills midway loses its summary and figures after hours.)
inline void check_room(double bytes, std::uintmax_t available, const std::string& what,
                       const std::string& fix) {
  if (bytes <= static_cast<double>(available)) return;
  auto gigabytes = [](double b) {
    std::ostringstream s;
    s << std::setprecision(3) << b / 1e9 << " GB";
    return s.str();
  };
  throw InputError(what + " would write about " + gigabytes(bytes) + ", where " +
                   gigabytes(static_cast<double>(available)) + " is free; " + fix);
}

// which talus made a summary and how: version, git commit of the build, the command as typed
inline void add_provenance(nlohmann::json& summary, const std::string& command_line) {
  summary["talus_version"] = talus_version();
  summary["git_commit"] = git_commit();
  summary["command_line"] = command_line;
}

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
