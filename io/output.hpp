// Particle output: the state as CSV and as ParaView's PolyData, and a pile's laser scan as CSV,
// written with host/files.hpp's atomic writers.
#pragma once
#include <string>

#include "solvers/particles.hpp"
#include "terrain/pile.hpp"

namespace talus {

// particles as CSV with header x,y,z,r,vx,vy,vz (SI units)
std::string particles_csv(const Particles& particles);
// particles as VTK XML PolyData (.vtp, readable by ParaView): points with radius, velocity,
// speed and fixed arrays; one vertex cell per particle (use the Point Gaussian representation)
std::string particles_vtp(const Particles& particles);
// a pile's laser scan as CSV with header x,z [m], one point per line (scan.csv of talus pile and
// talus run; talus synth reads it into a measured run's metadata)
std::string scan_csv(const PileScan& scan);

}  // namespace talus
