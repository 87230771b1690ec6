// Pictures of results: an RGB canvas written as PNG with libpng, and a side view of particles
// (what a user looks at before reading numbers).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "solvers/particles.hpp"

namespace talus {

class Image {
 public:
  Image(int width, int height, uint8_t grey = 255);
  int width() const { return width_; }
  int height() const { return height_; }
  void set(int x, int y, uint8_t r, uint8_t g, uint8_t b);
  const uint8_t* pixel(int x, int y) const { return &rgb_[3 * (size_t(y) * width_ + x)]; }
  uint8_t* pixel(int x, int y) { return &rgb_[3 * (size_t(y) * width_ + x)]; }
  // a filled disc, clipped to the canvas
  void disc(double cx, double cy, double radius, uint8_t r, uint8_t g, uint8_t b);
  // writes an 8-bit RGB PNG (to a temporary name, then renamed)
  void write_png(const std::string& path) const;

 private:
  int width_, height_;
  std::vector<uint8_t> rgb_;
};

// the length a scale bar shows for a picture `width_px` wide at `metres_per_px` [m/px]: the
// longest of 1, 2 or 5 times a power of ten [m] that takes at most a fifth of the width
double scale_bar_length(int width_px, double metres_per_px);

// draws a scale bar into the bottom-left corner of an orthographic picture: a black bar of
// scale_bar_length() on a white plate, with end ticks and its length written above ("1 m",
// "50 cm"), drawn and lettered with Cairo. talus::InputError for metres_per_px <= 0 or an image
// too small to hold it (under 120 x 60 px)
void draw_scale_bar(Image& image, double metres_per_px);

// orthographic side view (looking along +y): x to the right, z up, particles drawn far to near
// and shaded by depth; the view fits the particles with a margin, `width` pixels across
Image side_view(const Particles& particles, int width = 1200);

}  // namespace talus
