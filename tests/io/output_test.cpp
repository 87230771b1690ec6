// io/output: the text formats of particles and of a pile's laser scan, and the binary VTK files
// (io/vtk) of particles and the machine, decoded here from their bytes (tests/python/test_vtk.py
// reads them back with VTK's own reader)
#include "io/output.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Eigenvalues>

#include "vehicle/data_file.hpp"

namespace talus {
namespace {

// scan.csv: the header, then x,z per point in the scan's order, 6 decimals [m]
TEST(Output, ScanCsvListsThePointsUnderItsHeader) {
  PileScan scan;
  scan.points = {Eigen::Vector2d(-4.0, 0.0), Eigen::Vector2d(0.5, 1.25)};
  EXPECT_EQ(scan_csv(scan), "x,z\n-4.000000,0.000000\n0.500000,1.250000\n");
  EXPECT_EQ(scan_csv(PileScan{}), "x,z\n");
}

// particles.csv: one row per particle under the documented header
TEST(Output, ParticlesCsvHasOneRowPerParticle) {
  Particles p;
  p.add(Vec3(1.0, 2.0, 3.0), 0.1, 2590.0);
  p.add(Vec3(0.0, 0.0, 0.5), 0.2, 2590.0);
  const std::string csv = particles_csv(p);
  EXPECT_EQ(csv.substr(0, csv.find('\n')), "x,y,z,r,vx,vy,vz");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 3);
}

// the arrays of a VTK XML file with raw appended data: name -> bytes (every array's name is unique
// within what a test looks at; the last one wins otherwise)
std::map<std::string, std::string> appended_arrays(const std::string& file) {
  const size_t start = file.find("<AppendedData encoding=\"raw\">");
  const size_t underscore = file.find('_', start);
  EXPECT_NE(start, std::string::npos);
  std::map<std::string, std::string> arrays;
  for (size_t at = file.find("<DataArray "); at < start; at = file.find("<DataArray ", at + 1)) {
    const size_t end = file.find("/>", at);
    const std::string e = file.substr(at, end - at);
    const auto attribute = [&](const std::string& key) {
      const size_t k = e.find(key + "=\"") + key.size() + 2;
      return e.substr(k, e.find('"', k) - k);
    };
    EXPECT_EQ(attribute("format"), "appended");
    const size_t offset = underscore + 1 + std::stoull(attribute("offset"));
    std::uint64_t size = 0;
    std::memcpy(&size, file.data() + offset, sizeof(size));
    arrays[attribute("Name")] = file.substr(offset + sizeof(size), size);
  }
  return arrays;
}

template <typename T>
std::vector<T> values_of(const std::string& bytes) {
  std::vector<T> v(bytes.size() / sizeof(T));
  std::memcpy(v.data(), bytes.data(), v.size() * sizeof(T));
  return v;
}

// particles.vtp: the header says binary appended data with UInt64 byte counts, and each array's
// bytes are the particles' values as float32, fresh random particles every run
TEST(Output, ParticlesVtpHoldsTheParticlesInBinary) {
  const std::uint64_t seed = std::random_device{}();
  SCOPED_TRACE("random seed " + std::to_string(seed));  // a failure names the inputs to replay it
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-5.0, 5.0);
  Particles p;
  for (int i = 0; i < 37; ++i) {
    p.add(Vec3(u(rng), u(rng), u(rng)), 0.1 + 0.01 * (u(rng) + 5.0), 2590.0);
    p.velocity.back() = Vec3(u(rng), u(rng), u(rng));
  }
  p.inv_mass[3] = 0.0;  // a fixed particle
  const std::string file = particles_vtp(p);
  EXPECT_NE(file.find("byte_order=\"LittleEndian\" header_type=\"UInt64\""), std::string::npos);
  EXPECT_NE(file.find("NumberOfPoints=\"37\""), std::string::npos);
  const auto arrays = appended_arrays(file);
  const auto position = values_of<float>(arrays.at("position"));
  const auto radius = values_of<float>(arrays.at("radius"));
  const auto speed = values_of<float>(arrays.at("speed"));
  const auto fixed = values_of<std::uint8_t>(arrays.at("fixed"));
  const auto offsets = values_of<std::int64_t>(arrays.at("offsets"));
  ASSERT_EQ(position.size(), 3u * 37);
  ASSERT_EQ(radius.size(), 37u);
  for (int i = 0; i < 37; ++i) {
    for (int k = 0; k < 3; ++k)
      EXPECT_EQ(position[3 * i + k], static_cast<float>(p.position[i][k]));
    EXPECT_EQ(radius[i], static_cast<float>(p.radius[i]));
    EXPECT_EQ(speed[i], static_cast<float>(p.velocity[i].norm()));
    EXPECT_EQ(fixed[i], i == 3 ? 1 : 0);
    EXPECT_EQ(offsets[i], i + 1);
  }
}

