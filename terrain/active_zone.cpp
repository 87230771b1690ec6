#include "terrain/active_zone.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "host/error.hpp"
#include "terrain/earthmoving_equation.hpp"

namespace talus {
namespace {

constexpr double kDegree = M_PI / 180.0;
// the columns' heights are sums of cell volumes over h^2: 1 nm is far above their rounding and far
// below a grain [m]
constexpr double kOverlapRounding = 1e-9;
// a triangle whose projection onto the ground is under 1e-12 m^2 (twice its area) is seen edge-on
// from above: far below any plate of a bucket, far above the rounding of a vertical plate's
constexpr double kEdgeOnArea = 1e-12;
// a column centre on a triangle's edge, within rounding of the barycentric coordinates, belongs to
// it (so two triangles sharing the edge both see it)
constexpr double kOnEdge = 1e-12;

// the soil's surface under a point: the given heights (dynamic soil included) or the voxels'
// columns, interpolated bilinearly between the column centres (as terrain/heightmap's surface),
// so that a plane cut into the voxels reads as that plane and not as steps a cell wide; the
// ground off the grid
double surface_under(const VoxelTerrain& terrain, const std::vector<double>* surface,
                     const Vec3& p) {
  const double h = terrain.cell();
  const double fx = (p.x() - terrain.x0()) / h - 0.5, fy = (p.y() - terrain.y0()) / h - 0.5;
  if (!(fx > -1.0 && fx < terrain.nx() && fy > -1.0 && fy < terrain.ny())) return terrain.z0();
  const int i = std::clamp(static_cast<int>(std::floor(fx)), 0, std::max(0, terrain.nx() - 2));
  const int j = std::clamp(static_cast<int>(std::floor(fy)), 0, std::max(0, terrain.ny() - 2));
  const double u = std::clamp(fx - i, 0.0, 1.0), v = std::clamp(fy - j, 0.0, 1.0);
  const auto height = [&](int a, int b) {
    a = std::min(a, terrain.nx() - 1);
    b = std::min(b, terrain.ny() - 1);
    return surface ? (*surface)[static_cast<size_t>(b) * terrain.nx() + a]
                   : terrain.surface_height(a, b);
  };
  return (1 - u) * (1 - v) * height(i, j) + u * (1 - v) * height(i + 1, j) +
         (1 - u) * v * height(i, j + 1) + u * v * height(i + 1, j + 1);
}

// where a plane rising from the tip leaves through the surface along the centre line: the first
// s (stepping by a quarter cell in direction `sign`) where the plane stands on or above the
// surface, interpolated linearly between the last two samples; the whole grid's length if never
double exit_along(const VoxelTerrain& terrain, const std::vector<double>* surface,
                  const ActiveZone& zone, double sign, double rise) {
  const double step = 0.25 * terrain.cell();
  const double longest = (terrain.nx() + terrain.ny()) * terrain.cell();
  double prev_gap = zone.depth;  // surface minus plane at s = 0
  for (double s = step; s <= longest; s += step) {
    const Vec3 p = zone.tip + sign * s * zone.forward;
    const double gap = surface_under(terrain, surface, p) - (zone.tip.z() + s * rise);
    if (gap <= 0.0) return s - step * gap / (gap - prev_gap);
    prev_gap = gap;
  }
  return longest;
}

}  // namespace

bool ActiveZone::floor_at(double s, double* z_lo) const {
  if (s < -reach_behind || s > reach_ahead) return false;
  const double alpha = rake_deg * kDegree;
  if (s >= 0.0) {
    *z_lo = tip.z() + s * std::tan(failure_angle_deg * kDegree);
  } else {
    if (rake_deg >= 90.0) return false;  // behind a vertical tool: no zone
    *z_lo = tip.z() - s * std::tan(alpha);
  }
  return true;
}

bool ActiveZone::contains(const Vec3& p) const {
  const Vec3 r = p - tip;
  if (std::abs(r.dot(along)) > 0.5 * width) return false;
  double lo = 0.0;
  return floor_at(r.dot(forward), &lo) && p.z() >= lo;
}

ActiveZone predict_active_zone(const VoxelTerrain& terrain, const ToolEdges& tool,
                               const BulkSoil& soil, const std::vector<double>* surface) {
  if (surface && surface->size() != static_cast<size_t>(terrain.nx()) * terrain.ny())
    throw Error("active zone: the soil surface has " + std::to_string(surface->size()) +
                " heights for " + std::to_string(terrain.nx() * terrain.ny()) + " columns");
  ActiveZone zone;
  const Vec3 edge = tool.cutting_right - tool.cutting_left;
  zone.width = edge.norm();
  if (!(zone.width >= 1e-3)) throw Error("active zone: the cutting edge is shorter than 1 mm");
  zone.along = edge / zone.width;
  zone.tip = 0.5 * (tool.cutting_left + tool.cutting_right);
  // forward: horizontal, normal to the edge, away from the top edge's side
  Vec3 forward = Vec3::UnitZ().cross(zone.along);
  if (!(forward.norm() >= 0.1)) throw Error("active zone: the cutting edge stands nearly vertical");
  forward.normalize();
  const Vec3 top = 0.5 * (tool.top_left + tool.top_right) - zone.tip;
  if (top.dot(forward) > 0.0) forward = -forward;
  // a tool whose top edge stands straight above its tip faces the way it moves
  if (std::abs(top.dot(forward)) < 1e-9 * top.norm() && tool.velocity.dot(forward) < 0.0)
    forward = -forward;
  zone.forward = forward;
  // the rake: the tool plane's angle from the horizontal behind the tip, in the excavation plane
  zone.rake_deg = std::atan2(top.z(), -top.dot(forward)) / kDegree;
  zone.rake_deg = std::clamp(zone.rake_deg, 1.0, 179.0);
  // depth and speed in the excavation plane
  zone.depth = surface_under(terrain, surface, zone.tip) - zone.tip.z();
  const Vec3 v = tool.velocity;
  // only motion into the wedge counts: forward, or up through the soil over the tool; a tool
  // backing out or pressing down fails nothing ahead of it
  zone.speed = std::hypot(std::max(0.0, v.dot(forward)), std::max(0.0, v.z()));
  // the failure plane: none where the tool leans so far over the soil ahead that rake, tool
  // friction and internal friction reach 180 deg (the FEE has no wedge; the tool presses the soil
  // down rather than failing it ahead), and then no zone
  const double tool_friction_deg = std::atan(soil.tool_friction) / kDegree;
  if (zone.rake_deg + tool_friction_deg + soil.effective_friction_deg() >= 180.0) return zone;
  zone.failure_angle_deg =
      fee_failure_angle(zone.rake_deg, tool_friction_deg, soil.effective_friction_deg());
  zone.active = zone.depth > 0.0 && zone.speed > soil.activation_speed;
  if (zone.depth <= 0.0) return zone;
  // where the two planes leave through the surface
  zone.reach_ahead =
      exit_along(terrain, surface, zone, 1.0, std::tan(zone.failure_angle_deg * kDegree));
  if (zone.rake_deg < 90.0)
    zone.reach_behind = exit_along(terrain, surface, zone, -1.0, std::tan(zone.rake_deg * kDegree));
  return zone;
}

ActiveZone within_reach(const ActiveZone& zone, double reach) {
  if (!(reach >= 0.0 && std::isfinite(reach)))
    throw Error("active zone: an excavation reach of " + std::to_string(reach) +
                " m (0 for the whole zone, or a distance ahead of the cutting edge)");
  ActiveZone part = zone;
  if (reach > 0.0) part.reach_ahead = std::min(zone.reach_ahead, reach);
  return part;
}

bool zone_interval(const ActiveZone& zone, const VoxelTerrain& terrain, int i, int j, double* z_lo,
                   double* z_hi) {
  const Vec3 c(terrain.column_x(i), terrain.column_y(j), zone.tip.z());
  const Vec3 r = c - zone.tip;
  if (std::abs(r.dot(zone.along)) > 0.5 * zone.width) return false;
  double lo = 0.0;
  if (!zone.floor_at(r.dot(zone.forward), &lo)) return false;
  *z_lo = std::max(lo, terrain.z0());
  *z_hi = terrain.surface_height(i, j);
  return *z_hi > *z_lo;
}

namespace {

// the columns a zone can reach: the box around its footprint, clamped to the grid
void zone_columns(const ActiveZone& zone, const VoxelTerrain& terrain, int* i0, int* i1, int* j0,
                  int* j1) {
  const Vec3 half = 0.5 * zone.width * zone.along;
  const Vec3 corners[4] = {zone.tip - half + zone.reach_ahead * zone.forward,
                           zone.tip + half + zone.reach_ahead * zone.forward,
                           zone.tip - half - zone.reach_behind * zone.forward,
                           zone.tip + half - zone.reach_behind * zone.forward};
  double xlo = INFINITY, xhi = -INFINITY, ylo = INFINITY, yhi = -INFINITY;
  for (const Vec3& p : corners) {
    xlo = std::min(xlo, p.x());
    xhi = std::max(xhi, p.x());
    ylo = std::min(ylo, p.y());
    yhi = std::max(yhi, p.y());
  }
  const double h = terrain.cell();
  *i0 = std::max(0, static_cast<int>(std::floor((xlo - terrain.x0()) / h)));
  *i1 = std::min(terrain.nx() - 1, static_cast<int>(std::floor((xhi - terrain.x0()) / h)));
  *j0 = std::max(0, static_cast<int>(std::floor((ylo - terrain.y0()) / h)));
  *j1 = std::min(terrain.ny() - 1, static_cast<int>(std::floor((yhi - terrain.y0()) / h)));
}

}  // namespace

bool failure_plane_column(const ActiveZone& zone, const VoxelTerrain& terrain, int i, int j,
                          PlaneFloorColumn* column) {
  if (!zone.active) return false;
  // the column's centre in the zone's frame: within its width, on the failure plane's part
  const double h = terrain.cell();
  const Vec3 centre(terrain.column_x(i), terrain.column_y(j), zone.tip.z());
  const Vec3 r = centre - zone.tip;
  const double s = r.dot(zone.forward);
  if (std::abs(r.dot(zone.along)) > 0.5 * zone.width || s < 0.0 || s > zone.reach_ahead)
    return false;
  // excavated to the plane there, or deeper (a plane risen since, as the tool lifts), on soil
  const double beta = zone.failure_angle_deg * kDegree;
  const double tan_beta = std::tan(beta);
  const double top = terrain.surface_height(i, j);
  if (top <= terrain.z0() || top > zone.tip.z() + s * tan_beta + kOverlapRounding) return false;
  // the footprint's half extents along forward and along (a turned zone sees the square wider)
  const double half_forward = 0.5 * h * (std::abs(zone.forward.x()) + std::abs(zone.forward.y()));
  const double half_along = 0.5 * h * (std::abs(zone.along.x()) + std::abs(zone.along.y()));
  column->top = std::max(terrain.z0(), top - half_forward * tan_beta);
  // the plate: its top face the plane over the footprint, its depth the footprint's length along
  // forward (at least the plane's fall over it, h tan(beta) cos(beta), for beta up to 90 deg)
  const Vec3 up = Vec3::UnitZ();
  const Vec3 uphill = std::cos(beta) * zone.forward + std::sin(beta) * up;
  const Vec3 normal = -std::sin(beta) * zone.forward + std::cos(beta) * up;
  Eigen::Matrix3d axes;
  axes.col(0) = uphill;
  axes.col(1) = zone.along;
  axes.col(2) = normal;
  const double half_depth = half_forward;
  column->plate =
      StaticGeom::box(Vec3(centre.x(), centre.y(), top) - half_depth * normal,
                      Vec3(half_forward / std::cos(beta), half_along, half_depth), axes);
  return true;
}

double zone_soil_mass(const ActiveZone& zone, const VoxelTerrain& terrain) {
  if (zone.depth <= 0.0) return 0.0;
  int i0 = 0, i1 = 0, j0 = 0, j1 = 0;
  zone_columns(zone, terrain, &i0, &i1, &j0, &j1);
  double mass = 0.0;
  for (int j = j0; j <= j1; ++j)
    for (int i = i0; i <= i1; ++i) {
      double lo = 0.0, hi = 0.0;
      if (zone_interval(zone, terrain, i, j, &lo, &hi))
        mass += terrain.soil_between(i, j, lo, hi).mass;
    }
  return mass;
}

DynamicSoil excavate(VoxelTerrain& terrain, const ActiveZone& zone, const BulkSoil& soil,
                     std::vector<ExcavatedColumn>* columns) {
  DynamicSoil dynamic;
  if (!zone.active) return dynamic;
  int i0 = 0, i1 = 0, j0 = 0, j1 = 0;
  zone_columns(zone, terrain, &i0, &i1, &j0, &j1);
  // column by column in a fixed order, so the same bits on every run
  for (int j = j0; j <= j1; ++j)
    for (int i = i0; i <= i1; ++i) {
      double lo = 0.0, hi = 0.0;
      if (!zone_interval(zone, terrain, i, j, &lo, &hi)) continue;
      const SoilTaken taken = terrain.take(i, j, lo, hi);
      if (columns && taken.mass > 0.0)
        columns->push_back({i, j, lo,
                            std::min(hi, lo + taken.volume / (terrain.cell() * terrain.cell())),
                            taken.mass});
      dynamic.mass += taken.mass;
      dynamic.bank_volume += taken.bank_volume;
    }
  dynamic.volume = dynamic.bank_volume * soil.swell;
  return dynamic;
}

std::vector<double> tool_underside(const VoxelTerrain& terrain, const std::vector<Vec3>& vertices,
                                   const std::vector<std::array<int, 3>>& triangles) {
  const int nx = terrain.nx(), ny = terrain.ny();
  const double h = terrain.cell();
  std::vector<double> lowest(static_cast<size_t>(nx) * ny, INFINITY);
  for (const auto& t : triangles) {
    const Vec3 &a = vertices[t[0]], &b = vertices[t[1]], &c = vertices[t[2]];
    // the projection's signed double area; edge-on from above: no column centre inside
    const double area = (b.x() - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (b.y() - a.y());
    if (std::abs(area) < kEdgeOnArea) continue;
    // the column centres in the projection's box
    const double xlo = std::min({a.x(), b.x(), c.x()}), xhi = std::max({a.x(), b.x(), c.x()});
    const double ylo = std::min({a.y(), b.y(), c.y()}), yhi = std::max({a.y(), b.y(), c.y()});
    const int i0 = std::max(0, static_cast<int>(std::ceil((xlo - terrain.x0()) / h - 0.5)));
    const int i1 = std::min(nx - 1, static_cast<int>(std::floor((xhi - terrain.x0()) / h - 0.5)));
    const int j0 = std::max(0, static_cast<int>(std::ceil((ylo - terrain.y0()) / h - 0.5)));
    const int j1 = std::min(ny - 1, static_cast<int>(std::floor((yhi - terrain.y0()) / h - 0.5)));
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i) {
        // barycentric coordinates of the centre in the projection, edges included
        const double x = terrain.column_x(i), y = terrain.column_y(j);
        const double u = ((b.x() - x) * (c.y() - y) - (c.x() - x) * (b.y() - y)) / area;
        const double v = ((c.x() - x) * (a.y() - y) - (a.x() - x) * (c.y() - y)) / area;
        const double w = 1.0 - u - v;
        if (u < -kOnEdge || v < -kOnEdge || w < -kOnEdge) continue;
        double& low = lowest[static_cast<size_t>(j) * nx + i];
        low = std::min(low, u * a.z() + v * b.z() + w * c.z());
      }
  }
  return lowest;
}

std::vector<char> closed_columns(const VoxelTerrain& terrain,
                                 const std::vector<double>& underside) {
  const int nx = terrain.nx(), ny = terrain.ny();
  if (underside.size() != static_cast<size_t>(nx) * ny)
    throw Error("tool underside: " + std::to_string(underside.size()) +
                " columns for the terrain's " + std::to_string(nx * ny));
  std::vector<char> closed(underside.size(), 0);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const size_t c = static_cast<size_t>(j) * nx + i;
      closed[c] = underside[c] <= terrain.surface_height(i, j) + terrain.cell();
    }
  return closed;
}

