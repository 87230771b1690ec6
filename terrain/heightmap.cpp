#include "terrain/heightmap.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "host/error.hpp"

namespace talus {

namespace {

void check_grid(double dx, int nx, int ny) {
  if (!(dx > 0) || !std::isfinite(dx) || nx < 2 || ny < 2)
    throw Error("heightmap: need dx > 0 and at least 2 x 2 nodes (got dx " + std::to_string(dx) + ", " +
                std::to_string(nx) + " x " + std::to_string(ny) + ")");
}

}  // namespace

Heightmap::Heightmap(double x0, double y0, double dx, int nx, int ny, std::vector<double> heights,
                     const embree::Device& device)
    : x0_(x0), y0_(y0), dx_(dx), nx_(nx), ny_(ny), h_(std::move(heights)), scene_(device, RTC_SCENE_FLAG_ROBUST) {
  check_grid(dx, nx, ny);
  if (h_.size() != static_cast<size_t>(nx) * ny)
    throw Error("heightmap: " + std::to_string(h_.size()) + " heights for " + std::to_string(nx) + " x " +
                std::to_string(ny) + " nodes");
  for (double z : h_)
    if (!std::isfinite(z)) throw Error("heightmap: a node height is not finite");
  h_min_ = *std::min_element(h_.begin(), h_.end());
  h_max_ = *std::max_element(h_.begin(), h_.end());
  // float vertices for embree; two triangles per cell, counter-clockwise seen from above
  std::vector<float> xyz;
  xyz.reserve(3 * h_.size());
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      xyz.push_back(static_cast<float>(x0 + i * dx));
      xyz.push_back(static_cast<float>(y0 + j * dx));
      xyz.push_back(static_cast<float>(height(i, j)));
    }
  std::vector<unsigned> idx;
  idx.reserve(6 * static_cast<size_t>(nx - 1) * (ny - 1));
  for (int j = 0; j + 1 < ny; ++j)
    for (int i = 0; i + 1 < nx; ++i) {
      const unsigned k00 = j * nx + i, k10 = k00 + 1, k01 = k00 + nx, k11 = k01 + 1;
      for (unsigned k : {k00, k10, k11, k00, k11, k01}) idx.push_back(k);
    }
  embree::attach_triangles(scene_, xyz.data(), h_.size(), idx.data(), idx.size() / 3);
  scene_.commit();
}

Heightmap Heightmap::from_particles(const Particles& particles, double x0, double y0, double dx, int nx,
                                    int ny, const embree::Device& device) {
  check_grid(dx, nx, ny);
  const double none = -std::numeric_limits<double>::infinity();
  std::vector<double> h(static_cast<size_t>(nx) * ny, none);
  // highest particle top per bin (the bin of a node is the square of side dx centred on it)
  for (size_t p = 0; p < particles.size(); ++p) {
    const Vec3& x = particles.position[p];
    const long i = std::lround(std::floor((x.x() - x0) / dx + 0.5));
    const long j = std::lround(std::floor((x.y() - y0) / dx + 0.5));
    if (i < 0 || i >= nx || j < 0 || j >= ny) continue;
    double& cell = h[static_cast<size_t>(j) * nx + i];
    cell = std::max(cell, x.z() + particles.radius[p]);
  }
  const int holes = static_cast<int>(std::count(h.begin(), h.end(), none));
  if (holes == nx * ny) throw Error("heightmap: no particle centre lies on the grid");
  // holes: ring by ring from the filled region, each the mean of its filled 8-neighbours
  // (a pass reads only the previous pass's values, so the fill does not depend on loop order)
  for (int left = holes; left > 0;) {
    std::vector<double> next = h;
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        if (h[static_cast<size_t>(j) * nx + i] != none) continue;
        double sum = 0.0;
        int n = 0;
        for (int dj = -1; dj <= 1; ++dj)
          for (int di = -1; di <= 1; ++di) {
            const int a = i + di, b = j + dj;
            if ((di == 0 && dj == 0) || a < 0 || a >= nx || b < 0 || b >= ny) continue;
            const double z = h[static_cast<size_t>(b) * nx + a];
            if (z != none) {
              sum += z;
              ++n;
            }
          }
        if (n > 0) {
          next[static_cast<size_t>(j) * nx + i] = sum / n;
          --left;
        }
      }
    h.swap(next);
  }
  Heightmap map(x0, y0, dx, nx, ny, std::move(h), device);
  map.filled_holes_ = holes;
  return map;
}

std::optional<double> Heightmap::interpolate(double x, double y) const {
  return piecewise_linear_height(
      x0_, y0_, dx_, nx_, ny_, [this](int i, int j) { return height(i, j); }, x, y);
}

std::optional<Eigen::Vector3d> Heightmap::cast(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir) const {
  RTCRayHit rh;
  rh.ray.org_x = static_cast<float>(origin.x());
  rh.ray.org_y = static_cast<float>(origin.y());
  rh.ray.org_z = static_cast<float>(origin.z());
  rh.ray.dir_x = static_cast<float>(dir.x());
  rh.ray.dir_y = static_cast<float>(dir.y());
  rh.ray.dir_z = static_cast<float>(dir.z());
  rh.ray.tnear = 0.0f;
  rh.ray.tfar = std::numeric_limits<float>::infinity();
  rh.ray.time = 0.0f;
  rh.ray.mask = 0xFFFFFFFFu;
  rh.ray.id = 0;
  rh.ray.flags = 0;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  rtcIntersect1(scene_.get(), &context, &rh);
  scene_.device().check("rtcIntersect1");
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return std::nullopt;
  // the hit triangle in double, and the ray's crossing of its plane
  const int cell = static_cast<int>(rh.hit.primID / 2), i = cell % (nx_ - 1), j = cell / (nx_ - 1);
  const auto node = [&](int a, int b) {
    return Eigen::Vector3d(x0_ + a * dx_, y0_ + b * dx_, height(a, b));
  };
  const Eigen::Vector3d a = node(i, j), c = node(i + 1, j + 1);
  const Eigen::Vector3d b = (rh.hit.primID % 2 == 0) ? node(i + 1, j) : node(i, j + 1);
  const Eigen::Vector3d n = (b - a).cross(c - a);
  const double along = n.dot(dir);
  if (along == 0.0) return origin + static_cast<double>(rh.ray.tfar) * dir;  // grazing: embree's t
  return origin + (n.dot(a - origin) / along) * dir;
}

std::optional<double> Heightmap::height_at(double x, double y) const {
  const auto hit = cast(Eigen::Vector3d(x, y, h_max_ + 1.0), Eigen::Vector3d(0, 0, -1));
  if (!hit) return std::nullopt;
  return hit->z();
}

std::vector<Eigen::Vector2d> Heightmap::scan_profile(double y, double x_from, double x_to, int n,
                                                     const Eigen::Vector3d& sensor) const {
  if (n < 2) throw Error("heightmap scan_profile: need at least 2 rays (got " + std::to_string(n) + ")");
  if (!(std::abs(sensor.y() - y) <= 1e-9))
    throw Error("heightmap scan_profile: the sensor (y = " + std::to_string(sensor.y()) +
                ") must lie in the scan plane y = " + std::to_string(y));
  std::vector<Eigen::Vector2d> profile;
  for (int k = 0; k < n; ++k) {
    const double x = x_from + (x_to - x_from) * k / (n - 1);
    const auto hit = cast(sensor, Eigen::Vector3d(x, y, h_min_) - sensor);
    if (hit) profile.emplace_back(hit->x(), hit->z());
  }
  return profile;
}

}  // namespace talus
