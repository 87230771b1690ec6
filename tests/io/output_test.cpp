// io/output: the text formats of particles and of a pile's laser scan
#include "io/output.hpp"

#include <gtest/gtest.h>

#include <algorithm>

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

}  // namespace
}  // namespace talus
