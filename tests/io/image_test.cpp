// io/image: the side view places particles where they are, and the PNG is a valid file.
#include <gtest/gtest.h>

#include <filesystem>
#include <cstring>
#include <fstream>

#include "io/image.hpp"

#include "host/error.hpp"

namespace talus {
namespace {

TEST(Image, SideViewDrawsParticlesAtTheirPlace) {
  Particles p;
  p.add(Vec3(0.0, 0.0, 0.5), 0.5, 2590);
  p.add(Vec3(4.0, 0.0, 0.5), 0.5, 2590);
  Image img = side_view(p, 400);
  // the view spans x in [-0.5 - pad, 4.5 + pad]: the first centre sits left of the middle
  double pad = 0.05 * 5.0;
  double scale = 400 / (5.0 + 2 * pad);
  int cx = static_cast<int>((0.0 + 0.5 + pad) * scale);
  int cy = static_cast<int>((1.0 + pad - 0.5) * scale);
  const uint8_t* centre = img.pixel(cx, cy);
  EXPECT_LT(centre[0], 250);  // not background white
  const uint8_t* gap = img.pixel(200, cy);  // between the two particles
  EXPECT_EQ(gap[0], 255);
}

TEST(Image, PngHasSignatureAndSize) {
  Image img(7, 5);
  img.set(1, 1, 10, 20, 30);
  auto path = (std::filesystem::temp_directory_path() / "talus_image_test.png").string();
  img.write_png(path);
  std::ifstream in(path, std::ios::binary);
  unsigned char head[24];
  in.read(reinterpret_cast<char*>(head), 24);
  const unsigned char signature[8] = {137, 'P', 'N', 'G', 13, 10, 26, 10};
  EXPECT_EQ(0, std::memcmp(head, signature, 8));
  // IHDR width and height, big-endian at bytes 16..23
  EXPECT_EQ(head[19], 7);
  EXPECT_EQ(head[23], 5);
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
}

}  // namespace
}  // namespace talus

namespace talus {
namespace {

// the bar's length: the longest 1, 2 or 5 × 10^k metres within a fifth of the picture's width
TEST(ScaleBar, LengthIsARoundNumberWithinAFifthOfTheWidth) {
  EXPECT_DOUBLE_EQ(scale_bar_length(1600, 0.00635), 2.0);  // a fifth spans 2.03 m
  EXPECT_DOUBLE_EQ(scale_bar_length(1000, 0.001), 0.2);    // 0.2 m exactly
  EXPECT_DOUBLE_EQ(scale_bar_length(1000, 0.0049), 0.5);   // 0.98 m
  EXPECT_DOUBLE_EQ(scale_bar_length(1000, 0.06), 10.0);    // 12 m
  EXPECT_NEAR(scale_bar_length(500, 1e-5), 1e-3, 1e-15);   // 1 mm
}

// drawn on a white picture at 1 cm per pixel: a black bar 1 m = 100 px long near the bottom-left
// corner, its label above it, and nothing drawn in the rest of the picture
TEST(ScaleBar, DrawsABarOfItsLengthWithItsLabel) {
  Image image(800, 400);
  draw_scale_bar(image, 0.01);
  const auto dark = [&](int x, int y) {
    const uint8_t* p = image.pixel(x, y);
    return p[0] < 100 && p[1] < 100 && p[2] < 100;
  };
  // the longest horizontal run of dark pixels is the bar (line caps add nothing: butt ends)
  int longest = 0, bar_row = -1;
  for (int y = 0; y < 400; ++y) {
    int run = 0;
    for (int x = 0; x < 800; ++x) {
      run = dark(x, y) ? run + 1 : 0;
      if (run > longest) longest = run, bar_row = y;
    }
  }
  EXPECT_NEAR(longest, 100, 3);
  EXPECT_GT(bar_row, 300);
  // the label: dark pixels above the bar's middle
  int label = 0;
  for (int y = bar_row - 30; y < bar_row - 5; ++y)
    for (int x = 20; x < 140; ++x) label += dark(x, y) ? 1 : 0;
  EXPECT_GT(label, 20);
  // nothing in the upper half
  for (int y = 0; y < 200; ++y)
    for (int x = 0; x < 800; ++x) ASSERT_FALSE(dark(x, y)) << x << "," << y;
  EXPECT_THROW(draw_scale_bar(image, 0.0), InputError);
  Image tiny(60, 30);
  EXPECT_THROW(draw_scale_bar(tiny, 0.01), InputError);
}

}  // namespace
}  // namespace talus
