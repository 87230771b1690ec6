// terrain/active_zone: the predicted wedge against the analytic one of the fundamental earthmoving
// equation on a level bed (depth, rake, failure angle, reaches, soil mass); the same wedge turned
// a quarter round; excavation hands the zone's soil on with its swell and keeps the mass balance,
// within a reach of the edge only its near part;
// the excavated zone's floor is its failure plane, not a staircase;
// a slow tool or one above the surface turns nothing dynamic; the soil a tool's body overlaps is
// pushed aside down to the body's underside, unless it stands less than the pressed depth above it.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <vector>

#include "host/error.hpp"
#include "solvers/dem_reference.hpp"
#include "terrain/active_zone.hpp"
#include "terrain/earthmoving_equation.hpp"
#include "tests/terrain/voxel_test_util.hpp"

namespace talus {
namespace {

constexpr double kDeg = M_PI / 180.0;

using test::level_bed;

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

// within a reach: only the zone's columns no farther than the reach ahead of the edge leave the
// terrain, the far end of the wedge stays in place, and the whole zone taken afterwards hands on
// the rest, so that the two parts add up to the whole wedge
TEST(ActiveZone, ExcavationWithinAReachTakesTheNearPartOfTheWedge) {
  const BulkSoil soil;
  VoxelTerrain t = level_bed(0.1, 1.0);
  const double before = t.total_mass();
  const ActiveZone z = predict_active_zone(t, tool_in_bed(Vec3::UnitX(), 0.5, 45.0), soil);
  const double whole = zone_soil_mass(z, t);
  ASSERT_GT(z.reach_ahead, 0.4);
  // 0 is the whole zone; a reach beyond the wedge's is the whole zone too
  EXPECT_EQ(within_reach(z, 0.0).reach_ahead, z.reach_ahead);
  EXPECT_EQ(within_reach(z, 10.0).reach_ahead, z.reach_ahead);
  const ActiveZone near = within_reach(z, 0.2);
  EXPECT_EQ(near.reach_ahead, 0.2);
  const double near_mass = zone_soil_mass(near, t);
  EXPECT_GT(near_mass, 0.0);
  EXPECT_LT(near_mass, whole);
  const DynamicSoil first = excavate(t, near, soil);
  EXPECT_NEAR(first.mass, near_mass, 1e-12 * before);
  // a column 0.35 m ahead of the tip, inside the whole wedge, beyond the reach: untouched
  int i = 0, j = 0;
  ASSERT_TRUE(t.column_at(z.tip.x() + 0.35, z.tip.y(), &i, &j));
  double lo = 0.0, hi = 0.0;
  EXPECT_TRUE(zone_interval(z, t, i, j, &lo, &hi));
  EXPECT_DOUBLE_EQ(t.surface_height(i, j), 1.0);
  // the rest of the wedge, then: the parts add up to the whole
  const DynamicSoil rest = excavate(t, z, soil);
  EXPECT_NEAR(first.mass + rest.mass, whole, 1e-12 * before);
  EXPECT_NEAR(t.total_mass() + first.mass + rest.mass, before, 1e-12 * before);
  // a reach is a distance
  for (double bad : {-0.1, std::nan(""), static_cast<double>(INFINITY)})
    EXPECT_THROW(within_reach(z, bad), Error);
}

// the excavated zone's floor: with its columns' boxes alone a staircase whose steps stand above
// the failure plane; with failure_plane_column's plates and lowered boxes the plane itself, a
// grain touching the plane anywhere over the zone touching the floor and nothing above it, for a
// zone along x and one turned 30 deg; columns outside the zone, behind the tip or of an inactive
// zone are left as they are
TEST(ActiveZone, TheExcavatedZonesFloorIsItsFailurePlaneNotAStaircase) {
  const BulkSoil soil;
  const double h = 0.1, r = 0.02;
  for (double turn : {0.0, 30.0}) {
    VoxelTerrain t = level_bed(h, 1.0);
    const Vec3 forward(std::cos(turn * kDeg), std::sin(turn * kDeg), 0.0);
    const ActiveZone z = predict_active_zone(t, tool_in_bed(forward, 0.5, 45.0), soil);
    ASSERT_TRUE(z.active);
    excavate(t, z, soil);
    // the columns as boxes, with and without the plane's plates
    std::vector<StaticGeom> steps, plane;
    int plates = 0;
    for (int j = 0; j < t.ny(); ++j)
      for (int i = 0; i < t.nx(); ++i) {
        double top = t.surface_height(i, j);
        const auto box = [&](double z_top) {
          return StaticGeom::box(Vec3(t.column_x(i), t.column_y(j), 0.5 * z_top),
                                 Vec3(0.5 * h, 0.5 * h, 0.5 * z_top), Eigen::Matrix3d::Identity());
        };
        steps.push_back(box(top));
        PlaneFloorColumn floor;
        if (failure_plane_column(z, t, i, j, &floor)) {
          EXPECT_LE(floor.top, top);
          top = floor.top;
          plane.push_back(floor.plate);
          ++plates;
        }
        plane.push_back(box(top));
      }
    EXPECT_GT(plates, 20) << turn;
    // a grain touching the failure plane, a cell inside the zone's edges, at points a seventh of a
    // cell apart: the plane's floor touches it (gap 0), the staircase overlaps it
    const double beta = z.failure_angle_deg * kDeg;
    const Vec3 normal = -std::sin(beta) * z.forward + std::cos(beta) * Vec3::UnitZ();
    double worst_plane = INFINITY, worst_steps = INFINITY, highest_plane = -INFINITY;
    for (double s = h; s <= z.reach_ahead - h; s += h / 7.0)
      for (double a = -0.5 * z.width + h; a <= 0.5 * z.width - h; a += h / 7.0) {
        const Vec3 on_plane =
            z.tip + s * z.forward + a * z.along + s * std::tan(beta) * Vec3::UnitZ();
        const Vec3 grain = on_plane + r * normal;
        const auto min_gap = [&](const std::vector<StaticGeom>& geoms) {
          double gap = INFINITY;
          Vec3 n;
          for (const StaticGeom& g : geoms)
            gap = std::min(gap, reference::sphere_geom(grain, r, g, &n));
          return gap;
        };
        const double gap = min_gap(plane);
        worst_plane = std::min(worst_plane, gap);
        highest_plane = std::max(highest_plane, gap);
        worst_steps = std::min(worst_steps, min_gap(steps));
      }
    std::printf(
        "[ measured ] zone turned %.0f deg, beta %.1f deg: a grain on the plane overlaps "
        "the plane's floor by %.2g m at most (the staircase: %.3f m)\n",
        turn, z.failure_angle_deg, -worst_plane, -worst_steps);
    EXPECT_GT(worst_plane, -1e-9) << turn;
    EXPECT_LT(highest_plane, 1e-9) << turn;
    EXPECT_LT(worst_steps, -0.25 * h * std::tan(beta)) << turn;
    // outside the zone, behind its tip, or under an inactive zone: no plate
    PlaneFloorColumn floor;
    int i = 0, j = 0;
    ASSERT_TRUE(t.column_at(2.5, 2.5, &i, &j));
    EXPECT_FALSE(failure_plane_column(z, t, i, j, &floor));
    const Vec3 behind = z.tip - 0.3 * z.forward;
    ASSERT_TRUE(t.column_at(behind.x(), behind.y(), &i, &j));
    EXPECT_FALSE(failure_plane_column(z, t, i, j, &floor));
    const Vec3 ahead = z.tip + 0.5 * z.reach_ahead * z.forward;
    ASSERT_TRUE(t.column_at(ahead.x(), ahead.y(), &i, &j));
    EXPECT_TRUE(failure_plane_column(z, t, i, j, &floor));
    ActiveZone idle = z;
    idle.active = false;
    EXPECT_FALSE(failure_plane_column(idle, t, i, j, &floor));
  }
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

// the plate 0.4 m under a 1 m bed: its underside covers exactly the 100 column centres under it
// (cells of 0.1 m; a second, higher plate over it changes nothing, the lowest point counts), those
// columns are closed, and push_aside cuts each to the plate and lays its soil on open columns
// nearby, keeping the mass; a second push moves nothing, a plate above the bed nothing, and where
// no column has room the soil turns dynamic
TEST(ActiveZone, TheSoilABodyOverlapsIsPushedAsideDownToItsUnderside) {
  const BulkSoil soil;
  const double h = 0.1;
  VoxelTerrain t = level_bed(h, 1.0);
  const double before = t.total_mass();
  Plate p = plate_at(0.6);
  const Plate upper = plate_at(0.8);
  for (const auto& tri : upper.triangles)
    p.triangles.push_back({tri[0] + 6, tri[1] + 6, tri[2] + 6});
  p.vertices.insert(p.vertices.end(), upper.vertices.begin(), upper.vertices.end());
  const std::vector<double> under = tool_underside(t, p.vertices, p.triangles);
  const std::vector<char> closed = closed_columns(t, under);
  int covered = 0, shut = 0;
  for (size_t c = 0; c < under.size(); ++c) {
    shut += closed[c];
    if (!std::isfinite(under[c])) continue;
    ++covered;
    EXPECT_NEAR(under[c], 0.6, 1e-12);
    EXPECT_TRUE(closed[c]);
  }
  EXPECT_EQ(covered, 100);
  EXPECT_EQ(shut, 100);
  const PushedSoil pushed = push_aside(t, under, soil);
  EXPECT_NEAR(pushed.moved, 100 * 0.4 * h * h * kFieldBulkDensity, 1e-9);
  EXPECT_EQ(pushed.left.mass, 0.0);
  EXPECT_NEAR(t.total_mass(), before, 1e-12 * before);
  // the plate's columns end at it; the soil went to open columns within reach, none beyond
  double gained = 0.0;
  for (int j = 0; j < t.ny(); ++j)
    for (int i = 0; i < t.nx(); ++i) {
      const double x = t.column_x(i), y = t.column_y(j), top = t.surface_height(i, j);
      if (std::abs(x) < 0.5 && std::abs(y) < 0.5) {
        EXPECT_NEAR(top, 0.6, 1e-12);
        continue;
      }
      EXPECT_GE(top, 1.0 - 1e-12);
      gained += (top - 1.0) * h * h * kFieldBulkDensity;
      if (std::max(std::abs(x), std::abs(y)) > 0.5 + kPushReach * h) {
        EXPECT_NEAR(top, 1.0, 1e-12);
      }
    }
  EXPECT_NEAR(gained, pushed.moved, 1e-9);
  // nothing left to push; nothing under a plate above the bed
  EXPECT_EQ(push_aside(t, under, soil).moved, 0.0);
  const Plate high = plate_at(1.5);
  EXPECT_EQ(push_aside(t, tool_underside(t, high.vertices, high.triangles), soil).moved, 0.0);
  // a full grid (10 cells of a 1 m bed) has no room: the soil turns dynamic
  VoxelTerrain full(-3.0, -3.0, 0.0, h, 60, 60, 10, kFieldBulkDensity);
  for (int j = 0; j < 60; ++j)
    for (int i = 0; i < 60; ++i) full.deposit(i, j, 1.0 * h * h * kFieldBulkDensity, 1.0);
  const double full_mass = full.total_mass();
  const PushedSoil stuck = push_aside(full, tool_underside(full, p.vertices, p.triangles), soil);
  EXPECT_EQ(stuck.moved, 0.0);
  EXPECT_NEAR(stuck.left.mass, 100 * 0.4 * h * h * kFieldBulkDensity, 1e-9);
  EXPECT_NEAR(stuck.left.volume, soil.swell * stuck.left.bank_volume, 1e-12);
  EXPECT_NEAR(full.total_mass() + stuck.left.mass, full_mass, 1e-12 * full_mass);
}

// with a pressed depth (the digs' kPressedDepth, where the terrain's support holds the bucket up)
// soil standing less than it above the plate stays where it is; deeper, the column is cut to the
// plate as without one; a negative depth is refused
TEST(ActiveZone, SoilWithinThePressedDepthOfTheUndersideIsPressedNotPushed) {
  const BulkSoil soil;
  const double h = 0.1;
  for (double sink : {0.5 * kPressedDepth, 2.0 * kPressedDepth}) {
    VoxelTerrain t = level_bed(h, 1.0);
    const Plate p = plate_at(1.0 - sink);
    const std::vector<double> under = tool_underside(t, p.vertices, p.triangles);
    const PushedSoil pushed = push_aside(t, under, soil, kPressedDepth);
    const double top = t.surface_height(t.nx() / 2, t.ny() / 2);
    std::printf("[ measured ] plate %.3f m into the bed: %.3f kg pushed, column top %.4f m\n", sink,
                pushed.moved, top);
    if (sink < kPressedDepth) {
      EXPECT_EQ(pushed.moved, 0.0);
      EXPECT_NEAR(top, 1.0, 1e-12);
    } else {
      EXPECT_NEAR(pushed.moved, 100 * sink * h * h * kFieldBulkDensity, 1e-9);
      EXPECT_NEAR(top, 1.0 - sink, 1e-12);
    }
  }
  VoxelTerrain t = level_bed(h, 1.0);
  const Plate p = plate_at(0.9);
  EXPECT_THROW(push_aside(t, tool_underside(t, p.vertices, p.triangles), soil, -0.01), Error);
}

}  // namespace
}  // namespace talus
