// Particle output: the state as CSV and as ParaView's PolyData, written with host/files.hpp's
// atomic writers.
#pragma once
#include <string>

#include "solvers/particles.hpp"

namespace talus {

// particles as CSV with header x,y,z,r,vx,vy,vz (SI units)
std::string particles_csv(const Particles& particles);
// particles as VTK XML PolyData (.vtp, readable by ParaView): points with radius, velocity,
// speed and fixed arrays; one vertex cell per particle (use the Point Gaussian representation)
std::string particles_vtp(const Particles& particles);

}  // namespace talus
