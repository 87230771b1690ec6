// terrain/voxel_terrain: the solid soil of the type-G terrain. The pile of a profile at bank
// density; soil taken out of and laid onto columns keeps the mass balance and the columns'
// filled-from-the-bottom invariant under fresh random operations; loose soil swells; the surface
// heightmap stands where the columns' soil ends, and the surface at any point is the heightmap's
// piecewise-linear surface through the columns' tops.
#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <random>
#include <string>

#include "host/binary.hpp"
#include "host/error.hpp"
#include "terrain/voxel_terrain.hpp"

namespace talus {
namespace {

// every cell under a column's top one exactly full, none over full, and the top where the soil's
// volume says: the invariant every operation keeps
void expect_columns_filled_from_the_bottom(const VoxelTerrain& t) {
  for (int j = 0; j < t.ny(); ++j)
    for (int i = 0; i < t.nx(); ++i) {
      bool top_seen = false;
      for (int k = 0; k < t.nz(); ++k) {
        double occ = t.occupancy(i, j, k);
        ASSERT_LE(occ, 1.0 + 1e-12) << i << " " << j << " " << k;
        if (top_seen) {
          ASSERT_EQ(occ, 0.0) << "soil above a partly filled cell at " << i << " " << j << " " << k;
        }
        if (occ < 1.0) top_seen = true;
      }
    }
}

// the default pile at G200: the mass is the profile's volume at 1727 kg/m^3, each column stands at
// the profile's mean height over its span, all soil at bank compaction
TEST(VoxelTerrain, ThePileOfAProfileHoldsItsVolumeAtBankDensity) {
  const PileProfile profile = default_pile_profile();
  VoxelTerrainOptions options;
  options.cell = 0.2;
  const VoxelTerrain t = VoxelTerrain::from_profile(profile, options);
  EXPECT_EQ(t.ny(), 30);
  EXPECT_NEAR(t.x0() + t.nx() * t.cell(), profile.rear_wall_x, 1e-12);
  const double expected = profile.volume() * kFieldBulkDensity;
  EXPECT_NEAR(t.total_mass() / expected, 1.0, 1e-12);
  expect_columns_filled_from_the_bottom(t);
  // a column on the face (mean of a linear stretch) and one on the flat top
  int i = 0, j = 0;
  ASSERT_TRUE(t.column_at(1.5, 0.1, &i, &j));
  const double xa = t.x0() + i * t.cell(), xb = xa + t.cell();
  EXPECT_NEAR(t.surface_height(i, j), 0.5 * (profile.height_at(xa) + profile.height_at(xb)), 1e-12);
  ASSERT_TRUE(t.column_at(4.5, -2.9, &i, &j));
  EXPECT_NEAR(t.surface_height(i, j), 2.0, 1e-12);
  EXPECT_NEAR(t.compaction(i, j, 0), 1.0, 1e-12);
  ASSERT_TRUE(t.column_at(-1.0, 0.0, &i, &j));  // ahead of the toe: bare ground
  EXPECT_EQ(t.surface_height(i, j), 0.0);
}

// fresh random takes and deposits: the terrain's mass is what it started with, less what was
// taken, plus what was laid, to rounding; the columns stay filled from the bottom
TEST(VoxelTerrain, TakingAndLayingSoilKeepsTheMassBalance) {
  const unsigned seed = std::random_device{}();
  SCOPED_TRACE("seed " + std::to_string(seed));
  std::mt19937_64 rng(seed);
  VoxelTerrainOptions options;
  options.cell = 0.4;
  VoxelTerrain t = VoxelTerrain::from_profile(default_pile_profile(), options);
  const double start = t.total_mass();
  double taken = 0.0, laid = 0.0;
  std::uniform_int_distribution<int> ui(0, t.nx() - 1), uj(0, t.ny() - 1), op(0, 1);
  std::uniform_real_distribution<double> uz(-0.2, 2.5), um(0.0, 300.0), uc(0.6, 1.1);
  for (int n = 0; n < 2000; ++n) {
    int i = ui(rng), j = uj(rng);
    if (op(rng) == 0) {
      double a = uz(rng), b = uz(rng);
      double before = t.surface_height(i, j);
      SoilTaken s = t.take(i, j, std::min(a, b), std::max(a, b));
      taken += s.mass;
      // the column sank by the thickness taken
      EXPECT_NEAR(before - t.surface_height(i, j), s.volume / (t.cell() * t.cell()), 1e-12);
      EXPECT_GE(s.mass, 0.0);
    } else {
      double m = um(rng);
      try {
        t.deposit(i, j, m, uc(rng));
        laid += m;
      } catch (const Error&) {
        // a full column refuses and keeps its soil: the balance below checks it
      }
    }
  }
  EXPECT_NEAR(t.total_mass(), start - taken + laid, 1e-12 * start);
  expect_columns_filled_from_the_bottom(t);
}

// the avalanche's and the merge's kind of change on tall columns (G50's 5 cm cells, 40 and more
// under the surface): thin layers taken off the top and small loads laid on, fresh random ones.
// take and deposit restack only the cells that can change (VoxelTerrain::unchanged_cells), so
// each column's kept sum must be the sum of its cells afresh, bit for bit (a restored copy sums
// every column from the bottom), the columns stay filled from the bottom, the mass balances
TEST(VoxelTerrain, ChangesAtTheTopOfTallColumnsKeepTheSumsOfAFreshSum) {
  const unsigned seed = std::random_device{}();
  SCOPED_TRACE("seed " + std::to_string(seed));
  std::mt19937_64 rng(seed);
  VoxelTerrainOptions options;
  options.cell = 0.05;
  const PileProfile profile = default_pile_profile();
  VoxelTerrain t = VoxelTerrain::from_profile(profile, options);
  const double start = t.total_mass();
  double taken = 0.0, laid = 0.0;
  // a patch of the face and the top, a few columns changed many times
  int i0 = 0, j0 = 0;
  ASSERT_TRUE(t.column_at(2.0, -0.5, &i0, &j0));
  std::uniform_int_distribution<int> ui(i0, i0 + 40), uj(j0, j0 + 10), op(0, 1);
  // up to 8 cm off, up to 0.3 kg (about 8 cm of a 5 cm column) on
  std::uniform_real_distribution<double> thick(0.0, 0.08), um(0.0, 0.3), uc(0.6, 1.1);
  for (int n = 0; n < 4000; ++n) {
    const int i = ui(rng), j = uj(rng);
    const double top = t.surface_height(i, j);
    if (op(rng) == 0) {
      const double z = thick(rng);
      const SoilTaken s = t.take(i, j, top - z, top);
      taken += s.mass;
      // all of the layer left, the column lower by it
      EXPECT_NEAR(s.volume / (t.cell() * t.cell()), std::min(z, top - t.z0()), 1e-12);
      EXPECT_NEAR(top - t.surface_height(i, j), s.volume / (t.cell() * t.cell()), 1e-12);
    } else {
      const double m = um(rng);
      t.deposit(i, j, m, uc(rng));
      laid += m;
    }
  }
  EXPECT_NEAR(t.total_mass(), start - taken + laid, 1e-12 * start);
  expect_columns_filled_from_the_bottom(t);
  ByteWriter w;
  t.save_state(w);
  VoxelTerrain fresh = VoxelTerrain::from_profile(profile, options);
  ByteReader r(w.bytes(), w.bytes().size(), "test state", "");
  fresh.restore_state(r);
  int tall = 0;
  for (int j = j0; j <= j0 + 10; ++j)
    for (int i = i0; i <= i0 + 40; ++i) {
      ASSERT_EQ(t.column_volume(i, j), fresh.column_volume(i, j)) << i << " " << j;
      tall += t.surface_height(i, j) > 10 * t.cell();
    }
  EXPECT_GT(tall, 100);  // the changes were on columns tall enough to keep cells unchanged
}

// loose soil swells: 100 kg of bank soil laid back at compaction 0.8 stands 1 / 0.8 as tall, and
// a slab taken under it lets it drop with its looseness intact
TEST(VoxelTerrain, LooseSoilStandsTallerAndDropsIntoAGapUnchanged) {
  VoxelTerrain t(0.0, 0.0, 0.0, 0.5, 2, 2, 8, kFieldBulkDensity);
  t.deposit(0, 0, 2.0 * 0.125 * kFieldBulkDensity, 1.0);  // two full cells of bank soil
  EXPECT_DOUBLE_EQ(t.surface_height(0, 0), 1.0);
  const double loose = 0.8;
  t.deposit(0, 0, 0.125 * kFieldBulkDensity, loose);  // one cell's worth, loose
  EXPECT_NEAR(t.surface_height(0, 0), 1.0 + 0.5 / loose, 1e-12);
  // take the lower half of the bank soil: the loose soil comes down by 0.5 m
  SoilTaken s = t.take(0, 0, 0.0, 0.5);
  EXPECT_NEAR(s.mass, 0.125 * kFieldBulkDensity, 1e-9);
  EXPECT_NEAR(s.volume, s.bank_volume, 1e-12);
  EXPECT_NEAR(t.surface_height(0, 0), 0.5 + 0.5 / loose, 1e-12);
  EXPECT_NEAR(t.compaction(0, 0, 0), 1.0, 1e-12);
  EXPECT_NEAR(t.compaction(0, 0, 2), loose, 1e-12);
  // the loose soil taken off the top is worth less bank volume than it filled: its swell
  SoilTaken top = t.take(0, 0, 0.5, 10.0);
  EXPECT_NEAR(top.volume / top.bank_volume, 1.0 / loose, 1e-12);
}

// the heightmap of the surface: a vertical ray at a column's centre finds that column's height
TEST(VoxelTerrain, TheSurfaceHeightmapStandsOnTheColumns) {
  VoxelTerrainOptions options;
  options.cell = 0.4;
  const VoxelTerrain t = VoxelTerrain::from_profile(default_pile_profile(), options);
  const Heightmap map = t.surface();
  for (int i = 0; i < t.nx(); i += 3)
    for (int j = 0; j < t.ny(); j += 4) {
      auto z = map.height_at(t.column_x(i), t.column_y(j));
      ASSERT_TRUE(z.has_value());
      EXPECT_NEAR(*z, t.surface_height(i, j), 1e-6);
    }
}

// the surface at fresh random points of a random terrain is the heightmap's interpolation (the
// same triangles, the same law), exactly at the column centres, and nothing outside them
TEST(VoxelTerrain, TheSurfaceAtAPointIsTheHeightmapsThroughTheColumnTops) {
  std::random_device rd;
  const unsigned seed = rd();
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double h = 0.2;
  VoxelTerrain t(-1.0, -0.6, 0.0, h, 10, 6, 10, kFieldBulkDensity);
  for (int j = 0; j < t.ny(); ++j)
    for (int i = 0; i < t.nx(); ++i)
      t.deposit(i, j, 1.5 * unit(rng) * h * h * kFieldBulkDensity, 1.0);
  const Heightmap map = t.surface();
  for (int k = 0; k < 200; ++k) {
    const double x = -1.1 + 2.2 * unit(rng), y = -0.7 + 1.4 * unit(rng);
    const std::optional<double> z = t.surface_at(x, y), m = map.interpolate(x, y);
    ASSERT_EQ(z.has_value(), m.has_value()) << "seed " << seed << " at " << x << ", " << y;
    if (z) {
      EXPECT_NEAR(*z, *m, 1e-12) << "seed " << seed;
    }
  }
  for (int j = 0; j < t.ny(); ++j)
    for (int i = 0; i < t.nx(); ++i)
      EXPECT_NEAR(*t.surface_at(t.column_x(i), t.column_y(j)), t.surface_height(i, j), 1e-12);
  // by hand: between four column centres, the point a quarter cell right of and a tenth of a cell
  // above the lower-left one lies in the lower triangle (u >= v): h00 + u (h10 - h00) + v (h11 -
  // h10)
  const double u = 0.25, v = 0.1;
  const double h00 = t.surface_height(3, 2), h10 = t.surface_height(4, 2),
               h11 = t.surface_height(4, 3);
  EXPECT_NEAR(*t.surface_at(t.column_x(3) + u * h, t.column_y(2) + v * h),
              h00 + u * (h10 - h00) + v * (h11 - h10), 1e-12);
  // outside the columns' centres (half a cell in from the grid's edge) there is no surface
  EXPECT_FALSE(t.surface_at(-1.0 + 0.4 * h, 0.0).has_value());
  EXPECT_FALSE(t.surface_at(0.0, 0.6).has_value());
  VoxelTerrain one(0.0, 0.0, 0.0, h, 1, 4, 4, kFieldBulkDensity);
  EXPECT_FALSE(one.surface_at(0.5 * h, 0.3).has_value());
}

// bad sizes are named: a cell out of range, a profile in millimetres, a column that would
// overflow (refused whole, nothing changed)
TEST(VoxelTerrain, BadSizesAreNamedAndAnOverflowChangesNothing) {
  PileProfile profile = default_pile_profile();
  profile.path = "pile.json";
  VoxelTerrainOptions options;
  options.cell = 0.0;
  try {
    VoxelTerrain::from_profile(profile, options);
    FAIL() << "a zero cell was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("pile.json"), std::string::npos) << e.what();
  }
  options.cell = 0.05;
  for (Vec3& p : profile.points) p *= 50.0;
  profile.rear_wall_x *= 50.0;
  EXPECT_THROW(VoxelTerrain::from_profile(profile, options), InputError);

  VoxelTerrain t(0.0, 0.0, 0.0, 1.0, 1, 1, 2, 1000.0);
  t.deposit(0, 0, 1500.0, 1.0);
  EXPECT_THROW(t.deposit(0, 0, 600.0, 1.0), Error);
  EXPECT_DOUBLE_EQ(t.column_mass(0, 0), 1500.0);
  EXPECT_THROW(t.deposit(0, 0, 1.0, 0.0), Error);
  EXPECT_THROW(t.deposit(0, 0, 1.0, 2.0), Error);
}

}  // namespace
}  // namespace talus
