#include "io/image.hpp"

#include <cairo.h>
#include <png.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numeric>
#include <string>

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

double scale_bar_length(int width_px, double metres_per_px) {
  const double most = 0.2 * width_px * metres_per_px;  // [m]
  // a hair above the exact decade, so 0.2 m at a fifth gives 0.2, not 0.1, after rounding
  const double decade = std::pow(10.0, std::floor(std::log10(most) + 1e-9));
  for (const double step : {5.0, 2.0, 1.0})
    if (step * decade <= most) return step * decade;
  return decade;
}

namespace {
// a length as people write it on a drawing: "2 m", "50 cm", "5 mm"
std::string length_label(double metres) {
  const auto whole = [](double v) {
    return std::to_string(static_cast<long long>(std::llround(v)));
  };
  if (metres >= 1.0) return whole(metres) + " m";
  if (metres >= 0.01) return whole(100.0 * metres) + " cm";
  if (metres >= 0.001) return whole(1000.0 * metres) + " mm";
  return whole(1e6 * metres) + " \u00b5m";
}
}  // namespace

void draw_scale_bar(Image& image, double metres_per_px) {
  if (!(metres_per_px > 0.0) || !std::isfinite(metres_per_px))
    throw InputError(
        "scale bar: the picture's scale must be a positive number of metres per pixel");
  const int w = image.width(), h = image.height();
  if (w < 120 || h < 60)
    throw InputError("scale bar: the picture is too small for one (at least 120 x 60 px)");
  const double length_m = scale_bar_length(w, metres_per_px);
  const double bar_px = length_m / metres_per_px;
  // the picture into a Cairo surface (0xXXRRGGBB per pixel), drawn on, and back
  cairo_surface_t* surface = cairo_image_surface_create(CAIRO_FORMAT_RGB24, w, h);
  if (cairo_surface_status(surface) != CAIRO_STATUS_SUCCESS) {
    cairo_surface_destroy(surface);
    throw Error("scale bar: Cairo could not make a " + std::to_string(w) + " x " +
                std::to_string(h) + " surface (out of memory?)");
  }
  const int stride = cairo_image_surface_get_stride(surface);
  auto* data = cairo_image_surface_get_data(surface);
  cairo_surface_flush(surface);
  for (int y = 0; y < h; ++y) {
    auto* row = reinterpret_cast<uint32_t*>(data + static_cast<size_t>(y) * stride);
    for (int x = 0; x < w; ++x) {
      const uint8_t* p = image.pixel(x, y);
      row[x] = (uint32_t(p[0]) << 16) | (uint32_t(p[1]) << 8) | uint32_t(p[2]);
    }
  }
  cairo_surface_mark_dirty(surface);
  cairo_t* cr = cairo_create(surface);
  // sizes from the picture's height: the text a fortieth of it, at least 12 px
  const double text_px = std::max(12.0, h / 40.0);
  const double margin = text_px, x0 = margin + 0.5 * text_px, y0 = h - margin - 0.5 * text_px;
  const std::string label = length_label(length_m);
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, text_px);
  cairo_text_extents_t extents;
  cairo_text_extents(cr, label.c_str(), &extents);
  // the white plate behind bar and label
  cairo_set_source_rgba(cr, 1.0, 1.0, 1.0, 0.85);
  cairo_rectangle(cr, margin, y0 - 2.2 * text_px, bar_px + text_px, 2.2 * text_px + 0.5 * text_px);
  cairo_fill(cr);
  // the bar, its end ticks, and its length above its middle
  cairo_set_source_rgb(cr, 0.0, 0.0, 0.0);
  cairo_set_line_width(cr, std::max(2.0, text_px / 6.0));
  cairo_move_to(cr, x0, y0);
  cairo_line_to(cr, x0 + bar_px, y0);
  for (const double x : {x0, x0 + bar_px}) {
    cairo_move_to(cr, x, y0 - 0.4 * text_px);
    cairo_line_to(cr, x, y0 + 0.25 * text_px);
  }
  cairo_stroke(cr);
  cairo_move_to(cr, x0 + 0.5 * bar_px - 0.5 * extents.x_advance, y0 - 0.7 * text_px);
  cairo_show_text(cr, label.c_str());
  const bool drawn = cairo_status(cr) == CAIRO_STATUS_SUCCESS;
  cairo_destroy(cr);
  cairo_surface_flush(surface);
  for (int y = 0; drawn && y < h; ++y) {
    const auto* row = reinterpret_cast<const uint32_t*>(data + static_cast<size_t>(y) * stride);
    for (int x = 0; x < w; ++x)
      image.set(x, y, (row[x] >> 16) & 0xff, (row[x] >> 8) & 0xff, row[x] & 0xff);
  }
  cairo_surface_destroy(surface);
  if (!drawn)
    throw Error("scale bar: Cairo could not draw it (no fonts? apt-get install fonts-dejavu-core)");
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
