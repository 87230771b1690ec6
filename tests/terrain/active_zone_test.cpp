// terrain/active_zone: the predicted wedge against the analytic one of the fundamental earthmoving
// equation on a level bed (depth, rake, failure angle, reaches, soil mass); the same wedge turned
// a quarter round; excavation hands the zone's soil on with its swell and keeps the mass balance;
// a slow tool or one above the surface turns nothing dynamic; the soil a tool's body overlaps
// turns dynamic down to the body's underside.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <vector>

#include "terrain/active_zone.hpp"
#include "terrain/earthmoving_equation.hpp"

namespace talus {
namespace {

constexpr double kDeg = M_PI / 180.0;

// a level bed `height` high on a square grid of cells h over [-3, 3] m in x and y
VoxelTerrain level_bed(double h, double height) {
  const int n = static_cast<int>(std::lround(6.0 / h));
  VoxelTerrain t(-3.0, -3.0, 0.0, h, n, n, static_cast<int>(std::ceil((height + 1.0) / h)),
                 kFieldBulkDensity);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) t.deposit(i, j, height * h * h * kFieldBulkDensity, 1.0);
  return t;
}

// a tool 2 m wide cutting `depth` deep into a bed 1 m high, moving along `forward` (horizontal,
// unit) at 0.5 m/s, its top edge 1 m from the tip at `rake` degrees behind it
ToolEdges tool_in_bed(const Vec3& forward, double depth, double rake) {
  const Vec3 across = Vec3::UnitZ().cross(forward);  // the tool's left
  const Vec3 tip(0.0, 0.0, 1.0 - depth);
  const Vec3 lean = -std::cos(rake * kDeg) * forward + std::sin(rake * kDeg) * Vec3::UnitZ();
  ToolEdges tool;
  tool.cutting_left = tip + across;
  tool.cutting_right = tip - across;
  tool.top_left = tool.cutting_left + lean;
  tool.top_right = tool.cutting_right + lean;
  tool.velocity = 0.5 * forward;
  return tool;
}

// the zone on a level bed is the FEE's wedge: depth d, rake and beta as set, reaches d cot beta
// ahead and d cot alpha behind, soil rho w d^2 (cot alpha + cot beta) / 2; closer on a finer grid
TEST(ActiveZone, OnALevelBedItIsTheEarthmovingEquationsWedge) {
  const BulkSoil soil;
  const double d = 0.5, rake = 60.0, w = 2.0;
  const double beta = fee_failure_angle(rake, std::atan(soil.tool_friction) / kDeg, 40.0);
  const double analytic = kFieldBulkDensity * w * d * d *
                          (1.0 / std::tan(rake * kDeg) + 1.0 / std::tan(beta * kDeg)) / 2;
  double previous_error = INFINITY;
  for (double h : {0.2, 0.1, 0.05}) {
    const VoxelTerrain t = level_bed(h, 1.0);
    const ActiveZone z = predict_active_zone(t, tool_in_bed(Vec3::UnitX(), d, rake), soil);
    ASSERT_TRUE(z.active);
    EXPECT_NEAR(z.depth, d, 1e-12);
    EXPECT_NEAR(z.rake_deg, rake, 1e-9);
    EXPECT_NEAR(z.failure_angle_deg, beta, 1e-9);
    EXPECT_NEAR(z.width, w, 1e-12);
    EXPECT_NEAR(z.reach_ahead, d / std::tan(beta * kDeg), 1e-9);
    EXPECT_NEAR(z.reach_behind, d / std::tan(rake * kDeg), 1e-9);
    const double mass = zone_soil_mass(z, t);
    const double error = std::abs(mass / analytic - 1.0);
    std::printf("[ measured ] cell %.2f m: zone %.1f kg, analytic wedge %.1f kg, error %.2f %%\n",
                h, mass, analytic, 100.0 * error);
    EXPECT_LT(error, h < 0.1 ? 0.03 : 0.12);
    EXPECT_LT(error, previous_error * 1.01);
    previous_error = error;
  }
}

// turned a quarter round (moving along +y), and for a vertical blade (no soil behind the tip), the
// zone holds the same soil as along +x
TEST(ActiveZone, TheWedgeTurnsWithTheTool) {
  const BulkSoil soil;
  const VoxelTerrain t = level_bed(0.1, 1.0);
  for (double rake : {45.0, 90.0}) {
    const ActiveZone zx = predict_active_zone(t, tool_in_bed(Vec3::UnitX(), 0.4, rake), soil);
    const ActiveZone zy = predict_active_zone(t, tool_in_bed(Vec3::UnitY(), 0.4, rake), soil);
    EXPECT_NEAR(zy.forward.dot(Vec3::UnitY()), 1.0, 1e-12);
    EXPECT_NEAR(zone_soil_mass(zx, t), zone_soil_mass(zy, t), 1e-9 * zone_soil_mass(zx, t)) << rake;
    if (rake == 90.0) {
      EXPECT_EQ(zx.reach_behind, 0.0);
      double lo = 0.0;
      EXPECT_FALSE(zx.floor_at(-0.05, &lo));
    }
  }
}

// excavation: the zone's soil leaves the terrain, all of it and nothing else; it swells by 1.1
TEST(ActiveZone, ExcavationHandsTheZonesSoilOnWithItsSwell) {
  const BulkSoil soil;
  VoxelTerrain t = level_bed(0.1, 1.0);
  const double before = t.total_mass();
  const ActiveZone z = predict_active_zone(t, tool_in_bed(Vec3::UnitX(), 0.5, 45.0), soil);
  const double predicted = zone_soil_mass(z, t);
  const DynamicSoil dynamic = excavate(t, z, soil);
  EXPECT_NEAR(dynamic.mass, predicted, 1e-12 * before);
  EXPECT_NEAR(t.total_mass() + dynamic.mass, before, 1e-12 * before);
  EXPECT_NEAR(dynamic.bank_volume, dynamic.mass / kFieldBulkDensity, 1e-12);
  EXPECT_NEAR(dynamic.volume, 1.1 * dynamic.bank_volume, 1e-12);
  // nothing of the zone is left: the same wedge now holds no soil
  EXPECT_LT(zone_soil_mass(z, t), 1e-12 * before);
  // a column outside the zone is untouched
  int i = 0, j = 0;
  ASSERT_TRUE(t.column_at(2.5, 2.5, &i, &j));
  EXPECT_DOUBLE_EQ(t.surface_height(i, j), 1.0);
}

// no zone turns soil dynamic when the tool creeps (below 0.1 m/s) or rides above the surface
TEST(ActiveZone, ASlowToolOrOneAboveTheSurfaceTurnsNothingDynamic) {
  const BulkSoil soil;
  VoxelTerrain t = level_bed(0.2, 1.0);
  const double before = t.total_mass();
  ToolEdges slow = tool_in_bed(Vec3::UnitX(), 0.4, 60.0);
  slow.velocity = Vec3(0.05, 0.0, 0.03);
  const ActiveZone zs = predict_active_zone(t, slow, soil);
  EXPECT_FALSE(zs.active);
  EXPECT_GT(zone_soil_mass(zs, t), 0.0);  // the wedge is there, it is just not cut
  ToolEdges above = tool_in_bed(Vec3::UnitX(), -0.1, 60.0);
  const ActiveZone za = predict_active_zone(t, above, soil);
  EXPECT_FALSE(za.active);
  EXPECT_EQ(zone_soil_mass(za, t), 0.0);
  EXPECT_EQ(excavate(t, zs, soil).mass, 0.0);
  EXPECT_EQ(excavate(t, za, soil).mass, 0.0);
  EXPECT_EQ(t.total_mass(), before);
}

// a horizontal plate 1 m square at `z` (two triangles) and a side plate standing on its edge
// (seen edge-on from above, it covers no column), as the triangles of a tool's mesh in the world
struct Plate {
  std::vector<Vec3> vertices;
  std::vector<std::array<int, 3>> triangles;
};
Plate plate_at(double z) {
  Plate p;
  p.vertices = {{-0.5, -0.5, z}, {0.5, -0.5, z},        {0.5, 0.5, z},
                {-0.5, 0.5, z},  {-0.5, -0.5, z + 0.5}, {0.5, -0.5, z + 0.5}};
  p.triangles = {{0, 1, 2}, {0, 2, 3}, {0, 1, 5}, {0, 5, 4}};
  return p;
}

// the plate 0.4 m under a 1 m bed takes 0.4 m of soil from each of the 100 columns whose centres
// it covers (cells of 0.1 m), leaves every other column as it was and keeps the mass balance; a
// second, higher plate over the first changes nothing (the lowest point counts); above the bed
// nothing is taken, below its floor the whole column
TEST(ActiveZone, TheSoilABodyOverlapsTurnsDynamicDownToItsUnderside) {
  const BulkSoil soil;
  const double h = 0.1;
  VoxelTerrain t = level_bed(h, 1.0);
  const double before = t.total_mass();
  Plate p = plate_at(0.6);
  const Plate upper = plate_at(0.8);
  for (const auto& tri : upper.triangles)
    p.triangles.push_back({tri[0] + 6, tri[1] + 6, tri[2] + 6});
  p.vertices.insert(p.vertices.end(), upper.vertices.begin(), upper.vertices.end());
  std::vector<ExcavatedColumn> columns;
  const DynamicSoil d = displace_by_tool(t, p.vertices, p.triangles, soil, &columns);
  EXPECT_NEAR(d.mass, 100 * 0.4 * h * h * kFieldBulkDensity, 1e-9);
  EXPECT_NEAR(t.total_mass() + d.mass, before, 1e-12 * before);
  EXPECT_NEAR(d.volume, soil.swell * d.bank_volume, 1e-12);
  ASSERT_EQ(columns.size(), 100u);
  // by row, then column; each from the plate up to where the surface stood
  EXPECT_LT(columns[0].j * 1000 + columns[0].i, columns[1].j * 1000 + columns[1].i);
  for (const ExcavatedColumn& c : columns) {
    EXPECT_NEAR(c.z_lo, 0.6, 1e-12);
    EXPECT_NEAR(c.z_hi, 1.0, 1e-12);
    EXPECT_NEAR(t.surface_height(c.i, c.j), 0.6, 1e-12);
    EXPECT_LT(std::abs(t.column_x(c.i)), 0.5);
    EXPECT_LT(std::abs(t.column_y(c.j)), 0.5);
  }
  int i = 0, j = 0;
  ASSERT_TRUE(t.column_at(0.55, 0.0, &i, &j));  // beside the plate
  EXPECT_DOUBLE_EQ(t.surface_height(i, j), 1.0);
  // the same plate again takes nothing: the columns end at its underside now
  EXPECT_EQ(displace_by_tool(t, p.vertices, p.triangles, soil).mass, 0.0);
  const Plate high = plate_at(1.2);
  EXPECT_EQ(displace_by_tool(t, high.vertices, high.triangles, soil).mass, 0.0);
  const Plate deep = plate_at(-0.5);
  const double left = t.total_mass();
  EXPECT_NEAR(displace_by_tool(t, deep.vertices, deep.triangles, soil).mass,
              100 * 0.6 * h * h * kFieldBulkDensity, 1e-9);
  EXPECT_NEAR(t.total_mass(), left - 100 * 0.6 * h * h * kFieldBulkDensity, 1e-9);
}

}  // namespace
}  // namespace talus