// machine.vtp: the bucket's triangles at the posed mesh's vertices, six faces per moving body's
// inertia box, three cylinder lines; the boxes have the bodies' moments (a box of edges a, b, c
// and mass m has I_x = m (b^2 + c^2) / 12)
TEST(Output, MachineVtpHoldsTheBucketTheBodiesAndTheCylinders) {
  const vehicle::WheelLoader loader(vehicle::find_data_file("wa320", "machines"));
  const std::string file = machine_vtp(loader);
  const auto arrays = appended_arrays(file);
  const auto points = values_of<float>(arrays.at("position"));
  const auto part = values_of<std::uint8_t>(arrays.at("part"));
  const auto body = values_of<std::int64_t>(arrays.at("body"));
  int moving = 0;
  for (const auto& b : loader.bodies()) moving += b.fixed ? 0 : 1;
  const size_t triangles = loader.bucket_mesh().triangles.size();
  EXPECT_EQ(std::count(part.begin(), part.end(), 0), static_cast<long>(triangles));
  EXPECT_EQ(std::count(part.begin(), part.end(), 1), 6L * moving);
  EXPECT_EQ(std::count(part.begin(), part.end(), 2), 3L);
  // the bucket's vertices come first, posed as the DEM sees them
  for (int v = 0; v < static_cast<int>(loader.bucket_mesh().vertices.size()); ++v)
    for (int k = 0; k < 3; ++k)
      EXPECT_EQ(points[3 * v + k], static_cast<float>(loader.bucket_mesh_vertex_world(v)[k]));
  // each body's box: its eight corners follow the bucket's vertices in body order; the box's edge
  // lengths give back the body's principal moments
  size_t corner = loader.bucket_mesh().vertices.size();
  for (int b = 0; b < static_cast<int>(loader.bodies().size()); ++b) {
    const vehicle::RigidBody& rb = loader.bodies()[b];
    if (rb.fixed) continue;
    const auto at = [&](int c) {
      return Vec3(points[3 * (corner + c)], points[3 * (corner + c) + 1],
                  points[3 * (corner + c) + 2]);
    };
    const Vec3 edges((at(1) - at(0)).norm(), (at(2) - at(0)).norm(), (at(4) - at(0)).norm());
    const Eigen::SelfAdjointEigenSolver<vehicle::Mat3> eig(rb.inertia);
    const double m = rb.mass;
    const Vec3 moments(m * (edges.y() * edges.y() + edges.z() * edges.z()) / 12.0,
                       m * (edges.x() * edges.x() + edges.z() * edges.z()) / 12.0,
                       m * (edges.x() * edges.x() + edges.y() * edges.y()) / 12.0);
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(moments[k], eig.eigenvalues()[k], 1e-5 * eig.eigenvalues().maxCoeff()) << rb.name;
    EXPECT_NEAR((0.5 * (at(0) + at(7)) - rb.position).norm(), 0.0, 1e-5) << rb.name;
    corner += 8;
  }
  EXPECT_EQ(std::count(body.begin(), body.end(), loader.bucket_body()),
            static_cast<long>(triangles) + 6);
}

}  // namespace
}  // namespace talus
