// Writing results: every file goes to a temporary name first and is renamed into place, so an
// interrupted or failed run never leaves a half-written file behind nor clobbers an old one.
#pragma once
#include <nlohmann/json.hpp>
#include <string>

#include "terrain/particles.hpp"

namespace talus {

// creates the folder (and parents); InputError naming it when impossible
void make_output_dir(const std::string& dir);
// a temporary name next to `path`, unique to this process
std::string temporary_name(const std::string& path);
// writes `content` to a temporary name, then renames it to path
void write_file_atomically(const std::string& path, const std::string& content);
void write_json(const std::string& path, const nlohmann::json& j);

// particles as CSV with header x,y,z,r,vx,vy,vz (SI units)
std::string particles_csv(const Particles& particles);
// particles as VTK XML PolyData (.vtp, readable by ParaView): points with radius, velocity,
// speed and fixed arrays; one vertex cell per particle (use the Point Gaussian representation)
std::string particles_vtp(const Particles& particles);

}  // namespace talus
