#include "io/output.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <sstream>
#include <vector>

#include <Eigen/Eigenvalues>

#include "io/vtk.hpp"

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
  const size_t n = p.size();
  // per-particle data: radius (scale the Point Gaussian by it), velocity, speed, fixed (1 for
  // particles with zero inverse mass, e.g. the heap test's rough base)
  std::vector<double> position, velocity, speed(n);
  position.reserve(3 * n);
  velocity.reserve(3 * n);
  std::vector<std::uint8_t> fixed(n);
  std::vector<std::int64_t> connectivity(n), offsets(n);
  for (size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) {
      position.push_back(p.position[i][k]);
      velocity.push_back(p.velocity[i][k]);
    }
    speed[i] = p.velocity[i].norm();
    fixed[i] = p.inv_mass[i] > 0.0 ? 0 : 1;
    // one vertex cell per particle
    connectivity[i] = static_cast<std::int64_t>(i);
    offsets[i] = static_cast<std::int64_t>(i + 1);
  }
  VtkAppendedData data;
  std::string xml = vtk_file_open("PolyData");
  xml += "<PolyData>\n<Piece NumberOfPoints=\"" + std::to_string(n) + "\" NumberOfVerts=\"" +
         std::to_string(n) + "\" NumberOfLines=\"0\" NumberOfStrips=\"0\" NumberOfPolys=\"0\">\n";
  xml += "<Points>\n" + data.float32("position", position, 3) + "</Points>\n";
  xml += "<PointData Scalars=\"radius\" Vectors=\"velocity\">\n" +
         data.float32("radius", p.radius) + data.float32("velocity", velocity, 3) +
         data.float32("speed", speed) + data.uint8("fixed", fixed) + "</PointData>\n";
  xml += "<Verts>\n" + data.int64("connectivity", connectivity) + data.int64("offsets", offsets) +
         "</Verts>\n";
  xml += "</Piece>\n</PolyData>\n";
  return xml + vtk_file_close(data);
}

namespace {
// the box with a body's mass and principal moments of inertia: edge a_x = sqrt(6 (I_y + I_z -
// I_x) / m) and so on, along the principal axes (a moment that breaks the triangle inequality,
// as a floored inertia may, gives a flat edge)
Vec3 inertia_box(const vehicle::RigidBody& body, vehicle::Mat3& axes) {
  const Eigen::SelfAdjointEigenSolver<vehicle::Mat3> eig(body.inertia);
  axes = eig.eigenvectors();
  const Vec3& i = eig.eigenvalues();
  Vec3 edge;
  for (int k = 0; k < 3; ++k) {
    const double sum = i[(k + 1) % 3] + i[(k + 2) % 3] - i[k];
    edge[k] = std::sqrt(std::max(0.0, 6.0 * sum / body.mass));
  }
  return edge;
}
}  // namespace

