// io/image: the side view places particles where they are, and the PNG is a valid file.
#include <gtest/gtest.h>

#include <filesystem>
#include <cstring>
#include <fstream>

#include "io/image.hpp"

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
