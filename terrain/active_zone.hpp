// The active zone of the type-G terrain (issue 14, paper §4.4, Servin, Berglund & Nystedt 2021):
// the soil a moving tool is about to fail, predicted every step from the tool's cutting edge, its
// top edge and its motion. It is the wedge of the fundamental earthmoving equation
// (terrain/earthmoving_equation) in the excavation plane, extruded along the cutting edge:
//
//             surface ____________________________
//     top edge  \                        ___/ failure plane, beta from the horizontal
//                \ tool plane,     ___/
//                 \ rake alpha ___/
//                  \      ___/
//          cutting  *___/
//             edge
//
// Frame: the tip is the cutting edge's midpoint; `along` runs along the cutting edge; `forward` is
// horizontal, normal to the cutting edge, pointing away from the top edge's side (into the soil
// the tool faces). In the excavation plane (forward, up) a point is (s, z). The tool plane runs
// from the tip through the top edge at the rake angle alpha from the horizontal behind the tip
// (90 deg: a vertical blade; a loader's bucket with its bottom level, about 45 deg). The failure
// plane runs from the tip ahead at beta, the FEE's least-force angle for this alpha, the
// bucket-soil friction and the soil's effective internal friction phi + psi (paper §4.4: dilatancy
// "adds directly to the internal friction", 32 + 8 = 40 deg). The zone is the soil above both
// planes and under the surface, as wide as the cutting edge, from where the tool plane leaves the
// surface behind the tip to where the failure plane leaves it ahead.
//
// Soil turns dynamic only while the tool moves through it: when the cutting edge is under the
// surface and its speed into the wedge in the excavation plane (forward, or up) is above the
// activation speed (0.1 m/s, the reference engine's documented threshold, SPEC §2.5).
#pragma once
#include <array>
#include <vector>

#include "solvers/particles.hpp"
#include "terrain/voxel_terrain.hpp"

namespace talus {

// the bulk soil of the type-G terrain: the paper's §4.4 values for the field's gravel
struct BulkSoil {
  double internal_friction_deg = 32.0;  // phi
  double dilatancy_deg = 8.0;           // psi: phi + psi = 40 deg on a failure plane
  double tool_friction = 0.2;           // bucket-soil friction coefficient
  // the volume of excavated (dynamic) soil over its bank volume: the reference engine's default
  // swell factor, 1.1 (AGX Dynamics terrain material; the paper gives none)
  double swell = 1.1;
  // tool speed in the excavation plane above which soil turns dynamic [m/s] (SPEC §2.5)
  double activation_speed = 0.1;
  double effective_friction_deg() const { return internal_friction_deg + dilatancy_deg; }
};

// where the tool is: the ends of its cutting edge and of its top edge, and the cutting edge's
// velocity (the bucket's, at the edge's midpoint) [m, m/s]
struct ToolEdges {
  Vec3 cutting_left = Vec3::Zero(), cutting_right = Vec3::Zero();
  Vec3 top_left = Vec3::Zero(), top_right = Vec3::Zero();
  Vec3 velocity = Vec3::Zero();
};

struct ActiveZone {
  bool active = false;  // the tool cuts: edge under the surface, moving faster than activation
  Vec3 tip = Vec3::Zero();
  Vec3 along = Vec3::UnitY();
  Vec3 forward = Vec3::UnitX();
  double width = 0.0;              // the cutting edge's length [m]
  double depth = 0.0;              // the surface above the tip [m] (negative: the tip is above it)
  double speed = 0.0;              // the tool's speed in the excavation plane [m/s]
  double rake_deg = 90.0;          // alpha
  double failure_angle_deg = 0.0;  // beta
  double reach_ahead = 0.0;        // s where the failure plane leaves through the surface [m]
  double reach_behind = 0.0;       // -s where the tool plane leaves through the surface [m]

