// terrain/heightmap: the surface of a particle bed on a regular grid, heights by vertical Embree
// rays, and a simulated 2-D laser line scan of a 32° pile face.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include "host/error.hpp"
#include "terrain/heightmap.hpp"

namespace talus {
namespace {

// random particles resting on the plane z = 0.5 + 0.2 x - 0.1 y: the map is the particles' top,
// plane + 2 r at the node, within a radius; a hole left in the bed is filled from around it
TEST(Heightmap, ParticlesOnASlopedPlaneGiveTheirTopWithinARadius) {
  const unsigned seed = std::random_device{}();
  SCOPED_TRACE("seed " + std::to_string(seed));
  std::mt19937_64 rng(seed);
  const auto plane = [](double x, double y) { return 0.5 + 0.2 * x - 0.1 * y; };
  const double r = 0.05, dx = 0.1;
  const int nx = 41, ny = 31;  // 4 m x 3 m
  std::uniform_real_distribution<double> ux(-0.05, 4.05), uy(-0.05, 3.05), sink(-0.2 * r, 0.0);
  Particles p;
  for (int k = 0; k < 12 * nx * ny; ++k) {
    const double x = ux(rng), y = uy(rng);
    if (std::hypot(x - 2.0, y - 1.5) < 0.25) continue;  // the hole
    p.add(Vec3(x, y, plane(x, y) + r + sink(rng)), r, 2590.0);
  }
  const Heightmap map = Heightmap::from_particles(p, 0.0, 0.0, dx, nx, ny);
  EXPECT_GT(map.filled_holes(), 0);
  double worst = 0.0, worst_hole = 0.0;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const double x = i * dx, y = j * dx;
      const double err = std::abs(map.height(i, j) - (plane(x, y) + 2 * r));
      double& w = std::hypot(x - 2.0, y - 1.5) < 0.25 ? worst_hole : worst;
      w = std::max(w, err);
    }
  std::printf("%zu particles, %d holes filled; max |height - (plane + 2r)| %.4f m (bed), %.4f m (hole), r = %.2f\n",
              p.size(), map.filled_holes(), worst, worst_hole, r);
  EXPECT_LT(worst, r);
  EXPECT_LT(worst_hole, r);
}

// the ray heights are the triangle interpolation of the nodes (independent formula here) on a
// rough random surface, and equal the bilinear interpolation on a plane
TEST(Heightmap, RayHeightsEqualTheTriangleInterpolation) {
  const unsigned seed = std::random_device{}();
  SCOPED_TRACE("seed " + std::to_string(seed));
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const int nx = 30, ny = 20;
  const double x0 = -1.3, y0 = 2.1, dx = 0.1;
  std::vector<double> rough(nx * ny), flat(nx * ny);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      rough[j * nx + i] = 0.3 * u(rng);
      flat[j * nx + i] = 1.0 + 0.35 * (x0 + i * dx) - 0.2 * (y0 + j * dx);
    }
  const Heightmap a(x0, y0, dx, nx, ny, rough), b(x0, y0, dx, nx, ny, flat);
  double worst_rough = 0.0, worst_flat = 0.0, worst_interp = 0.0;
  for (int k = 0; k < 20000; ++k) {
    const double x = x0 + (nx - 1) * dx * u(rng), y = y0 + (ny - 1) * dx * u(rng);
    // the cell's two triangles split along (i, j)-(i+1, j+1)
    const double s = (x - x0) / dx, t = (y - y0) / dx;
    const int i = std::min(static_cast<int>(s), nx - 2), j = std::min(static_cast<int>(t), ny - 2);
    const double fu = s - i, fv = t - j;
    const double h00 = rough[j * nx + i], h10 = rough[j * nx + i + 1];
    const double h01 = rough[(j + 1) * nx + i], h11 = rough[(j + 1) * nx + i + 1];
    const Vec3 n = fu >= fv ? Vec3(dx, 0, h10 - h00).cross(Vec3(dx, dx, h11 - h00))
                            : Vec3(dx, dx, h11 - h00).cross(Vec3(0, dx, h01 - h00));
    const double expected = h00 - (n.x() * fu * dx + n.y() * fv * dx) / n.z();
    const auto ray = a.height_at(x, y);
    ASSERT_TRUE(ray.has_value()) << x << " " << y;
    worst_rough = std::max(worst_rough, std::abs(*ray - expected));
    worst_interp = std::max(worst_interp, std::abs(*a.interpolate(x, y) - expected));
    const double bilinear = (1 - fu) * (1 - fv) * flat[j * nx + i] + fu * (1 - fv) * flat[j * nx + i + 1] +
                            (1 - fu) * fv * flat[(j + 1) * nx + i] + fu * fv * flat[(j + 1) * nx + i + 1];
    worst_flat = std::max(worst_flat, std::abs(*b.height_at(x, y) - bilinear));
  }
  std::printf("20000 rays: max |ray - triangle interpolation| %.1e m (rough, slopes up to %.0f), "
              "|interpolate - formula| %.1e m, |ray - bilinear| on a plane %.1e m\n",
              worst_rough, 0.3 / dx, worst_interp, worst_flat);
  EXPECT_LT(worst_rough, 1e-5);
  EXPECT_LT(worst_interp, 1e-12);
  EXPECT_LT(worst_flat, 1e-9);
  // off the grid: no hit
  EXPECT_FALSE(a.height_at(x0 - 0.01, y0 + 0.5).has_value());
  EXPECT_FALSE(a.interpolate(x0 + 0.5, y0 + ny * dx).has_value());
}

