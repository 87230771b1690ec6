#include "io/output.hpp"

#include <sstream>

namespace talus {

std::string particles_csv(const Particles& p) {
  std::ostringstream os;
  os.precision(9);
  os << "x,y,z,r,vx,vy,vz\n";
  for (size_t i = 0; i < p.size(); ++i) {
    const Vec3& x = p.position[i];
    const Vec3& v = p.velocity[i];
    os << x.x() << ',' << x.y() << ',' << x.z() << ',' << p.radius[i] << ',' << v.x() << ','
       << v.y() << ',' << v.z() << '\n';
  }
  return os.str();
}

std::string particles_vtp(const Particles& p) {
  std::ostringstream os;
  os.precision(7);
  size_t n = p.size();
  os << "<?xml version=\"1.0\"?>\n"
     << "<VTKFile type=\"PolyData\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
     << "<PolyData>\n<Piece NumberOfPoints=\"" << n << "\" NumberOfVerts=\"" << n
     << "\" NumberOfLines=\"0\" NumberOfStrips=\"0\" NumberOfPolys=\"0\">\n";
  // points
  os << "<Points><DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"ascii\">\n";
  for (size_t i = 0; i < n; ++i)
    os << p.position[i].x() << ' ' << p.position[i].y() << ' ' << p.position[i].z() << '\n';
  os << "</DataArray></Points>\n";
  // per-particle data: radius (scale the Point Gaussian by it), velocity, speed, fixed (1 for
  // particles with zero inverse mass, e.g. the heap test's rough base)
  os << "<PointData Scalars=\"radius\" Vectors=\"velocity\">\n"
     << "<DataArray type=\"Float32\" Name=\"radius\" format=\"ascii\">\n";
  for (size_t i = 0; i < n; ++i) os << p.radius[i] << '\n';
  os << "</DataArray>\n<DataArray type=\"Float32\" Name=\"velocity\" NumberOfComponents=\"3\" "
        "format=\"ascii\">\n";
  for (size_t i = 0; i < n; ++i)
    os << p.velocity[i].x() << ' ' << p.velocity[i].y() << ' ' << p.velocity[i].z() << '\n';
  os << "</DataArray>\n<DataArray type=\"Float32\" Name=\"speed\" format=\"ascii\">\n";
  for (size_t i = 0; i < n; ++i) os << p.velocity[i].norm() << '\n';
  os << "</DataArray>\n<DataArray type=\"UInt8\" Name=\"fixed\" format=\"ascii\">\n";
  for (size_t i = 0; i < n; ++i) os << (p.inv_mass[i] > 0.0 ? 0 : 1) << '\n';
  os << "</DataArray>\n</PointData>\n";
  // one vertex cell per particle
  os << "<Verts><DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n";
  for (size_t i = 0; i < n; ++i) os << i << '\n';
  os << "</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n";
  for (size_t i = 0; i < n; ++i) os << i + 1 << '\n';
  os << "</DataArray></Verts>\n</Piece>\n</PolyData>\n</VTKFile>\n";
  return os.str();
}

std::string scan_csv(const PileScan& scan) {
  std::string csv = "x,z\n";
  for (const auto& q : scan.points)
    csv += std::to_string(q.x()) + "," + std::to_string(q.y()) + "\n";
  return csv;
}

std::string terrain_vts(const VoxelTerrain& t) {
  std::ostringstream os;
  os.precision(7);
  const int nx = t.nx(), ny = t.ny();
  os << "<?xml version=\"1.0\"?>\n"
     << "<VTKFile type=\"StructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
     << "<StructuredGrid WholeExtent=\"0 " << nx - 1 << " 0 " << ny - 1 << " 0 0\">\n"
     << "<Piece Extent=\"0 " << nx - 1 << " 0 " << ny - 1 << " 0 0\">\n";
  // points: x fastest, then y (VTK's order), at the columns' centres and surface heights
  os << "<Points><DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"ascii\">\n";
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i)
      os << t.column_x(i) << ' ' << t.column_y(j) << ' ' << t.surface_height(i, j) << '\n';
  os << "</DataArray></Points>\n<PointData Scalars=\"height\">\n"
     << "<DataArray type=\"Float32\" Name=\"height\" format=\"ascii\">\n";
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) os << t.surface_height(i, j) << '\n';
  os << "</DataArray>\n<DataArray type=\"Float32\" Name=\"mass\" format=\"ascii\">\n";
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) os << t.column_mass(i, j) << '\n';
  // the column's mean compaction: its mass over the bank mass of the volume it fills
  os << "</DataArray>\n<DataArray type=\"Float32\" Name=\"compaction\" format=\"ascii\">\n";
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const double v = t.column_volume(i, j);
      os << (v > 0.0 ? t.column_mass(i, j) / (t.bank_density() * v) : 1.0) << '\n';
    }
  os << "</DataArray>\n</PointData>\n</Piece>\n</StructuredGrid>\n</VTKFile>\n";
  return os.str();
}

}  // namespace talus
