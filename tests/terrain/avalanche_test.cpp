// terrain/avalanche: a pair's excess slope decays at the stated rate; a slope under the repose
// angle stays put; a tower of soil slumps to the repose angle symmetrically, keeping its mass; no
// soil slides into a closed column (where a tool's body stands).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "host/error.hpp"
#include "terrain/avalanche.hpp"

namespace talus {
namespace {

constexpr double kDeg = M_PI / 180.0;

// two columns: one step takes the excess over the repose slope down by the fraction 1 - exp(-k dt)
TEST(Avalanche, APairsExcessDecaysAtTheStatedRate) {
  VoxelTerrain t(0.0, 0.0, 0.0, 0.2, 2, 1, 20, kFieldBulkDensity);
  t.deposit(0, 0, 2.0 * 0.04 * kFieldBulkDensity, 1.0);  // 2 m of soil
  t.deposit(1, 0, 0.5 * 0.04 * kFieldBulkDensity, 0.8);  // 0.4 m of loose soil
  const AvalancheOptions options;
  const double dt = 0.02;
  const double stable = 0.2 * std::tan(options.repose_deg * kDeg);
  const double excess = t.surface_height(0, 0) - t.surface_height(1, 0) - stable;
  const double mass = t.total_mass();
  const AvalancheStep s = avalanche(t, dt, options);
  EXPECT_EQ(s.slopes, 1);
  const double after = t.surface_height(0, 0) - t.surface_height(1, 0) - stable;
  EXPECT_NEAR(after, excess * std::exp(-options.rate * dt), 1e-12);
  EXPECT_NEAR(t.total_mass(), mass, 1e-12 * mass);
  // the soil that slid is bank soil and keeps its compaction on the loose column: its top cell
  // mixes loose and bank soil, so its compaction lies between
  const double top = t.compaction(1, 0, 2);
  EXPECT_GT(top, 0.8);
  EXPECT_LE(top, 1.0 + 1e-12);
}

// a 30 deg slope, under the 32 deg repose angle, does not move at all
TEST(Avalanche, ASlopeUnderTheReposeAngleStaysPut) {
  VoxelTerrain t(0.0, 0.0, 0.0, 0.1, 30, 4, 40, kFieldBulkDensity);
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 30; ++i)
      t.deposit(i, j, (0.05 + i * 0.1 * std::tan(30.0 * kDeg)) * 0.01 * kFieldBulkDensity, 1.0);
  const std::vector<double> before = t.surface_heights();
  const AvalancheStep s = avalanche(t, 0.05);
  EXPECT_EQ(s.moved_mass, 0.0);
  EXPECT_EQ(s.slopes, 0);
  EXPECT_NEAR(s.steepest_deg, 30.0, 1e-9);
  EXPECT_EQ(t.surface_heights(), before);
}

// a tower 1.6 m high on a 0.2 m bed slumps: after 30 simulated seconds no slope is steeper than
// the repose angle (to the last step's small remainder), the mass is what it was, and the heap is
// as symmetric as the tower was (the exchanges have no sweep order)
TEST(Avalanche, ATowerSlumpsToTheReposeAngleSymmetrically) {
  const int n = 21;
  VoxelTerrain t(0.0, 0.0, 0.0, 0.2, n, n, 20, kFieldBulkDensity);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const bool tower = std::abs(i - n / 2) <= 1 && std::abs(j - n / 2) <= 1;
      t.deposit(i, j, (tower ? 1.8 : 0.2) * 0.04 * kFieldBulkDensity, tower ? 0.9 : 1.0);
    }
  const double mass = t.total_mass();
  AvalancheStep s;
  double moved = 0.0;
  int steps = 0;
  for (; steps < 1500; ++steps) {
    s = avalanche(t, 0.02);
    moved += s.moved_mass;
  }
  std::printf(
      "[ measured ] after %d steps: steepest slope %.3f deg, %d slopes over 32 deg, %.1f kg moved "
      "in all\n",
      steps, s.steepest_deg, s.slopes, moved);
  EXPECT_LT(s.steepest_deg, 32.01);
  EXPECT_GT(moved, 0.1 * mass * 0.1);
  EXPECT_NEAR(t.total_mass(), mass, 1e-12 * mass);
  double asymmetry = 0.0;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      asymmetry =
          std::max(asymmetry, std::abs(t.surface_height(i, j) - t.surface_height(n - 1 - i, j)));
      asymmetry = std::max(asymmetry, std::abs(t.surface_height(i, j) - t.surface_height(j, i)));
    }
  EXPECT_LT(asymmetry, 1e-9);
  // the heap's top stands lower than the tower's, its foot wider
  EXPECT_LT(t.surface_height(n / 2, n / 2), 1.8);
  EXPECT_GT(t.surface_height(n / 2 + 4, n / 2), 0.2);
}

// a pit between two tall columns, closed (a bucket stands in it): its neighbours' slopes into it
// stay as they are, while the same neighbours still give soil to an open lower column beyond;
// the mass is kept and a wrong-sized mask is refused
TEST(Avalanche, NoSoilSlidesIntoAClosedColumn) {
  VoxelTerrain t(0.0, 0.0, 0.0, 0.2, 4, 1, 20, kFieldBulkDensity);
  const double column = 0.04 * kFieldBulkDensity;  // kg per metre of height
  t.deposit(0, 0, 1.5 * column, 1.0);
  t.deposit(1, 0, 0.1 * column, 1.0);  // the pit
  t.deposit(2, 0, 1.5 * column, 1.0);
  t.deposit(3, 0, 0.2 * column, 1.0);  // open and low
  const std::vector<char> closed = {0, 1, 0, 0};
  const double mass = t.total_mass();
  const double pit = t.surface_height(1, 0), left = t.surface_height(0, 0);
  const double right = t.surface_height(2, 0);
  const AvalancheStep s = avalanche(t, 0.02, {}, &closed);
  EXPECT_EQ(s.slopes, 3);  // all three are steep; one of them may move
  EXPECT_EQ(t.surface_height(1, 0), pit);
  EXPECT_EQ(t.surface_height(0, 0), left);  // its only lower neighbour is the pit
  EXPECT_LT(t.surface_height(2, 0), right);
  EXPECT_GT(t.surface_height(3, 0), 0.2);
  EXPECT_NEAR(t.total_mass(), mass, 1e-12 * mass);
  const std::vector<char> wrong(3, 0);
  EXPECT_THROW(avalanche(t, 0.02, {}, &wrong), Error);
}

}  // namespace
}  // namespace talus
