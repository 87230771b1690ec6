#include "io/image.hpp"

#include <png.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numeric>

#include "host/error.hpp"
#include "host/files.hpp"

namespace talus {

Image::Image(int width, int height, uint8_t grey)
    : width_(width), height_(height), rgb_(size_t(width) * height * 3, grey) {}

void Image::set(int x, int y, uint8_t r, uint8_t g, uint8_t b) {
  if (x < 0 || y < 0 || x >= width_ || y >= height_) return;
  uint8_t* p = &rgb_[3 * (size_t(y) * width_ + x)];
  p[0] = r;
  p[1] = g;
  p[2] = b;
}

void Image::disc(double cx, double cy, double radius, uint8_t r, uint8_t g, uint8_t b) {
  int x0 = static_cast<int>(std::floor(cx - radius)), x1 = static_cast<int>(std::ceil(cx + radius));
  int y0 = static_cast<int>(std::floor(cy - radius)), y1 = static_cast<int>(std::ceil(cy + radius));
  for (int y = std::max(0, y0); y <= std::min(height_ - 1, y1); ++y)
    for (int x = std::max(0, x0); x <= std::min(width_ - 1, x1); ++x) {
      double dx = x + 0.5 - cx, dy = y + 0.5 - cy;
      if (dx * dx + dy * dy <= radius * radius) set(x, y, r, g, b);
    }
}

void Image::write_png(const std::string& path) const {
  std::string tmp = temporary_name(path);
  FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) throw Error(path + ": cannot write the image (check the folder exists and is writable)");
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!png || !info || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    std::fclose(f);
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    throw Error(path + ": libpng failed while writing the image");
  }
  png_init_io(png, f);
  png_set_IHDR(png, info, width_, height_, 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  for (int y = 0; y < height_; ++y)
    png_write_row(png, const_cast<png_bytep>(&rgb_[3 * size_t(y) * width_]));
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  std::error_code ec;
  if (std::fclose(f) != 0) {
    std::filesystem::remove(tmp, ec);
    throw Error(path + ": write failed (disk full?); the previous image, if any, is untouched");
  }
  move_into_place(tmp, path);
}

Image side_view(const Particles& p, int width) {
  if (p.size() == 0) return Image(width, width / 2);
  // the particles' x-z extent, with a 5% margin
  double xmin = 1e300, xmax = -1e300, zmin = 1e300, zmax = -1e300, ymin = 1e300, ymax = -1e300;
  for (size_t i = 0; i < p.size(); ++i) {
    const Vec3& x = p.position[i];
    double r = p.radius[i];
    xmin = std::min(xmin, x.x() - r);
    xmax = std::max(xmax, x.x() + r);
    zmin = std::min(zmin, x.z() - r);
    zmax = std::max(zmax, x.z() + r);
    ymin = std::min(ymin, x.y());
    ymax = std::max(ymax, x.y());
  }
  double pad = 0.05 * std::max(xmax - xmin, zmax - zmin);
  xmin -= pad, xmax += pad, zmin -= pad, zmax += pad;
  double scale = width / (xmax - xmin);
  int height = std::max(64, static_cast<int>(std::ceil((zmax - zmin) * scale)));
  Image img(width, height, 255);
  // far to near (large y first, the viewer looks along +y from y = -infinity)
  std::vector<size_t> order(p.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return p.position[a].y() > p.position[b].y(); });
  double depth_span = std::max(ymax - ymin, 1e-9);
  for (size_t i : order) {
    const Vec3& x = p.position[i];
    double near = 1.0 - (x.y() - ymin) / depth_span;  // 1 nearest, 0 farthest
    bool fixed = p.inv_mass[i] <= 0.0;
    // gravel brown, lighter with distance; fixed particles grey
    auto shade = [&](double c) { return static_cast<uint8_t>(std::clamp(c, 0.0, 255.0)); };
    uint8_t r = fixed ? 120 : shade(140 + 90 * (1 - near));
    uint8_t g = fixed ? 120 : shade(100 + 100 * (1 - near));
    uint8_t b = fixed ? 120 : shade(60 + 120 * (1 - near));
    double cx = (x.x() - xmin) * scale, cy = (zmax - x.z()) * scale;
    double rad = std::max(0.7, p.radius[i] * scale);
    img.disc(cx, cy, rad, shade(r * 0.6), shade(g * 0.6), shade(b * 0.6));  // outline
    img.disc(cx, cy, std::max(0.5, rad - 1.0), r, g, b);
  }
  // the ground line z = 0 when it is in view
  int yg = static_cast<int>((zmax - 0.0) * scale);
  if (yg >= 0 && yg < height)
    for (int x = 0; x < width; ++x) img.set(x, yg, 40, 40, 40);
  return img;
}

}  // namespace talus