// a pile of particles with a 32° face, scanned by a line laser above and in front of it: the
// profile's face is 32° within a degree, and the flat top is at the pile height
TEST(Heightmap, LaserScanOfA32DegreePileFaceReturnsTheSlope) {
  const double d = 0.1, r = 0.5 * d, top = 1.5, crest = 1.0;
  const double tan_face = std::tan(32.0 * M_PI / 180.0);
  const auto surface = [&](double x) { return std::clamp(top - (x - crest) * tan_face, 0.0, top); };
  // columns of particles on a lattice (one spacing d) up to the surface, over a ground layer
  Particles p;
  for (double x = 0.0; x <= 6.0 + 1e-9; x += d)
    for (double y = 0.0; y <= 1.0 + 1e-9; y += d) {
      p.add(Vec3(x, y, r), r, 2590.0);
      for (double z = r + d; z + r <= surface(x) + 1e-9; z += d) p.add(Vec3(x, y, z), r, 2590.0);
    }
  const Heightmap map = Heightmap::from_particles(p, 0.0, 0.0, d, 61, 11);
  EXPECT_EQ(map.filled_holes(), 0);
  // the sensor 4 m above the ground, 2 m in front of the toe, in the mid plane of the pile; the
  // rays aim at ground points from 4 m behind the pile (they see its top) to its far end
  const Eigen::Vector3d sensor(crest + top / tan_face + 2.0, 0.5, 4.0);
  const int rays = 300;
  const auto profile = map.scan_profile(0.5, -4.0, 6.0, rays, sensor);
  ASSERT_GT(profile.size(), 200u);
  // least-squares line through the points on the face, away from crest and toe
  double sx = 0, sz = 0, sxx = 0, sxz = 0;
  int n = 0;
  double top_mean = 0.0;
  int n_top = 0;
  for (const auto& q : profile) {
    if (q.y() > 0.3 && q.y() < top - 0.2) {
      sx += q.x(), sz += q.y(), sxx += q.x() * q.x(), sxz += q.x() * q.y();
      ++n;
    }
    if (q.x() < crest - 0.2) top_mean += q.y(), ++n_top;
  }
  ASSERT_GT(n, 20);
  const double slope = (n * sxz - sx * sz) / (n * sxx - sx * sx);
  const double angle = -std::atan(slope) * 180.0 / M_PI;
  top_mean /= std::max(n_top, 1);
  std::printf("scan: %zu of %d rays hit, %d on the face: %.2f deg (pile 32); top %.3f m (%d points, "
              "pile top %.2f m)\n",
              profile.size(), rays, n, angle, top_mean, n_top, top);
  EXPECT_NEAR(angle, 32.0, 1.0);
  EXPECT_GT(n_top, 5);
  EXPECT_NEAR(top_mean, top, d);
  EXPECT_THROW(map.scan_profile(0.4, 0.0, 6.0, 10, sensor), Error);
  EXPECT_THROW(map.scan_profile(0.5, 0.0, 6.0, 1, sensor), Error);
}

TEST(Heightmap, BadGridsAreRefused) {
  EXPECT_THROW(Heightmap(0, 0, 0.0, 4, 4, std::vector<double>(16, 0.0)), Error);
  EXPECT_THROW(Heightmap(0, 0, 0.1, 4, 4, std::vector<double>(15, 0.0)), Error);
  Particles far;
  far.add(Vec3(100, 100, 0), 0.05, 2590.0);
  EXPECT_THROW(Heightmap::from_particles(far, 0, 0, 0.1, 4, 4), Error);
}

}  // namespace
}  // namespace talus
