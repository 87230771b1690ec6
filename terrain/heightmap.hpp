// The terrain surface as a regular grid of heights (SPEC §2.5), with an Embree scene of its
// triangles for ray queries: heights under a point by a vertical ray, and a simulated 2-D laser
// line scan of the pile as the field tests measured it before loading.
//
// Grid. Node (i, j) sits at (x0 + i dx, y0 + j dx), i < nx, j < ny, row-major by j. Each grid cell
// between four nodes is split along its diagonal (i, j)–(i+1, j+1) into two triangles, so the
// surface is the piecewise-linear interpolation of the node heights (`interpolate`).
//
// Precision. Embree sees float vertices and float rays and only tells which triangle a ray hits;
// the hit point is then recomputed in double on that triangle's plane from the double heights.
// Away from triangle edges this is exact; on an edge the float ray may pick the neighbour, whose
// plane meets the true one there, so the error is float rounding of the ray times the slope jump.
#pragma once
#include <Eigen/Core>
#include <algorithm>
#include <optional>
#include <vector>

#include "solvers/particles.hpp"
#include "solvers/embree.hpp"

namespace talus {

// the piecewise-linear surface of a grid of node heights at (x, y): node (i, j) at
// (x0 + i dx, y0 + j dx) with height `height(i, j)`, each cell split along its (i, j)-(i+1, j+1)
// diagonal (the triangles of the header's grid); nullopt off the grid (outside the nodes' hull)
// and for a grid of fewer than 2 x 2 nodes (no triangle).
// One law for every grid of heights: Heightmap::interpolate and VoxelTerrain::surface_at
template <class Height>
std::optional<double> piecewise_linear_height(double x0, double y0, double dx, int nx, int ny,
                                              const Height& height, double x, double y) {
  if (nx < 2 || ny < 2) return std::nullopt;
  const double s = (x - x0) / dx, t = (y - y0) / dx;
  if (!(s >= 0 && t >= 0 && s <= nx - 1 && t <= ny - 1)) return std::nullopt;
  const int i = std::min(static_cast<int>(s), nx - 2), j = std::min(static_cast<int>(t), ny - 2);
  const double u = s - i, v = t - j;
  const double h00 = height(i, j), h10 = height(i + 1, j), h01 = height(i, j + 1),
               h11 = height(i + 1, j + 1);
  // lower triangle (00, 10, 11) where u >= v, upper (00, 11, 01) otherwise
  if (u >= v) return h00 + u * (h10 - h00) + v * (h11 - h10);
  return h00 + v * (h01 - h00) + u * (h11 - h01);
}

class Heightmap {
 public:
  // a grid of given node heights (nx × ny, index j * nx + i); throws talus::Error for a grid
  // smaller than 2 × 2, dx <= 0, a size mismatch or non-finite heights
  Heightmap(double x0, double y0, double dx, int nx, int ny, std::vector<double> heights,
            const embree::Device& device = embree::Device());

  // the surface of a particle bed: each node takes the highest particle top (centre z + radius)
  // among particles whose centre lies in its bin, the dx × dx square centred on the node.
  // Empty bins (holes) are filled from their filled neighbours, ring by ring, with the mean of
  // the filled 8-neighbours; throws talus::Error when no particle falls on the grid.
  static Heightmap from_particles(const Particles& particles, double x0, double y0, double dx, int nx,
                                  int ny, const embree::Device& device = embree::Device());

  int nx() const { return nx_; }
  int ny() const { return ny_; }
  double dx() const { return dx_; }
  double x0() const { return x0_; }
  double y0() const { return y0_; }
  double height(int i, int j) const { return h_[static_cast<size_t>(j) * nx_ + i]; }
  const std::vector<double>& heights() const { return h_; }
  int filled_holes() const { return filled_holes_; }  // bins without particles (from_particles)

  // the piecewise-linear surface at (x, y) in double, without Embree; nullopt off the grid
  std::optional<double> interpolate(double x, double y) const;

  // the surface height under (x, y) by a vertical ray cast down from above the highest node
  // (rtcIntersect1); nullopt when the ray misses (off the grid)
  std::optional<double> height_at(double x, double y) const;

  // first hit of the ray origin + t dir, t > 0 (dir need not be unit); nullopt on a miss
  std::optional<Eigen::Vector3d> cast(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir) const;

  // a 2-D laser line scan in the vertical plane y = sensor.y(): n rays from the sensor towards
  // the ground points (x_k, y, z_min), x_k evenly spaced over [x_from, x_to] and z_min the lowest
  // node, each returning the first surface hit as (x, z); rays that leave the grid are dropped,
  // so occluded ground simply has no points. Throws talus::Error for n < 2 or a sensor outside
  // the scan plane (|sensor.y() - y| > 1e-9 m).
  std::vector<Eigen::Vector2d> scan_profile(double y, double x_from, double x_to, int n,
                                            const Eigen::Vector3d& sensor) const;

 private:
  double x0_, y0_, dx_;
  int nx_, ny_;
  std::vector<double> h_;
  double h_min_ = 0.0, h_max_ = 0.0;
  int filled_holes_ = 0;
  embree::Scene scene_;
};

}  // namespace talus