  // the zone's floor at s from the tip (the zone is the soil above it, up to the surface): the
  // failure plane ahead of the tip, the tool plane behind it (alpha < 90 deg); false where s lies
  // outside [-reach_behind, reach_ahead]. (forward is taken away from the top edge, so the tool
  // plane stands vertical or leans back over the soil it lifts: alpha <= 90 deg)
  bool floor_at(double s, double* z_lo) const;
  // is the point within the zone's width and reach and above its floor? (the surface is not
  // asked: the zone's particles stand above the voxels' surface)
  bool contains(const Vec3& p) const;
};

// predicts the zone from the tool's edges on the soil's surface: the voxels' columns, or `surface`
// when given (nx × ny heights, index j nx + i: the dynamic soil heaped on the voxels included, as
// terrain/multiscale_terrain passes it). Throws talus::Error for a cutting edge shorter than 1 mm
// or lying nearly vertical (no excavation plane), or a surface of the wrong size
ActiveZone predict_active_zone(const VoxelTerrain& terrain, const ToolEdges& tool,
                               const BulkSoil& soil, const std::vector<double>* surface = nullptr);

// the zone's share of column (i, j): its soil between z_lo and z_hi; false when the column's centre
// lies outside the zone or the zone holds none of its soil
bool zone_interval(const ActiveZone& zone, const VoxelTerrain& terrain, int i, int j, double* z_lo,
                   double* z_hi);

// the part of a zone no farther than `reach` [m] ahead of its cutting edge: the same zone with
// reach_ahead cut to `reach` (0: the whole zone). What turns dynamic is then the soil the edge is
// about to meet, and the wedge's far end stays voxels until the edge comes within `reach` of it (a
// type-G study, MultiscaleOptions::excavation_reach; docs/multiscale.md "Excavation reach").
// Throws talus::Error for a negative or non-finite reach
ActiveZone within_reach(const ActiveZone& zone, double reach);

// the zone's floor as its particles stand on it (MultiscaleOptions::failure_plane_floor, the
// default since 2026-11-30): the failure plane itself, not the staircase of its columns.
// Excavation leaves each column of the zone at the plane's height over the column's centre, so on
// a grid of cell h the floor is a staircase whose steps, h tan(beta) high (17 cm at G200 with
// HD27's beta of about 40 deg, most of a grain), face the tool: the soil it pushes has to climb
// each one, where the model's wedge slides up a plane (docs/multiscale.md "The zone's floor is
// its failure plane"). Column (i, j) is under the plane when the zone is active, the column's
// centre lies within the zone's width ahead of the tip (the failure plane's part,
// 0 <= s <= reach_ahead) and its top stands on soil at or below the plane
// there (excavated to it, within a nanometre, or deeper: the plane rises as the tool lifts). Such
// a column's top is shown to the particles as a plane parallel to the failure plane through the
// top over the column's centre (the same soil under it): `top`, that plane's height at the
// footprint's nearest point to the tip, for the column's box (nothing of it stands above the
// plane), and `plate`, a box whose top face is that plane over the footprint (its extent along
// `forward` and `along`, so a turned zone's plates overlap a little) and deep enough to cover the
// box's top. The plates of neighbouring columns cut to the plane join into the plane itself
struct PlaneFloorColumn {
  double top = 0.0;
  StaticGeom plate;
};
bool failure_plane_column(const ActiveZone& zone, const VoxelTerrain& terrain, int i, int j,
                          PlaneFloorColumn* column);

// the solid soil inside the zone [kg], left in place
double zone_soil_mass(const ActiveZone& zone, const VoxelTerrain& terrain);

// soil turned dynamic by the tool: its mass, the bank volume it stood for (mass / rho_bank) and
// the volume it fills now, swollen (bank volume times the swell) [kg, m^3]
struct DynamicSoil {
  double mass = 0.0;
  double bank_volume = 0.0;
  double volume = 0.0;
};

// one column's share of an excavation: where the soil was [m] and its mass [kg]
struct ExcavatedColumn {
  int i = 0, j = 0;
  double z_lo = 0.0, z_hi = 0.0;
  double mass = 0.0;
};

// excavation: every column's share of an active zone leaves the terrain as dynamic soil; an
// inactive zone takes nothing. `columns`, when given, receives each column's share, in the order
// taken (by row j, then i)
DynamicSoil excavate(VoxelTerrain& terrain, const ActiveZone& zone, const BulkSoil& soil,
                     std::vector<ExcavatedColumn>* columns = nullptr);

// the tool's underside over the terrain: per column (index j nx + i) the lowest point of the
// tool's surface over the column's centre, +inf where the tool does not pass over it. The tool is
// its triangles in the world (`vertices` indexed by `triangles`); a triangle seen edge-on from
// above (a vertical side plate) covers no column centre and is skipped, its neighbours cover its
// columns
std::vector<double> tool_underside(const VoxelTerrain& terrain, const std::vector<Vec3>& vertices,
                                   const std::vector<std::array<int, 3>>& triangles);

// the columns a tool stands on: those whose top lies within a cell below the tool's underside
// (or above it). Soil neither slides into them (terrain/avalanche) nor is pushed into them
std::vector<char> closed_columns(const VoxelTerrain& terrain, const std::vector<double>& underside);

// what push_aside moved: the soil taken from under the tool's body and laid on open columns [kg],
// and what found no open column with room within kPushReach and is handed on as dynamic soil
struct PushedSoil {
  double moved = 0.0;
  DynamicSoil left;
};

// [m] how far a tool may press into the voxel surface before the soil under it gives way and
// push_aside moves it, in a dig with the terrain's support under the bucket: 1 cm, above what the
// support's rows let the machine's whole weight press in (150 kN on four points of 1e8 N/m, the
// bucket's ground-contact stiffness: 0.4 mm) and below the finest level's cell (G50: 5 cm)
inline constexpr double kPressedDepth = 0.01;

// how far push_aside looks for an open column with room [cells]
inline constexpr int kPushReach = 8;

// the soil the tool's body overlaps is pushed aside: in every column whose centre the tool passes
// over below the column's surface (`underside`, from tool_underside), the soil from the tool's
// lowest point there upwards is taken (what lay above that point drops into the gap, so the
// column ends where the tool's underside is) and laid, with its compaction, on the nearest open
// column (closed_columns) with room, the nearest by centre distance, ties in row order, searched
// ring by ring out to kPushReach cells. The active zone fails the soil ahead of the cutting edge;
// this moves what the rest of the tool sweeps, which no zone predicts: a bucket's heel dragged back
// through the pile (a berm forms behind it), its body pressed in where the zone is not active.
// Without it the voxel columns stood inside the bucket and scraped its load out
// (docs/multiscale.md). Columns are taken in row order, so the same bits on every run
//
// `pressed_depth` [m]: soil standing less than this above the tool's underside is pressed, not
// pushed (0: every overlap beyond rounding is pushed). The terrain's support under the bucket
// (terrain/bucket_support) holds the bucket's bottom on the surface with stiff rows that let it
// press in a little; pushing that little aside every step would let the bucket sink through the
// support step by step, so a dig with the support passes kPressedDepth
PushedSoil push_aside(VoxelTerrain& terrain, const std::vector<double>& underside,
                      const BulkSoil& soil, double pressed_depth = 0.0);

}  // namespace talus
