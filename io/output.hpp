// Particle output: the state as CSV and as ParaView's PolyData, a pile's laser scan as CSV, and the
// type-G terrain's surface as ParaView's StructuredGrid, written with host/files.hpp's atomic
// writers.
#pragma once
#include <string>

#include "solvers/particles.hpp"
#include "terrain/pile.hpp"
#include "terrain/voxel_terrain.hpp"
#include "vehicle/wheel_loader.hpp"

namespace talus {

// particles as CSV with header x,y,z,r,vx,vy,vz (SI units)
std::string particles_csv(const Particles& particles);
// particles as VTK XML PolyData (.vtp, readable by ParaView; binary, io/vtk.hpp): points with
// radius, velocity, speed and fixed arrays; one vertex cell per particle (use the Point Gaussian
// representation, scaled by radius)
std::string particles_vtp(const Particles& particles);
// the machine posed now as VTK XML PolyData (.vtp, binary): the bucket's mesh as the DEM sees it
// (cell data part 0), every moving body as its inertia box, the box with the body's mass and
// principal moments, as MuJoCo's inertia view draws it (part 1, cell data body = its index), and
// the hydraulic cylinders as lines pin to pin (part 2)
std::string machine_vtp(const vehicle::WheelLoader& loader);
// a pile's laser scan as CSV with header x,z [m], one point per line (scan.csv of talus pile and
// talus run; talus synth reads it into a measured run's metadata)
std::string scan_csv(const PileScan& scan);
// the type-G terrain's surface as VTK XML StructuredGrid (.vts, readable by ParaView; binary): one
// point per voxel column at its centre and surface height, with the column's height [m], soil mass
// [kg] and mean compaction as point data
std::string terrain_vts(const VoxelTerrain& terrain);

}  // namespace talus