PushedSoil push_aside(VoxelTerrain& terrain, const std::vector<double>& underside,
                      const BulkSoil& soil, double pressed_depth) {
  if (!(pressed_depth >= 0.0))
    throw Error("push aside: a pressed depth of " + std::to_string(pressed_depth) +
                " m (it is 0 or more)");
  const std::vector<char> closed = closed_columns(terrain, underside);
  const int nx = terrain.nx(), ny = terrain.ny();
  const double h = terrain.cell();
  const double capacity = terrain.nz() * h * h * h;  // a column's volume [m^3]
  PushedSoil pushed;
  // column by column in a fixed order, so the same bits on every run
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const double low = underside[static_cast<size_t>(j) * nx + i];
      if (!std::isfinite(low)) continue;
      const double lo = std::max(low, terrain.z0()), hi = terrain.surface_height(i, j);
      // an overlap within the columns' rounding is none (a column cut to the tool's underside
      // stands a few 1e-16 m above it), and one within the pressed depth the soil bears
      if (!(hi > lo + std::max(kOverlapRounding, pressed_depth))) continue;
      const SoilTaken taken = terrain.take(i, j, lo, hi);
      if (!(taken.mass > 0.0)) continue;
      const double compaction =
          std::min(kMaxCompaction, taken.mass / (terrain.bank_density() * taken.volume));
      // the nearest open column with room for all of it, ring by ring
      int to_i = -1, to_j = -1;
      for (int r = 1; r <= kPushReach && to_i < 0; ++r) {
        double best = INFINITY;
        for (int b = std::max(0, j - r); b <= std::min(ny - 1, j + r); ++b)
          for (int a = std::max(0, i - r); a <= std::min(nx - 1, i + r); ++a) {
            if (std::max(std::abs(a - i), std::abs(b - j)) != r) continue;  // the ring only
            if (closed[static_cast<size_t>(b) * nx + a]) continue;
            if (terrain.column_volume(a, b) + taken.volume > capacity) continue;
            const double d2 = (a - i) * (a - i) + (b - j) * (b - j);
            if (d2 < best) best = d2, to_i = a, to_j = b;
          }
      }
      if (to_i >= 0) {
        terrain.deposit(to_i, to_j, taken.mass, compaction);
        pushed.moved += taken.mass;
      } else {
        pushed.left.mass += taken.mass;
        pushed.left.bank_volume += taken.bank_volume;
      }
    }
  pushed.left.volume = pushed.left.bank_volume * soil.swell;
  return pushed;
}

}  // namespace talus