std::string machine_vtp(const vehicle::WheelLoader& loader) {
  std::vector<double> points;
  std::vector<std::int64_t> poly_connectivity, poly_offsets, line_connectivity, line_offsets;
  std::vector<std::uint8_t> poly_part, line_part;
  std::vector<std::int64_t> poly_body, line_body;
  auto add_point = [&](const Vec3& x) {
    for (int k = 0; k < 3; ++k) points.push_back(x[k]);
    return static_cast<std::int64_t>(points.size() / 3 - 1);
  };
  auto add_polygon = [&](std::initializer_list<std::int64_t> ids, std::uint8_t part, int body) {
    poly_connectivity.insert(poly_connectivity.end(), ids);
    poly_offsets.push_back(static_cast<std::int64_t>(poly_connectivity.size()));
    poly_part.push_back(part);
    poly_body.push_back(body);
  };
  const std::vector<vehicle::RigidBody>& bodies = loader.bodies();

  // part 0: the bucket's mesh as the DEM sees it
  const vehicle::BucketMesh& mesh = loader.bucket_mesh();
  const std::int64_t first = static_cast<std::int64_t>(points.size() / 3);
  for (int v = 0; v < static_cast<int>(mesh.vertices.size()); ++v)
    add_point(loader.bucket_mesh_vertex_world(v));
  for (const auto& t : mesh.triangles)
    add_polygon({first + t[0], first + t[1], first + t[2]}, 0, loader.bucket_body());

  // part 1: every body as its inertia box, six quads, posed
  for (int b = 0; b < static_cast<int>(bodies.size()); ++b) {
    const vehicle::RigidBody& body = bodies[b];
    if (body.fixed || !(body.mass > 0.0)) continue;
    vehicle::Mat3 axes;
    const Vec3 half = 0.5 * inertia_box(body, axes);
    std::int64_t corner[8];
    for (int c = 0; c < 8; ++c) {
      const Vec3 local(c & 1 ? half.x() : -half.x(), c & 2 ? half.y() : -half.y(),
                       c & 4 ? half.z() : -half.z());
      corner[c] = add_point(body.point_to_world(axes * local));
    }
    static constexpr int kFaces[6][4] = {{0, 2, 6, 4}, {1, 5, 7, 3}, {0, 4, 5, 1},
                                         {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 6, 7, 5}};
    for (const auto& f : kFaces)
      add_polygon({corner[f[0]], corner[f[1]], corner[f[2]], corner[f[3]]}, 1, b);
  }

  // part 2: the hydraulic cylinders, pin to pin
  auto add_cylinder = [&](const vehicle::CylinderJoint& c) {
    const std::int64_t a = add_point(c.frame_a().world_anchor(bodies));
    const std::int64_t b = add_point(c.frame_b().world_anchor(bodies));
    line_connectivity.insert(line_connectivity.end(), {a, b});
    line_offsets.push_back(static_cast<std::int64_t>(line_connectivity.size()));
    line_part.push_back(2);
    line_body.push_back(-1);
  };
  for (const vehicle::CylinderJoint* c : loader.lift_cylinders()) add_cylinder(*c);
  add_cylinder(loader.tilt_cylinder());

  // cell data runs over lines first, then polygons (VTK's order of the cell kinds)
  std::vector<std::uint8_t> part(line_part);
  part.insert(part.end(), poly_part.begin(), poly_part.end());
  std::vector<std::int64_t> body(line_body);
  body.insert(body.end(), poly_body.begin(), poly_body.end());
  VtkAppendedData data;
  std::string xml = vtk_file_open("PolyData");
  xml += "<PolyData>\n<Piece NumberOfPoints=\"" + std::to_string(points.size() / 3) +
         "\" NumberOfVerts=\"0\" NumberOfLines=\"" + std::to_string(line_offsets.size()) +
         "\" NumberOfStrips=\"0\" NumberOfPolys=\"" + std::to_string(poly_offsets.size()) + "\">\n";
  xml += "<Points>\n" + data.float32("position", points, 3) + "</Points>\n";
  xml += "<CellData Scalars=\"part\">\n" + data.uint8("part", part) + data.int64("body", body) +
         "</CellData>\n";
  xml += "<Lines>\n" + data.int64("connectivity", line_connectivity) +
         data.int64("offsets", line_offsets) + "</Lines>\n";
  xml += "<Polys>\n" + data.int64("connectivity", poly_connectivity) +
         data.int64("offsets", poly_offsets) + "</Polys>\n";
  xml += "</Piece>\n</PolyData>\n";
  return xml + vtk_file_close(data);
}

std::string scan_csv(const PileScan& scan) {
  std::string csv = "x,z\n";
  for (const auto& q : scan.points)
    csv += std::to_string(q.x()) + "," + std::to_string(q.y()) + "\n";
  return csv;
}

std::string terrain_vts(const VoxelTerrain& t) {
  const int nx = t.nx(), ny = t.ny();
  // points: x fastest, then y (VTK's order), at the columns' centres and surface heights, with
  // each column's height, soil mass and mean compaction (its mass over the bank mass of the
  // volume it fills)
  std::vector<double> points, height, mass, compaction;
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const double z = t.surface_height(i, j), v = t.column_volume(i, j);
      points.insert(points.end(), {t.column_x(i), t.column_y(j), z});
      height.push_back(z);
      mass.push_back(t.column_mass(i, j));
      compaction.push_back(v > 0.0 ? t.column_mass(i, j) / (t.bank_density() * v) : 1.0);
    }
  }
  const std::string extent =
      "0 " + std::to_string(nx - 1) + " 0 " + std::to_string(ny - 1) + " 0 0";
  VtkAppendedData data;
  std::string xml = vtk_file_open("StructuredGrid");
  xml += "<StructuredGrid WholeExtent=\"" + extent + "\">\n<Piece Extent=\"" + extent + "\">\n";
  xml += "<Points>\n" + data.float32("position", points, 3) + "</Points>\n";
  xml += "<PointData Scalars=\"height\">\n" + data.float32("height", height) +
         data.float32("mass", mass) + data.float32("compaction", compaction) + "</PointData>\n";
  xml += "</Piece>\n</StructuredGrid>\n";
  return xml + vtk_file_close(data);
}

}  // namespace talus
